"""The phases every experiment starts with: inflate with the rim held, settle, meet the road, load.

Settling is dynamic relaxation: the explicit dynamics with mass-proportional damping (critical
for the tire's lowest in-plane modes, ~30-60 Hz) and the loads ramped smoothly, run until the
kinetic energy falls below `ke_tol` (a diffrax event), and checked after the run (a phase that
hit its time limit instead is reported as not settled: the result is not valid). Measured on the
default tire: inflation settles in ~0.1 s of simulated time, loading in ~0.1-0.2 s.
Dynamic relaxation was chosen over a Newton solve because it needs no initial guess that moves with
the prescribed rim and passes through contact and friction changes without special cases (physics
notes: Newton statics converged only with such guesses).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .. import solve
from ..physics.contact import FlatRoad, NoSurface
from ..state import Drive, TireState

RIM_LOCKED = np.zeros(6)
RIM_Z = np.array([0.0, 0, 1, 0, 0, 0])
RIM_YZ = np.array([0.0, 1, 1, 0, 0, 0])


class Protocol(eqx.Module):
    """Solver and settling settings, SI, as arrays (so they are never static)."""

    settle_damping: jnp.ndarray  # 1/s
    ke_tol: jnp.ndarray  # J
    inflate_ramp: jnp.ndarray  # s
    inflate_max: jnp.ndarray  # s
    load_ramp: jnp.ndarray  # s
    settle_max: jnp.ndarray  # s, after the end of a ramp

    @staticmethod
    def from_dict(d):
        return Protocol(**{k: jnp.asarray(float(d[k]), dtype=float) for k in  # dtype: never weakly typed (a weak leaf would retrace)
                           ("settle_damping", "ke_tol", "inflate_ramp", "inflate_max", "load_ramp", "settle_max")})


def steps_for(duration: float, dt: float) -> int:
    """Static loop bound for a phase: the shared solve.MAX_STEPS (one compiled program for all
    phases); a phase that would need more is refused here rather than cut short."""
    n = int(np.ceil(duration / dt)) + 16
    if n > solve.MAX_STEPS:
        from ..errors import ConfigError

        raise ConfigError(f"phase of {duration:g} s needs {n} steps of {dt:.3g} s: more than the {solve.MAX_STEPS} allowed")
    return solve.MAX_STEPS


def make_drive(pressure, dt, proto, *, pressure0=None, force0=np.zeros(6), force1=np.zeros(6), t0=0.0, t1=0.0,
               rim_free=RIM_LOCKED, rim_velocity=np.zeros(6), surface=None, damping=None, rim_frame=0.0,
               gravity=np.zeros(3), rigid_belt=False, belt_load0=None, belt_load1=None):
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    return Drive(
        pressure0=f(pressure if pressure0 is None else pressure0), pressure1=f(pressure), force0=f(force0),
        force1=f(force1), t_ramp0=f(t0), t_ramp1=f(t1), rim_free=f(rim_free), rim_velocity=f(rim_velocity),
        surface=NoSurface() if surface is None else surface,
        settle_damping=f(proto.settle_damping if damping is None else damping), damp_rim_frame=f(rim_frame),
        gravity=f(gravity), dt=f(dt), rigid_belt=bool(rigid_belt),
        belt_load0=None if belt_load1 is None else f(np.zeros(6) if belt_load0 is None else belt_load0),
        belt_load1=None if belt_load1 is None else f(belt_load1),
    )


def far_road():
    """A flat road far below the tire: the same surface type as the loaded phases (so the
    inflation phase reuses their compiled program) with no contact."""
    return flat_road(-10.0)


def inflate(model, params, pressure, dt, proto, max_steps: int):
    """Rim held, pressure ramped 0 -> p, run until settled. Returns a PhaseResult."""
    drive = make_drive(pressure, dt, proto, pressure0=0.0, t0=0.0, t1=proto.inflate_ramp, surface=far_road())
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    ts = jnp.linspace(0.0, proto.inflate_max, solve.N_SAVE)
    return solve.run_phase_jit(model, params, drive, y0, jnp.asarray(0.0), proto.inflate_max, ts,
                               proto.inflate_ramp, proto.ke_tol, max_steps)


def first_contact_height(model, y):
    """Road height (m) that just touches the lowest tread point of state y."""
    P = model.tread_points(model.assemble(y.x, y.q))
    return jnp.min(P.z)


def load_phase(model, params, pressure, dt, proto, y0, t0, road, force0, force1, rim_free, ramp, max_time,
               max_steps: int, damping=None, rigid_belt=False, belt_load0=None, belt_load1=None):
    """Ramp the rim force force0 -> force1 over `ramp` s from t0 with the road `road`, then settle."""
    drive = make_drive(pressure, dt, proto, force0=force0, force1=force1, t0=t0, t1=t0 + ramp,
                       rim_free=rim_free, surface=road, damping=damping, rigid_belt=rigid_belt,
                       belt_load0=belt_load0, belt_load1=belt_load1)
    ts = jnp.linspace(t0, t0 + max_time, solve.N_SAVE)
    return solve.run_phase_jit(model, params, drive, y0, jnp.asarray(t0), jnp.asarray(t0 + max_time), ts,
                               jnp.asarray(t0 + ramp), proto.ke_tol, max_steps)


def flat_road(height):
    return FlatRoad(height=jnp.asarray(height, float), velocity=jnp.zeros(3))


def with_spin(model, y, omega):
    """State y set spinning about the axle at omega (rad/s, + = forward rolling in ISO axes, the
    bottom of the tire moving towards -x): every node gets the rim frame's velocity, so rolling
    starts without a spin-up transient."""
    import equinox as eqx

    from ..physics import rim

    qd = y.qd.at[4].set(omega)
    v = rim.frame_velocity(y.q, qd, y.x)
    return eqx.tree_at(lambda s: (s.qd, s.v), y, (qd, v))
