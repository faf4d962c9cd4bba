"""Membrane action of the cord-reinforced layers: edge stretch and in-plane shear.

Generalized strains of the quadrilateral net (X: a `V` of (T, S+2) planes, columns 0 and S+1 are the
rim-attached ghosts, 1 and S the beads):
  meridional edge lengths     (T, S-1)  carcass cords (radial) / belt transverse
  circumferential edge lengths (T, S-2)  rubber in the sidewall, steel belt in the crown
  shear angle per quad         (T, S-1)  cosine of the angle between the mean meridional and
                                         mean circumferential directions (0 on the mould shape)
The bead rings (both ends on the rim) carry no strain. Orthotropy comes from the different moduli
along the two families of edges (`MaterialParams.E_meridional`, `.E_circumferential`).
"""

import jax.numpy as jnp

from .geometry_ops import dot, norm, unit


def meridional_lengths(X):
    """(T, S-1) lengths of the edges bead -> bead."""
    real = X[:, 1:-1]
    return norm(real[:, 1:] - real[:, :-1])


def circumferential_lengths(X):
    """(T, S-2) lengths of the edges between segment i and i+1 at each free column."""
    free = X[:, 2:-2]
    return norm(free.roll(-1, 0) - free)


def shear_strains(X):
    """(T, S-1) cos of the angle between the quad's mean meridional and circumferential edges."""
    real = X[:, 1:-1]
    nxt = real.roll(-1, 0)
    m = (real[:, 1:] - real[:, :-1]) + (nxt[:, 1:] - nxt[:, :-1])
    c = (nxt[:, :-1] - real[:, :-1]) + (nxt[:, 1:] - real[:, 1:])
    return dot(unit(m), unit(c))


def membrane_stiffness(mesh_arrays, params):
    """Stiffnesses (N/m for edges, N m for shear) of the membrane strains, from part moduli.

    Edge k = E t w / L0 (w the tributary width across the edge); shear k = G t A.
    The undertread membrane is an isotropic rubber layer in parallel with the belt in the crown.
    """
    ma = mesh_arrays
    ep, npart = ma.elem_part, ma.node_part[1:-1]
    ut = params.undertread_E * params.undertread_thickness
    crown_e, crown_n = ma.elem_is_crown, ma.node_is_crown[1:-1]
    Et_m = params.E_meridional[ep] * params.thickness[ep] + ut * crown_e
    Et_c = params.E_circumferential[npart] * params.thickness[npart] + ut * crown_n
    Gt = params.G_shear[ep] * params.thickness[ep] + (ut / 3.0) * crown_e
    k_mer = Et_m[None, :] * ma.w_mer_edge / ma.L0_mer
    k_circ = Et_c[None, :] * ma.l_circ_edge / ma.L0_circ
    k_shear = Gt[None, :] * ma.quad_area
    return k_mer, k_circ, k_shear
