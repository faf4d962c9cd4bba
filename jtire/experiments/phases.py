"""The pieces every experiment is built from: the case, the solver protocol, drives, and the
branches that inflate the tire and load it onto a surface.

Settling is dynamic relaxation: the explicit dynamics with mass-proportional damping and the loads
ramped smoothly, run until the kinetic energy falls below `ke_tol` (a diffrax event, checked after the
run: a phase that hit its time limit instead is not settled and its result not valid).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics import rim
from ..physics.contact import FlatRoad, NoSurface
from ..state import Drive, TireState
from .loads import DOWN, RIM_Z
from .program import Phase, f64, run_plan


class Case(eqx.Module):
    """One case of an experiment, traced: vertical load (N), pressure (Pa), the explicit step (s,
    from `solve.stable_step` for this tire and pressure) and `aux`, the experiment's own case
    variables (e.g. the slip angle), shape (k,)."""

    load: jax.Array
    pressure: jax.Array
    dt: jax.Array
    aux: jax.Array

    @staticmethod
    def of(load, pressure, dt, aux=()):
        return Case(f64(load), f64(pressure), f64(dt), f64(np.asarray(aux, float).reshape(-1)))


class Protocol(eqx.Module):
    """Solver and settling settings, SI, as arrays (never static, never weakly typed)."""

    settle_damping: jax.Array  # 1/s
    ke_tol: jax.Array  # J
    inflate_ramp: jax.Array  # s
    inflate_max: jax.Array  # s
    load_ramp: jax.Array  # s
    settle_max: jax.Array  # s, after the end of a ramp

    @staticmethod
    def from_dict(d):
        return Protocol(**{k: f64(float(d[k])) for k in
                           ("settle_damping", "ke_tol", "inflate_ramp", "inflate_max", "load_ramp", "settle_max")})

    def as_dict(self) -> dict:
        return {k: float(getattr(self, k)) for k in
                ("settle_damping", "ke_tol", "inflate_ramp", "inflate_max", "load_ramp", "settle_max")}


def make_drive(pressure, dt, *, pressure0=None, force0=np.zeros(6), force1=np.zeros(6), t0=0.0, t1=0.0,
               rim_free=np.zeros(6), rim_velocity=np.zeros(6), surface=None, damping=0.0, rim_frame=0.0,
               gravity=np.zeros(3), rigid_belt=False, belt_load0=None, belt_load1=None):
    """A Drive with every leaf a float64 array (traced values pass through unchanged)."""
    return Drive(
        pressure0=f64(pressure if pressure0 is None else pressure0), pressure1=f64(pressure), force0=f64(force0),
        force1=f64(force1), t_ramp0=f64(t0), t_ramp1=f64(t1), rim_free=f64(rim_free), rim_velocity=f64(rim_velocity),
        surface=NoSurface() if surface is None else surface, settle_damping=f64(damping),
        damp_rim_frame=f64(rim_frame), gravity=f64(gravity), dt=f64(dt), rigid_belt=bool(rigid_belt),
        belt_load0=None if belt_load1 is None else f64(np.zeros(6) if belt_load0 is None else belt_load0),
        belt_load1=None if belt_load1 is None else f64(belt_load1),
    )


def flat_road(height, velocity=np.zeros(3)):
    return FlatRoad(height=f64(height), velocity=f64(velocity))


FAR = 10.0  # m below the axle: a surface placed here touches nothing (same type as the real one)


def first_contact_height(model, y):
    """Height (m) of the lowest tread point of state y: a flat road there just touches it."""
    return jnp.min(model.tread_points(model.assemble(y.x, y.q)).z)


def inflate_branch(case, proto, surface, **drive_kw):
    """Rim held, pressure ramped 0 -> p over inflate_ramp, run until settled (at most inflate_max).
    `surface` is of the same type as the experiment's later phases, placed out of reach."""
    def branch(y, t, mem):
        drive = make_drive(case.pressure, case.dt, pressure0=0.0, t0=t, t1=t + proto.inflate_ramp, surface=surface,
                           damping=proto.settle_damping, **drive_kw)
        return Phase(drive, y, proto.inflate_max, proto.inflate_ramp), mem
    return branch


def load_branch(model, case, proto, surface_at, force1, rim_free, *, force0=np.zeros(6), ramp=None, hold=None,
                mem_key="z_road", **drive_kw):
    """Ramp the rim force force0 -> force1 over `ramp` (default load_ramp) and settle (at most
    `hold`, default settle_max, after the ramp). surface_at(mem) -> the surface (e.g. a road at
    mem["z_road"]). When mem_key is given and mem[mem_key] is not yet set (nan), it is set here to
    the first contact height of the start state (the road that just touches the inflated tire)."""
    ramp = proto.load_ramp if ramp is None else ramp
    hold = proto.settle_max if hold is None else hold

    def branch(y, t, mem):
        if mem_key is not None:
            z = first_contact_height(model, y)
            mem = dict(mem, **{mem_key: jnp.where(jnp.isnan(mem[mem_key]), z, mem[mem_key])})
        drive = make_drive(case.pressure, case.dt, force0=force0, force1=force1, t0=t, t1=t + ramp,
                           rim_free=rim_free, surface=surface_at(mem), damping=proto.settle_damping, **drive_kw)
        return Phase(drive, y, ramp + hold, ramp), mem
    return branch


def with_spin(y, omega):
    """State y set spinning about the axle at omega (rad/s, + = forward rolling in ISO axes, the
    bottom of the tire moving towards -x): every node gets the rim frame's velocity, so rolling
    starts without a spin-up transient."""
    qd = y.qd.at[4].set(omega)
    v = rim.frame_velocity(y.q, qd, y.x)
    return eqx.tree_at(lambda s: (s.qd, s.v), y, (qd, v))


def spin_increment(y, d_omega):
    """State y with the whole wheel (rim and nodes) spun d_omega (rad/s) faster about the axle: a
    rigid increment that adds no deformation rate, so a new wheel speed starts without a jolt."""
    dq = jnp.zeros(6).at[4].set(d_omega)
    return eqx.tree_at(lambda s: (s.qd, s.v), y, (y.qd + dq, y.v + rim.frame_velocity(y.q, dq, y.x)))


def loaded_plan(model, params, case, proto, load, n_save, extra=(), ramp=None, mem=None):
    """Inflate, touch the road, ramp `load` (N) onto the rim (z free) over `ramp` (default the
    protocol's) and settle, then any `extra` branches. Returns (PhaseOut stacked, end state, mem with
    z_road and the entries of `mem`)."""
    branches = [inflate_branch(case, proto, flat_road(-FAR)),
                load_branch(model, case, proto, lambda mem: flat_road(mem["z_road"]), load * DOWN, RIM_Z, ramp=ramp),
                *extra]
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    return run_plan(model, params, branches, y0, {"z_road": jnp.nan} | (mem or {}), proto.ke_tol, n_save)
