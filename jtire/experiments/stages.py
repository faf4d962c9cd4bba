"""Rolling on the flat-track machine: the axle stays, the road moves under it (E10, E11, E12).

After inflation and loading (rim z free under the load, on a still road) the road starts moving at
V (-cos a, +sin a, 0) (ISO axes, SAE slip angle a) with the rim spin free (no drive torque, "dragged")
and the tire spinning at V / R_est from the first step (`phases.with_spin`: no spin-up), then:
  settle:  mass-proportional damping relative to the RIM FRAME (on absolute velocity it would be a
           fake drag on the spinning tire), `settle_s`;
  ramp:    that damping lowered to zero over `ramp_s` in RAMP_STAGE_S stages (switched off at once it
           rings the wheel's lightly damped rotational modes);
  release: damping off, `release_s`, not measured;
  measure: damping off, a whole number of segment-passing periods close to `measure_s` (a uniform
           mean over whole periods cancels the polygon ripple).
Every stage is one phase of the experiment's plan (one compiled loop for all of them).
"""

import jax.numpy as jnp
import numpy as np

from .footprint import loaded_plan
from .loads import DOWN, RIM_Z_SPIN
from .phases import flat_road, make_drive, with_spin
from .program import Phase

RAMP_STAGE_S = 0.005  # s per step of the damping ramp: a third of the rim's torsional period (~17 ms)
STAGE_CODE = {"settle": 0, "ramp": 1, "release": 2, "measure": 3}


def road_velocity(speed, slip_angle=0.0):
    """(3,) ISO velocity (m/s) of the road under a fixed axle for a wheel travelling at `speed` with
    SAE slip angle `slip_angle` (rad): positive when the wheel centre travels to the RIGHT of its
    heading. The wheel's ground velocity is V (cos a, -sin a, 0) in ISO (y left), so the road moves at
    minus that. The tire then slides right over the road, friction pushes it left: F_y(ISO) > 0, i.e.
    F_y(SAE) < 0 for a > 0 (cornering stiffness = -dF_y,SAE / d alpha > 0)."""
    a = jnp.asarray(slip_angle, dtype=jnp.float64)
    return jnp.stack([-speed * jnp.cos(a), speed * jnp.sin(a), jnp.zeros_like(a)], axis=-1)


def rolling_radius_estimate(outer_radius, deflection):
    """First guess of the effective rolling radius, m: R0 - deflection / 3 (radial tire estimate).
    Only the start spin uses it; the free spin finds the real one during the settle stage."""
    return outer_radius - deflection / 3.0


def segment_period(n_theta: int, omega):
    """Time (s) for one mesh segment to pass the contact patch at spin omega (rad/s)."""
    return 2 * jnp.pi / (n_theta * jnp.abs(omega))


def whole_periods(duration, period):
    """`duration` rounded to a whole number (>= 1) of `period`."""
    return jnp.maximum(1.0, jnp.round(duration / period)) * period


def release_schedule(ramp_s: float) -> list:
    """Damping fractions (1 -> 0 along a smoothstep, sampled at each stage's midpoint) and the stage
    length: [(fraction, duration)] for a ramp of `ramp_s` s in RAMP_STAGE_S stages."""
    n = int(round(ramp_s / RAMP_STAGE_S)) if ramp_s > 0 else 0
    if n == 0:
        return []
    x = (np.arange(n) + 0.5) / n
    return [(float(1 - v * v * (3 - 2 * v)), ramp_s / n) for v in x]


def stage_names(ramp_s: float, release_s: float) -> list:
    return (["settle"] + ["ramp"] * len(release_schedule(ramp_s)) + (["release"] if release_s > 0 else [])
            + ["measure"])


def rolling_plan(model, params, case, proto, *, outer_radius, speed, slip_angle, settle_s, ramp_s, release_s,
                 measure_s, damping, n_save, final=()):
    """The whole rolling sequence for one case. ramp_s, release_s are static (they fix the number of
    stages); the others may be traced. Returns (PhaseOut stacked: inflate, load, stages..., end
    state, mem)."""
    vel = road_velocity(speed, slip_angle)

    def drive(y, t, mem, c):
        return make_drive(case.pressure, case.dt, force0=case.load * DOWN, force1=case.load * DOWN, t0=t, t1=t,
                          rim_free=RIM_Z_SPIN, surface=flat_road(mem["z_road"], vel), damping=c, rim_frame=1.0)

    def settle(y, t, mem):
        r_est = rolling_radius_estimate(outer_radius, -y.q[2])
        return Phase(drive(y, t, mem, damping), with_spin(y, speed / r_est), settle_s, jnp.inf), mem

    def stage(frac, dur):
        return lambda y, t, mem: (Phase(drive(y, t, mem, damping * frac), y, dur, jnp.inf), mem)

    def measure(y, t, mem):
        dur = whole_periods(measure_s, segment_period(model.n_theta, y.qd[4]))
        return Phase(drive(y, t, mem, 0.0), y, dur, jnp.inf), mem

    extra = [settle] + [stage(f, d) for f, d in release_schedule(ramp_s)]
    if release_s > 0:
        extra.append(stage(0.0, release_s))
    extra.append(measure)
    extra += list(final)
    return loaded_plan(model, params, case, proto, case.load, n_save, extra=extra)
