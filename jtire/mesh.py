"""The tire mesh: a meridional cross-section profile swept around the axle.

Axes (internal, used everywhere inside jtire): ISO 8855, x forward, y to the LEFT (along the
axle), z UP; the wheel centre is the origin of the reference geometry. SAE (x forward, y right,
z down) is the same frame turned about x: y_SAE = -y, z_SAE = -z. Results convert at their
boundary (`jtire.experiments`), nowhere else.

The section is described bead to bead by `n_s` nodes (j = 0 and j = n_s - 1 are the beads, tied
to the rigid rim), swept into `n_theta` equal segments. Each meridional element belongs to a named
part; per-part parameters live in `MaterialParams` and are gathered by the static part index.
Structure (counts, indices, part maps) is numpy and static; geometry and masses are arrays.
"""

import dataclasses

import numpy as np

# Parts along the section, bead -> crown (mirrored on the other side). Order is the index order.
PART_NAMES = ("bead", "lower_sidewall", "mid_sidewall", "upper_sidewall", "shoulder", "crown")
N_PARTS = len(PART_NAMES)
CROWN = PART_NAMES.index("crown")
SHOULDER = PART_NAMES.index("shoulder")


@dataclasses.dataclass(frozen=True)
class Geometry:
    """Cross-section geometry, SI (m). Built by `jtire.config` from the tire TOML."""

    rim_radius: float  # rim diameter / 2
    rim_width: float  # between the bead seats (flange to flange)
    flange_height: float  # where the carcass leaves the rim, above the rim radius
    section_width: float
    section_height: float
    outer_radius: float  # unloaded outer diameter / 2 (tread surface at the centre line)
    tread_depth: float  # rubber above the belt mid-surface at the centre line
    tread_width: float  # width of the full-depth tread
    belt_width: float  # width of the crown (belt) part
    crown_radius: float  # transverse radius of the crown (flatness of the wide-base crown)
    widest_point_ratio: float = 0.5  # height of the widest point above the rim / section height
    carcass_inset: float = 0.0  # the sidewall mid-surface's widest point lies this far inside section_width / 2


@dataclasses.dataclass(frozen=True)
class MassTargets:
    """Masses the mesh reproduces by construction (kg): areal densities are derived from them."""

    tire: float
    belt: float
    rim: float
    rim_Iy: float  # rim inertia about the axle (kg m^2)
    rim_Ixz: float  # rim inertia about a diameter (kg m^2)


