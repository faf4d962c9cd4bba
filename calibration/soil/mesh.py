"""Axisymmetric (r, z) mesh of a cylindrical soil block under a rigid circular plate.

Geometry: r in [0, R] (r = 0 is the symmetry axis), z in [-H, 0] (z = 0 is the soil surface,
z up). The plate covers the surface for r <= a. Elements are 4-node quadrilaterals with 2 x 2
Gauss points and the B-bar (mean-dilatation) volumetric strain: plastic flow with little or no
dilatancy is nearly isochoric, and fully integrated Q4 elements lock on it (too stiff a
collapse), which B-bar removes.

Spacing: uniform under the plate (n_r_plate elements across a), then geometric growth outwards
and downwards, starting from the plate's element size, so that a few hundred elements reach a
block many plate radii wide and deep (the far field sees only a smooth, small displacement).

Boundary conditions: u_r = 0 on the axis and on the outer wall (roller), u_r = u_z = 0 on the
bottom; every surface node under the plate shares ONE vertical degree of freedom (the plate's
settlement: a rigid, smooth plate; those nodes slide radially freely, as in the Boussinesq
frictionless rigid punch).

Unknowns are numbered row by row (one node row = one block, padded to a common size), so the
stiffness is block-tridiagonal and `block_tridiagonal_solve` factors it in O(rows * m^3).

Everything in SoilMesh is numpy and static (the topology of the jitted solve); strain-
displacement matrices are precomputed per Gauss point.
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import brentq

from ...errors import ConfigError

_GAUSS = 1.0 / np.sqrt(3.0)
# Gauss points of the 2 x 2 rule in (xi, eta); all weights are 1.
_GP = np.array([[-_GAUSS, -_GAUSS], [_GAUSS, -_GAUSS], [_GAUSS, _GAUSS], [-_GAUSS, _GAUSS]])
# Corner nodes of the parent square, counter-clockwise.
_CORNERS = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


@dataclasses.dataclass(frozen=True, eq=False)
class SoilMesh:
    """Static topology and Gauss-point geometry of the block (numpy arrays).

    Attributes:
        nodes: (n_nodes, 2) node coordinates [r, z] in m.
        elements: (n_elem, 4) node indices, counter-clockwise in the (r, z) plane.
        element_dofs: (n_elem, 8) global dof index of [u_r, u_z] of each corner; fixed dofs
            point at index n_free (a dump slot that the assembly discards).
        n_free: number of unknowns = n_blocks * block_size (the plate's settlement included;
            padding slots carry an identity row and stay zero).
        plate_dof: index of the plate's vertical displacement (m, positive up).
        b_bar: (n_elem, 4, 4, 8) B-bar matrices per Gauss point; rows are the engineering
            strains [eps_rr, eps_zz, eps_tt, gamma_rz] (1), columns the element dofs (m).
        weight: (n_elem, 4) integration weight 2 pi r det(J) per Gauss point (m^3).
        gp_depth: (n_elem, 4) depth of each Gauss point below the surface (m, >= 0).
        n_blocks, block_size: the block-tridiagonal layout of the unknowns (one block per
            node row from the surface down).
        ke_index: (n_elem, 8, 8) flat index of each element-matrix entry in the
            (n_blocks, 3, block_size, block_size) block array; n_blocks*3*block_size**2 = dump.
        pad_mask: (n_blocks, block_size) True on padding slots.
    """

    nodes: np.ndarray
    elements: np.ndarray
    element_dofs: np.ndarray
    n_free: int
    plate_dof: int
    b_bar: np.ndarray
    weight: np.ndarray
    gp_depth: np.ndarray
    n_blocks: int
    block_size: int
    ke_index: np.ndarray
    pad_mask: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.elements.shape[0])


def graded_spacing(length: float, n: int, first: float) -> np.ndarray:
    """Coordinates 0 = x_0 < ... < x_n = length with x_1 = first and geometric growth.

    Returns an (n + 1,) array in the units of `length`. Uniform spacing when n * first >= length.
    """
    if n * first >= length * (1.0 - 1e-12):
        return np.linspace(0.0, length, n + 1)
    # Sum of the geometric series first * (q^n - 1) / (q - 1) equals length for one q > 1.
    q = brentq(lambda q: first * (q**n - 1.0) / (q - 1.0) - length, 1.0 + 1e-12, 100.0)
    steps = first * q ** np.arange(n)
    x = np.concatenate([[0.0], np.cumsum(steps)])
    x[-1] = length  # remove the root finder's last-bit error
    return x


def _shape(xi: float, eta: float):
    """Bilinear shape functions N (4,) and their parent derivatives dN (2, 4)."""
    n = 0.25 * (1 + _CORNERS[:, 0] * xi) * (1 + _CORNERS[:, 1] * eta)
    dn = 0.25 * np.stack(
        [_CORNERS[:, 0] * (1 + _CORNERS[:, 1] * eta), _CORNERS[:, 1] * (1 + _CORNERS[:, 0] * xi)]
    )
    return n, dn


def _element_geometry(xy: np.ndarray):
    """B-bar (4 gp, 4, 8), weights (4,) and Gauss-point coordinates (4, 2) of one element."""
    b = np.zeros((4, 4, 8))
    w = np.zeros(4)
    pts = np.zeros((4, 2))
    for g, (xi, eta) in enumerate(_GP):
        n, dn = _shape(xi, eta)
        jac = dn @ xy  # (2, 2): d(r, z) / d(xi, eta)
        det = np.linalg.det(jac)
        if det <= 0.0:
            raise ConfigError("soil mesh: an element is inverted; check block and plate sizes")
        dxy = np.linalg.solve(jac, dn)  # (2, 4): dN/dr, dN/dz
        r = n @ xy[:, 0]
        b[g, 0, 0::2] = dxy[0]  # eps_rr = du_r/dr
        b[g, 1, 1::2] = dxy[1]  # eps_zz = du_z/dz
        b[g, 2, 0::2] = n / r  # eps_tt = u_r / r (hoop)
        b[g, 3, 0::2] = dxy[1]  # gamma_rz = du_r/dz + du_z/dr
        b[g, 3, 1::2] = dxy[0]
        w[g] = 2.0 * np.pi * r * det
        pts[g] = n @ xy
    # Mean dilatation: replace each point's volumetric strain by the element's volume average.
    vol = b[:, 0] + b[:, 1] + b[:, 2]  # (4, 8)
    vol_bar = (w[:, None] * vol).sum(0) / w.sum()
    b[:, 0:3, :] += ((vol_bar[None] - vol) / 3.0)[:, None, :]
    return b, w, pts


def build_mesh(
    plate_radius_m: float,
    block_radius_m: float,
    block_depth_m: float,
    n_r_plate: int,
    n_r_outer: int,
    n_z: int,
) -> SoilMesh:
    """Graded structured mesh of (n_r_plate + n_r_outer) x n_z quads; see the module docstring."""
    a = plate_radius_m
    h0 = a / n_r_plate
    r = np.concatenate(
        [
            np.linspace(0.0, a, n_r_plate + 1),
            a + graded_spacing(block_radius_m - a, n_r_outer, h0)[1:],
        ]
    )
    z = -graded_spacing(block_depth_m, n_z, h0)  # z[0] = 0 at the surface, decreasing downward
    nr = r.size
    rr, zz = np.meshgrid(r, z)  # (n_z + 1, nr), row j = depth index
    nodes = np.stack([rr.ravel(), zz.ravel()], axis=1)

    def nid(i, j):
        return j * nr + i

    elements = np.array(
        [
            [nid(i, j + 1), nid(i + 1, j + 1), nid(i + 1, j), nid(i, j)]
            for j in range(n_z)
            for i in range(nr - 1)
        ]
    )

    # Dof numbering by node row (depth level): row j is block j of a block-tridiagonal
    # stiffness (elements couple only neighbouring rows), each block padded to one size m.
    # The plate's dof is slot 0 of block 0; the bottom row is fully fixed and has no block.
    tol = 1e-9 * block_radius_m
    on_axis = nodes[:, 0] < tol
    on_wall = nodes[:, 0] > block_radius_m - tol
    on_bottom = nodes[:, 1] < -block_depth_m + tol
    under_plate = (nodes[:, 1] > -tol) & (nodes[:, 0] < a + tol)
    free_r = ~(on_axis | on_wall | on_bottom)
    free_z = ~(on_bottom | under_plate)
    row = np.arange(nodes.shape[0]) // nr
    n_per_node = free_r.astype(int) + free_z.astype(int)
    count = np.bincount(row, weights=n_per_node, minlength=n_z + 1).astype(int)
    count[0] += 1  # the plate
    n_blocks, size = n_z, int(count.max())
    n_free = n_blocks * size
    dof = np.full((nodes.shape[0], 2), n_free, dtype=np.int64)  # n_free = dump slot (fixed)
    slot = np.zeros(n_z + 1, dtype=np.int64)
    slot[0] = 1
    plate_dof = 0
    dof[under_plate, 1] = plate_dof
    for k in range(nodes.shape[0]):
        for c, free in ((0, free_r[k]), (1, free_z[k])):
            if free:
                dof[k, c] = row[k] * size + slot[row[k]]
                slot[row[k]] += 1
    element_dofs = dof[elements].reshape(len(elements), 8)
    pad_mask = np.arange(size)[None, :] >= count[:n_blocks, None]

    # Flat position of each element-matrix entry in the (n_blocks, 3, size, size) block array
    # [sub-diagonal, diagonal, super-diagonal]; entries touching a fixed dof go to a dump slot.
    i, j = element_dofs[:, :, None], element_dofs[:, None, :]
    bi, bj = i // size, j // size
    flat = ((bi * 3 + (bj - bi + 1)) * size + i % size) * size + j % size
    dump = n_blocks * 3 * size * size
    ke_index = np.where((i == n_free) | (j == n_free), dump, flat)
    if np.any(np.abs(bj - bi)[(i < n_free) & (j < n_free)] > 1):
        raise AssertionError("soil mesh: dof numbering is not block-tridiagonal")

    geo = [_element_geometry(nodes[e]) for e in elements]
    b_bar = np.stack([g[0] for g in geo])
    weight = np.stack([g[1] for g in geo])
    gp_depth = -np.stack([g[2][:, 1] for g in geo])
    return SoilMesh(nodes, elements, element_dofs, n_free, plate_dof, b_bar, weight, gp_depth,
                    n_blocks, size, ke_index, pad_mask)


def block_tridiagonal_solve(kb, rhs):
    """Solve K x = rhs for block-tridiagonal K (block Gaussian elimination, then back substitution).

    kb: (n_blocks, 3, m, m) sub-diagonal (coupling block j to j - 1), diagonal and super-diagonal
    blocks; rhs: (n_blocks, m). Returns x (n_blocks, m). Pivoting happens inside each diagonal
    block only, which suffices for stiffness matrices (their symmetric part stays positive
    definite below collapse). Cost O(n_blocks m^3) against O((n_blocks m)^3) for a dense solve.
    """
    m = kb.shape[-1]

    def forward(carry, blocks):
        g_prev, y_prev = carry  # D'_{j-1}^-1 U_{j-1} and D'_{j-1}^-1 r'_{j-1}
        low, diag, up, r = blocks
        sol = jnp.linalg.solve(
            diag - low @ g_prev, jnp.concatenate([up, (r - low @ y_prev)[:, None]], axis=1)
        )
        return (sol[:, :m], sol[:, m]), (sol[:, :m], sol[:, m])

    init = (jnp.zeros((m, m), kb.dtype), jnp.zeros(m, kb.dtype))
    _, (g, y) = jax.lax.scan(forward, init, (kb[:, 0], kb[:, 1], kb[:, 2], rhs))

    def backward(x_next, gy):
        x = gy[1] - gy[0] @ x_next
        return x, x

    _, x = jax.lax.scan(backward, jnp.zeros(m, kb.dtype), (g, y), reverse=True)
    return x
