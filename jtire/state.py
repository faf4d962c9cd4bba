"""The simulation state, the per-step drive (loads, motions, surfaces), and the step update.

Pure state-in/state-out (house rule 3): `TireState.advance` is the kinematic part of the
symplectic (semi-implicit) Euler step: velocities first from the accelerations at the old state,
then positions with the new velocities. Internal variables (Maxwell stresses, bristles) arrive
already updated from the vector field, which integrates them exactly over the step.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .physics.contact import AbstractSurface
from .physics.geometry_ops import V
from .physics.geometry_ops import smooth_step


class TireState(eqx.Module):
    """x, v: V of (T, S-2) free nodes (m, m/s); q, qd: (6,) rim; maxwell: (B, n_strain) branch
    stresses; bristle: V of (N,) tread shear deflections (m); dissipated: J in the rubber (Maxwell
    branches and tread), settle_work: J removed by the artificial settling damping, friction_work:
    J lost to sliding at the contact points (the bristles' plastic slip); aq: (6,) the rim's
    acceleration in the last step (0 on prescribed DOFs), for the settled test's force residual."""

    x: V
    v: V
    q: Float[Array, " 6"]
    qd: Float[Array, " 6"]
    maxwell: Float[Array, "B n"]
    bristle: V
    dissipated: Float[Array, ""]
    settle_work: Float[Array, ""]
    friction_work: Float[Array, ""]
    aq: Float[Array, " 6"]
    drum: Float[Array, " 2"]  # (angle rad, spin rad/s) of a free drum (E06); zero without one

    @staticmethod
    def at_rest(model, n_branches: int):
        z = jnp.zeros(())
        zp = jnp.zeros(model.n_points)
        return TireState(model.x_ref, model.x_ref.map(jnp.zeros_like), jnp.zeros(6), jnp.zeros(6),
                         jnp.zeros((n_branches, model.s0.shape[0])), V(zp, zp, zp), z, z, z, jnp.zeros(6), jnp.zeros(2))

    def advance(self, upd: "Update", h, drive: "Drive"):
        free = drive.rim_free
        qd = jnp.where(free, self.qd + h * upd.aq, drive.rim_velocity)
        v = self.v + upd.ax * h
        return TireState(self.x + v * h, v, self.q + h * qd, qd, upd.maxwell, upd.bristle,
                         self.dissipated + h * upd.power_rubber, self.settle_work + h * upd.power_settle,
                         self.friction_work + h * upd.power_friction, jnp.where(free, upd.aq, 0.0),
                         self._drum(upd, h))

    def _drum(self, upd, h):
        w = self.drum[1] + h * upd.drum_acc
        return jnp.stack([self.drum[0] + h * w, w])


class Update(eqx.Module):
    """What the vector field returns for one step: accelerations and updated internal variables."""

    ax: Array
    aq: Array
    maxwell: Array
    bristle: Array
    power_rubber: Array
    power_settle: Array
    power_friction: Array
    drum_acc: Array = 0.0  # rad/s^2 of a free drum (0 without one)


class Drive(eqx.Module):
    """Everything imposed on the tire during one phase, as arrays (so phases and cases vmap).

    Pressure and rim loads ramp smoothly from their start to their end values over
    [t_ramp0, t_ramp1]; rim DOFs with rim_free = 0 follow rim_velocity (0 = locked).
    settle_damping (1/s): mass-proportional damping for dynamic relaxation, on velocities
    relative to the rim frame (damp_rim_frame = 1) or to the ground (0); 0 in dynamic experiments.
    rigid_belt (static): the crown nodes move as one rigid body (`physics.rigid_belt`).
    belt_load0/1: optional (6,) force + moment on the belt (None: no belt load, nothing computed).
    """

    pressure0: Float[Array, ""]
    pressure1: Float[Array, ""]
    force0: Float[Array, " 6"]
    force1: Float[Array, " 6"]
    t_ramp0: Float[Array, ""]
    t_ramp1: Float[Array, ""]
    rim_free: Float[Array, " 6"]
    rim_velocity: Float[Array, " 6"]
    surface: AbstractSurface
    settle_damping: Float[Array, ""]
    damp_rim_frame: Float[Array, ""]
    gravity: Float[Array, " 3"]
    dt: Float[Array, ""]
    belt_load0: Float[Array, " 6"] = None
    belt_load1: Float[Array, " 6"] = None
    rigid_belt: bool = eqx.field(static=True, default=False)

    @property
    def belt_loaded(self) -> bool:
        return self.belt_load1 is not None

    def belt_load(self, t):
        """(6,) force and moment (about the belt's mass centre) on the belt, ramped like the rim force."""
        return self.belt_load0 + (self.belt_load1 - self.belt_load0) * self.ramp(t)

    def ramp(self, t):
        return smooth_step((t - self.t_ramp0) / jnp.maximum(self.t_ramp1 - self.t_ramp0, 1e-12))

    def pressure(self, t):
        return self.pressure0 + (self.pressure1 - self.pressure0) * self.ramp(t)

    def rim_force(self, t):
        return self.force0 + (self.force1 - self.force0) * self.ramp(t)