def section_profile(g: Geometry, n_side: int, n_crown: int):
    """Reference mid-surface of the section, bead to bead.

    Returns (y, r, elem_part) for n_s = 2 n_side + n_crown + 1 nodes: y lateral, r radial
    (distance from the axle). Each sidewall (bead to belt edge) has `n_side` equal-arc elements
    and the crown `n_crown`. The right half is a crown arc, an elliptic shoulder and an elliptic
    lower sidewall (a wide-base truck section: flat crown of large transverse radius, widest point
    at `widest_point_ratio` of the section height, vertical tangent at the flange); the left half
    mirrors it exactly. The widest point is at section_width / 2 - carcass_inset (0: the outer
    width; half the sidewall's thickness: the carcass, where the mid-surface is).
    The sidewall is split into the five sidewall parts by arc length, bead to belt edge.
    """
    n_sw = N_PARTS - 1
    if n_side < n_sw or n_side % n_sw:
        raise ValueError(f"mesh.n_side = {n_side}: must be a positive multiple of {n_sw} (one part per element at least)")
    if n_crown < 4 or n_crown % 2:
        raise ValueError(f"mesh.n_crown = {n_crown}: must be an even integer >= 4 (>= 5 nodes across the crown)")
    r_belt = g.outer_radius - g.tread_depth
    r_bead = g.rim_radius + g.flange_height
    hb = g.belt_width / 2
    half_w = g.section_width / 2 - g.carcass_inset
    r_mw = g.rim_radius + g.widest_point_ratio * g.section_height  # widest point of the section
    if not (g.rim_width / 2 < hb < half_w and r_bead < r_mw < r_belt):
        raise ValueError("tire geometry: need rim_width < belt_width < section_width and a "
                         "section height that puts the widest point between bead and belt")
    # dense polylines of the right half: a crown arc of large transverse radius (centre -> belt
    # edge), and the sidewall from the bead up to the belt edge: an elliptic lower sidewall
    # (vertical tangent at the flange) and an elliptic shoulder from the widest point
    yc = np.linspace(0.0, hb, 400)
    rc = r_belt - yc**2 / (2 * g.crown_radius)
    t = np.linspace(0, np.pi / 2, 400)
    yl = g.rim_width / 2 + (half_w - g.rim_width / 2) * np.sin(t)
    rl = r_bead + (r_mw - r_bead) * (1 - np.cos(t))
    ys_ = hb + (half_w - hb) * np.cos(t[1:])
    rs_ = r_mw + (rc[-1] - r_mw) * np.sin(t[1:])
    side = np.stack([np.concatenate([yl, ys_]), np.concatenate([rl, rs_])], axis=1)
    crown = np.stack([yc, rc], axis=1)

    def resample(p, n):
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
        s = np.linspace(0, arc[-1], n + 1)
        return np.stack([np.interp(s, arc, p[:, 0]), np.interp(s, arc, p[:, 1])], axis=1)

    side_n = resample(side, n_side)  # right bead -> belt edge
    crown_n = resample(crown, n_crown // 2)  # centre -> belt edge
    right = np.concatenate([crown_n, side_n[::-1][1:]], axis=0)  # centre -> right bead
    yr = np.concatenate([right[::-1][:-1] * [-1, 1], right], axis=0)
    side_parts = np.arange(n_side) * n_sw // n_side  # bead ... shoulder
    elem_part = np.concatenate([side_parts, np.full(n_crown, CROWN), side_parts[::-1]]).astype(np.int32)
    return yr[:, 0], yr[:, 1], elem_part


@dataclasses.dataclass(frozen=True, eq=False)
class Mesh:
    """Static topology and reference geometry (numpy). Shapes use T = n_theta, S = n_s.

    nodes:        (T, S, 3) reference mid-surface positions, m
    ghosts:       (T, 2, 3) rim-attached points continuing the section beyond each bead (they
                  clamp the bead rotation: the carcass leaves the rim at a fixed angle)
    elem_part:    (S-1,) part index of each meridional element
    node_part:    (S,) part index used for node-based terms (circumferential edges, hinges)
    node_mass:    (T, S) lumped mass, kg (bead nodes' mass moves with the rim)
    tread_depth:  (S,) rubber thickness above the mid-surface, m (0 off the tread)
    w_circ:       (T, S) circumferential tributary width of each node, m
    l_mer:        (T, S) meridional tributary length of each node, m
    """

    n_theta: int
    n_s: int
    geometry: Geometry
    nodes: np.ndarray
    ghosts: np.ndarray
    elem_part: np.ndarray
    node_part: np.ndarray
    node_mass: np.ndarray
    tread_depth: np.ndarray
    w_circ: np.ndarray
    l_mer: np.ndarray
    rim_mass: float  # rim + bead nodes, kg
    rim_inertia: np.ndarray  # (3,) about x, y (axle), z, kg m^2, beads included
    belt_mask: np.ndarray  # (S,) nodes of the belt (the crown part: belt, undertread, tread)

    @property
    def n_free(self) -> int:
        return self.n_s - 2

    @property
    def tread_nodes(self) -> np.ndarray:
        """Section indices of nodes that carry tread rubber (can touch a road)."""
        return np.nonzero(self.tread_depth > 0)[0]

    def masses(self) -> dict:
        """Tire, belt and rim masses (kg) and the belt's and the rest of the tire's inertias (kg m^2:
        sidewalls and beads, about the axle y and about x), for reporting and the rigid ring."""
        m = self.node_mass
        x, y, z = self.nodes[..., 0], self.nodes[..., 1], self.nodes[..., 2]
        belt = m * self.belt_mask[None, :]
        rest = m - belt
        return {
            "tire_kg": float(m.sum()),
            "belt_kg": float(belt.sum()),
            "rim_kg": float(self.rim_mass - m[:, [0, -1]].sum()),
            "belt_Iy_kgm2": float((belt * (x**2 + z**2)).sum()),
            "belt_Ix_kgm2": float((belt * (y**2 + z**2)).sum()),
            "nonbelt_Iy_kgm2": float((rest * (x**2 + z**2)).sum()),
            "nonbelt_Ix_kgm2": float((rest * (y**2 + z**2)).sum()),
        }


def build_mesh(g: Geometry, masses: MassTargets, n_theta: int, n_side: int, n_crown: int) -> Mesh:
    """Sweep the tire's section profile into a ring of `n_theta` segments and lump the masses."""
    y, r, elem_part = section_profile(g, n_side, n_crown)
    return build_mesh_from_section(g, masses, n_theta, y, r, elem_part)


def build_mesh_from_section(g: Geometry, masses: MassTargets, n_theta: int, y, r, elem_part) -> Mesh:
    """Sweep any bead-to-bead section (y, r: (S,) m; elem_part: (S-1,) part indices) around the axle.

    Areal densities are set per region so that the crown region (the crown part: the rigid-ring
    "belt" with its tread) carries the belt mass and the rest of the section carries the remainder
    of the tire mass: the data give those two masses, not a density per part.
    """
    if n_theta < 16:
        raise ValueError(f"mesh.n_theta = {n_theta}: must be >= 16")
    y, r, elem_part = np.asarray(y, float), np.asarray(r, float), np.asarray(elem_part, np.int32)
    n_s = y.shape[0]
    theta = np.arange(n_theta) * 2 * np.pi / n_theta
    # theta measured from the contact point (bottom, -z) towards +x: node i=0 is at the bottom
    ct, st = np.cos(theta), np.sin(theta)
    nodes = np.stack(
        [r[None, :] * st[:, None], np.broadcast_to(y, (n_theta, n_s)), -r[None, :] * ct[:, None]], axis=-1
    )
    # ghosts: one element length beyond each bead along the profile tangent there
    def ghost(j0, j1):
        d = np.array([y[j0] - y[j1], r[j0] - r[j1]])
        yg, rg = y[j0] + d[0], r[j0] + d[1]
        return np.stack([rg * st, np.full(n_theta, yg), -rg * ct], axis=-1)

    ghosts = np.stack([ghost(0, 1), ghost(n_s - 1, n_s - 2)], axis=1)
    # a node takes the part of the element on its crown side (so the belt edge node is belt)
    half = n_s // 2
    node_part = np.concatenate([elem_part[:half], [CROWN], elem_part[half:]]).astype(np.int32)
    # tributary lengths
    l_elem = np.hypot(np.diff(y), np.diff(r))
    l_node = np.zeros(n_s)
    l_node[:-1] += 0.5 * l_elem
    l_node[1:] += 0.5 * l_elem
    dtheta = 2 * np.pi / n_theta
    w_circ = np.broadcast_to(r * dtheta, (n_theta, n_s)).copy()
    l_mer = np.broadcast_to(l_node, (n_theta, n_s)).copy()
    # tread: full depth over the tread width, tapering to zero across the shoulder
    hw = g.tread_width / 2
    taper = np.clip(1.0 - (np.abs(y) - hw) / 0.03, 0.0, 1.0)
    tread_depth = np.where(r > g.rim_radius + 0.75 * g.section_height, g.tread_depth * taper, 0.0)
    # masses: areal density per region from the target masses
    belt_mask = node_part == CROWN
    area = w_circ * l_mer
    a_belt = area[:, belt_mask].sum()
    a_rest = area[:, ~belt_mask].sum()
    rho_rest = (masses.tire - masses.belt) / a_rest if a_rest > 0 else 0.0
    rho = np.where(belt_mask, masses.belt / a_belt, rho_rest)
    node_mass = area * rho[None, :]
    bead_m = node_mass[:, [0, -1]]
    bead_xyz = nodes[:, [0, -1]]
    rim_mass = masses.rim + bead_m.sum()
    rim_inertia = np.array([
        masses.rim_Ixz + (bead_m * (bead_xyz[..., 1] ** 2 + bead_xyz[..., 2] ** 2)).sum(),
        masses.rim_Iy + (bead_m * (bead_xyz[..., 0] ** 2 + bead_xyz[..., 2] ** 2)).sum(),
        masses.rim_Ixz + (bead_m * (bead_xyz[..., 0] ** 2 + bead_xyz[..., 1] ** 2)).sum(),
    ])
    return Mesh(
        n_theta=n_theta, n_s=n_s, geometry=g, nodes=nodes, ghosts=ghosts, elem_part=elem_part,
        node_part=node_part, node_mass=node_mass, tread_depth=tread_depth, w_circ=w_circ,
        l_mer=l_mer, rim_mass=float(rim_mass), rim_inertia=rim_inertia, belt_mask=belt_mask,
    )
