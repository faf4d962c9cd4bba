"""TireModel: the mesh's reference arrays plus the maps the force terms are built on.

Degrees of freedom are the free nodes x (a V of (T, S-2) planes) and the rim's 6 coordinates q; the beads and
their ghosts follow the rim (`physics.rim`), which removes the stiffest springs of the model. All
terms are written as functions of the assembled net X (a V of (T, S+2) planes:
`physics.geometry_ops`), so their forces on (x, q)
come from autodiff of one map each (physics notes: forces f = -vjp(g)(sigma)).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .mesh import CROWN, Mesh
from .materials import MaterialParams
from .physics import bending, membrane, pressure, rim, tread
from .physics.geometry_ops import V


class TireModel(eqx.Module):
    """Static structure (tuples, ints) and reference geometry (arrays) of one mesh.

    Built once per mesh by `TireModel.from_mesh`; hashable structure is static, so a sweep or a
    calibration reuses one compiled program for any parameters and conditions.
    """

    n_theta: int = eqx.field(static=True)
    n_s: int = eqx.field(static=True)
    n_sub: int = eqx.field(static=True)
    elem_part_t: tuple = eqx.field(static=True)
    node_part_t: tuple = eqx.field(static=True)
    tread_cols_t: tuple = eqx.field(static=True)
    strain_part_t: tuple = eqx.field(static=True)  # part index of every generalized strain
    vol_sign: float = eqx.field(static=True)
    normal_sign: float = eqx.field(static=True)
    elem_is_crown: jnp.ndarray
    node_is_crown: jnp.ndarray
    w_mer_edge: jnp.ndarray  # (T, S-1)
    L0_mer: jnp.ndarray  # (T, S-1)
    l_circ_edge: jnp.ndarray  # (T, S-2)
    L0_circ: jnp.ndarray  # (T, S-2)
    quad_area: jnp.ndarray  # (T, S-1)
    w_node: jnp.ndarray  # (T, S)
    l_node: jnp.ndarray  # (T, S)
    tread_depth: jnp.ndarray  # (n_tread,)
    node_mass: jnp.ndarray  # (T, S-2) free nodes, kg
    rim_mass: jnp.ndarray  # kg, beads included
    rim_inertia: jnp.ndarray  # (3,) kg m^2
    x_ref: V  # (T, S-2) planes: free nodes, reference (unloaded mould shape)
    att_ref: V  # (T, 4) planes: ghostL, beadL, beadR, ghostR in the rim frame
    s0: jnp.ndarray  # (n_strain,) generalized strains of the reference (stress free)
    belt_mask: jnp.ndarray  # (T, S-2) 1 on the free nodes of the belt (crown part)

    @property
    def elem_part(self):
        return np.asarray(self.elem_part_t, np.int32)

    @property
    def node_part(self):
        return np.asarray(self.node_part_t, np.int32)

    @property
    def tread_cols(self):
        return np.asarray(self.tread_cols_t, np.int32)

    @property
    def n_points(self) -> int:
        return self.n_theta * len(self.tread_cols_t) * self.n_sub

    @staticmethod
    def from_mesh(mesh: Mesh, n_sub: int = 2) -> "TireModel":
        T, S = mesh.n_theta, mesh.n_s
        X = np.concatenate([mesh.ghosts[:, :1], mesh.nodes, mesh.ghosts[:, 1:]], axis=1)
        real = mesh.nodes
        L0_mer = np.linalg.norm(np.diff(real, axis=1), axis=-1)
        free = real[:, 1:-1]
        L0_circ = np.linalg.norm(np.roll(free, -1, axis=0) - free, axis=-1)
        w_mer_edge = 0.5 * (mesh.w_circ[:, 1:] + mesh.w_circ[:, :-1])
        quad_area = w_mer_edge * L0_mer
        elem_part = mesh.elem_part
        node_part = mesh.node_part
        crown_e = (elem_part == CROWN).astype(float)
        crown_n = (node_part == CROWN).astype(float)
        tread_cols = mesh.tread_nodes
        strain_part = np.concatenate([
            np.tile(elem_part, T), np.tile(node_part[1:-1], T), np.tile(elem_part, T),
            np.tile(node_part, T), np.tile(node_part[1:-1], T)])
        # orientation signs: cavity volume positive, tread normals pointing away from the axle
        planes = lambda a: V(*(jnp.asarray(a[..., k]) for k in range(3)))  # noqa: E731
        Xj = planes(X)
        v = float(pressure.cavity_volume(Xj, 1.0))
        nrm = tread.outward_normals(Xj, 1.0)[0, S // 2]
        nrm = np.array([float(nrm.x), float(nrm.y), float(nrm.z)])
        normal_sign = 1.0 if float(np.dot(nrm, real[0, S // 2])) > 0 else -1.0
        att = np.stack([X[:, 0], X[:, 1], X[:, -2], X[:, -1]], axis=1)
        model = TireModel(
            n_theta=T, n_s=S, n_sub=int(n_sub), elem_part_t=tuple(int(p) for p in elem_part),
            node_part_t=tuple(int(p) for p in node_part), tread_cols_t=tuple(int(c) for c in tread_cols),
            strain_part_t=tuple(int(p) for p in strain_part), vol_sign=1.0 if v > 0 else -1.0,
            normal_sign=normal_sign, elem_is_crown=jnp.asarray(crown_e), node_is_crown=jnp.asarray(crown_n),
            w_mer_edge=jnp.asarray(w_mer_edge), L0_mer=jnp.asarray(L0_mer), l_circ_edge=jnp.asarray(mesh.l_mer[:, 1:-1]),
            L0_circ=jnp.asarray(L0_circ), quad_area=jnp.asarray(quad_area), w_node=jnp.asarray(mesh.w_circ),
            l_node=jnp.asarray(mesh.l_mer), tread_depth=jnp.asarray(mesh.tread_depth[tread_cols]),
            node_mass=jnp.asarray(mesh.node_mass[:, 1:-1]), rim_mass=jnp.asarray(mesh.rim_mass),
            rim_inertia=jnp.asarray(mesh.rim_inertia), x_ref=planes(free), att_ref=planes(att),
            s0=jnp.zeros(len(strain_part)),
            belt_mask=jnp.asarray(np.broadcast_to(mesh.belt_mask[1:-1].astype(float), free.shape[:2]).copy()),
        )
        s0 = model.strains(model.assemble(model.x_ref, jnp.zeros(6)))
        return eqx.tree_at(lambda m: m.s0, model, s0)

    # ---- maps -------------------------------------------------------------------------------
    def assemble(self, x, q):
        """V of (T, S+2) planes: ghost, bead, free nodes, bead, ghost."""
        att = rim.attached_positions(q, self.att_ref)
        cat = lambda a, b: jnp.concatenate([a[:, :2], b, a[:, 2:]], axis=1)  # noqa: E731
        return V(cat(att.x, x.x), cat(att.y, x.y), cat(att.z, x.z))

    def strains(self, X):
        """Generalized strain vector (n_strain,): lengths (m), shear cosines, hinge angles (rad)."""
        parts = (membrane.meridional_lengths(X), membrane.circumferential_lengths(X),
                 membrane.shear_strains(X), bending.meridional_hinges(X), bending.circumferential_hinges(X))
        return jnp.concatenate([p.reshape(-1) for p in parts])

    def stiffness(self, params: MaterialParams):
        """(n_strain,) long-term stiffness of every generalized strain, in the order of `strains`."""
        k_mer, k_circ, k_shear = membrane.membrane_stiffness(self, params)
        k_mh, k_ch = bending.bending_stiffness(self, params)
        return jnp.concatenate([k.reshape(-1) for k in (k_mer, k_circ, k_shear, k_mh, k_ch)])

    def strain_loss(self, params: MaterialParams):
        """(n_strain,) loss tangent of the rubber behind each generalized strain."""
        return params.loss[np.asarray(self.strain_part_t)]

    def volume(self, X):
        return pressure.cavity_volume(X, self.vol_sign)

    def tread_points(self, X):
        return tread.tread_points(X, self.tread_cols, self.tread_depth, self.n_sub, self.normal_sign)

    def contact_stiffness(self, params: MaterialParams):
        return tread.tread_stiffness(self, params, self.n_sub)

    def strain_energy(self, params, X):
        K = self.stiffness(params)
        d = self.strains(X) - self.s0
        return 0.5 * jnp.sum(K * d * d)
