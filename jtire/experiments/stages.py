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

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import solve
from .. import units as U
from ..equilibrium import rolling as ER
from ..equilibrium.rolling import road_velocity
from ..schema import Field
from .base import Experiment
from .loads import DOWN, RIM_Z_SPIN
from .phases import flat_road, loaded_plan, make_drive, with_spin
from .program import Phase, check_phase, f64, phase, phase_checks
from .steady import check_subpoints, loaded

RAMP_STAGE_S = 0.005  # s per step of the damping ramp: a third of the rim's torsional period (~17 ms)
STAGE_CODE = {"settle": 0, "ramp": 1, "release": 2, "measure": 3}


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


# Stage lengths: the defaults let the dissipated power settle in the damped rolling, the ramp and the
# free rolling calm the spin, and the measurement give the hub-force mean to a few percent (block
# standard error reported); measured on the default tire (docs/design-notes.md).
ROLLING_SCHEMA = {
    "speed_mph": Field(float, U.MPH, 0.5, 60, 15.0, "mph"),
    "settle_s": Field(float, 1, 0.005, 2, 0.04, "s"),
    "ramp_s": Field(float, 1, 0.0, 1, 0.06, "s"),
    "release_s": Field(float, 1, 0.0, 2, 0.02, "s"),
    "measure_s": Field(float, 1, 0.005, 5, 0.08, "s"),
}


class Rolling(Experiment):
    """Settings shared by the rolling experiments (E10, E11, E12)."""

    speed: jax.Array
    settle_s: jax.Array
    measure_s: jax.Array
    damping: jax.Array  # 1/s, relative to the rim frame, in the settle stage
    ramp_s: float = eqx.field(static=True)
    release_s: float = eqx.field(static=True)
    outer_radius: float = eqx.field(static=True)
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)
    method: str = eqx.field(static=True, default="transient")  # "steady": `experiments.steady`
    subpoints: int = eqx.field(static=True, default=8)  # steady: contact points per segment
    load_levels: int = eqx.field(static=True, default=3)  # steady: levels of the loading at speed

    @staticmethod
    def rolling_fields(table, proto, tire_spec, damping=0.0, name=""):
        steady = {}
        if "method" in table:
            steady = dict(method=table["method"], load_levels=int(table["steady_load_levels"]),
                          subpoints=check_subpoints(name, table, tire_spec))
        return dict(proto=proto, speed=f64(table["speed_mph"]), settle_s=f64(table["settle_s"]),
                    measure_s=f64(table["measure_s"]),
                    damping=f64(damping if damping > 0 else float(proto.settle_damping)),
                    ramp_s=float(table["ramp_s"]), release_s=float(table["release_s"]),
                    outer_radius=float(tire_spec.geometry.outer_radius), **steady)

    def loaded(self, model, params, case, road=ER.Road(), slip_angle=0.0):
        """The steady free-rolling loaded path of `case` at this experiment's speed."""
        return loaded(model, params, case, road, self.speed, subpoints=self.subpoints, n_load=self.load_levels,
                      outer_radius=self.outer_radius, slip_angle=slip_angle)

    def roll(self, model, params, case, slip_angle):
        outs, y, mem = rolling_plan(model, params, case, self.proto, outer_radius=self.outer_radius, speed=self.speed,
                                    slip_angle=slip_angle, settle_s=self.settle_s, ramp_s=self.ramp_s,
                                    release_s=self.release_s, measure_s=self.measure_s, damping=self.damping,
                                    n_save=self.n_save)
        return {"phases": outs}

    def stages(self):
        return ["inflate", "load"] + stage_names(self.ramp_s, self.release_s)

    def check(self, out, model, where=""):
        names = self.stages()
        for i, name in enumerate(names):
            check_phase(name, phase(out["phases"], i), model, require_settled=i < 2, where=where)
        return phase_checks("inflate", phase(out["phases"], 0), model) | phase_checks("load", phase(out["phases"], 1), model)

    def measure_samples(self, out):
        """(t (n_save,), saved dict) of the measurement stage (numpy)."""
        ms = phase(out["phases"], len(self.stages()) - 1)
        t = np.linspace(float(ms.t0), float(ms.t_end), self.n_save)
        return t, jax.tree_util.tree_map(np.asarray, ms.saved)
