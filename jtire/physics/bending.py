"""Shell bending as hinge rotations between neighbouring edges.

  meridional hinges      (T, S)    at every real node, bead included (the ghost beyond the bead
                                   clamps the carcass to the rim's flange angle)
  circumferential hinges (T, S-2)  at every free node, between segments i-1 -> i -> i+1
Angles are signed atan2 about the local tangent of the other family, so they stay regular when
the belt flattens in the footprint. Stiffness per hinge: D w / l with D = E_bending t^3 / 12,
w the hinge's length and l the tributary length across it.
"""

import jax.numpy as jnp

from .geometry_ops import signed_angle


def meridional_hinges(X):
    """(T, S) bending angle of the meridian at each real node (columns 1..S)."""
    a = X[:, 1:-1] - X[:, :-2]
    b = X[:, 2:] - X[:, 1:-1]
    real = X[:, 1:-1]
    axis = real.roll(-1, 0) - real.roll(1, 0)
    return signed_angle(a, b, axis)


def circumferential_hinges(X):
    """(T, S-2) bending angle of the circumferential lines at each free node."""
    free = X[:, 2:-2]
    a = free - free.roll(1, 0)
    b = free.roll(-1, 0) - free
    axis = X[:, 3:-1] - X[:, 1:-3]
    return signed_angle(a, b, axis)


def bending_stiffness(mesh_arrays, params):
    """(T, S) and (T, S-2) hinge stiffnesses, N m / rad."""
    ma = mesh_arrays
    p_all = ma.node_part  # real nodes (S,)
    D = params.E_bending[p_all] * params.thickness[p_all] ** 3 / 12.0
    k_mh = D[None, :] * ma.w_node / ma.l_node
    k_ch = D[None, 1:-1] * ma.l_node[:, 1:-1] / ma.w_node[:, 1:-1]
    return k_mh, k_ch
