"""E12 rolling resistance on a flat-track machine: the axle stays, the road moves under it.

The sequence is `stages.rolling_plan` (inflate, load, settle with rim-frame damping, damping ramped
off, release, measure over whole segment-passing periods) at slip angle 0. Two readings of the
rolling resistance (physics notes): the hub force (steady mean of -F_x; `contact_force` is the road's
force on the tire, so the drag is -F_x) and the lost power over the speed (the model's own losses,
smooth: Maxwell branches and tread normal damping, `dissipated`, plus sliding in the patch,
`friction_work`). No rolling-resistance coefficient is prescribed anywhere. The hub force is noisy
(polygon effect, the wheel's rotational modes on the tread's shear stiffness): on the default tire
at 38.7-45.4 kN its standard deviation is 45-75 N around a 200-240 N mean, and an 80 ms mean carries
a block standard error of 3-7 N (1.5-3 %). In steady state the road's power -F_x V equals the lost
power; their relative difference is the energy-balance check.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..errors import ConfigError
from ..schema import Field
from .base import Experiment
from .footprint import run_info
from .program import check_phase, f64, phase, phase_checks
from .result import ExperimentResult
from .stages import STAGE_CODE, rolling_plan, stage_names

N_BLOCKS = 10  # batch means for the standard error of the hub-force mean


def block_stderr(y, n_blocks: int = N_BLOCKS) -> float:
    """Standard error of the mean of a correlated series by batch means (n_blocks equal blocks)."""
    y = np.asarray(y, float)
    n = len(y) // n_blocks
    if n < 2:
        raise ConfigError(f"series of {len(y)} samples: need at least {2 * n_blocks} for {n_blocks} blocks")
    means = y[: n * n_blocks].reshape(n_blocks, n).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(n_blocks))


def reduce_rolling(t, fx, fz, dissipated, speed, friction=None):
    """Rolling resistance from one measurement window.

    t, fx, fz, dissipated, friction: (n,) samples at uniform times spanning a whole number of
    ripple periods, endpoint included (s, N, N, J, J; friction None = no sliding loss); speed m/s.
    The hub-force mean uses samples [0, n-1) (uniform over one half-open span of whole periods);
    the lost powers are exact energies over the span, (D[-1] - D[0]) / T. Returns a dict of SI
    quantities.
    """
    t, fx, fz, d_rub = (np.asarray(a, float) for a in (t, fx, fz, dissipated))
    d_fric = np.zeros_like(t) if friction is None else np.asarray(friction, float)
    d = d_rub + d_fric
    drag = signals.steady_mean(t[:-1], -fx[:-1])
    span = t[-1] - t[0]
    p_diss = (d[-1] - d[0]) / span
    p_fric = (d_fric[-1] - d_fric[0]) / span
    half = len(t) // 2
    p1 = (d[half] - d[0]) / (t[half] - t[0])
    p2 = (d[-1] - d[half]) / (t[-1] - t[half])
    f_power = p_diss / speed
    fz_mean = float(fz[:-1].mean())
    diff = drag.mean - f_power
    return {
        "rolling_resistance_N": drag.mean,
        "rrc": drag.mean / fz_mean,
        "rolling_resistance_stderr_N": block_stderr(-fx[:-1]),
        "rolling_resistance_std_N": drag.std,
        "dissipated_power_W": p_diss,  # rubber + sliding
        "rubber_power_W": p_diss - p_fric,
        "friction_power_W": p_fric,
        "rolling_resistance_from_power_N": f_power,
        "rrc_from_power": f_power / fz_mean,
        "energy_balance_rel_diff": diff / f_power if f_power > 0 else None,  # None: nothing dissipated
        "unaccounted_power_W": diff * speed,  # hub-force noise + O(dt) bristle storage
        "dissipated_power_halves_rel_diff": (p2 - p1) / p_diss if p_diss > 0 else 0.0,
        "vertical_force_N": fz_mean,
        "window_s": span,
    }


# Stage lengths (defaults measured on the default tire at 41.4 kN, 15 mph): the dissipated power is
# within 1 % of its final value after 40 ms of damped rolling; the ramp (60 ms) and 20 ms of free
# rolling leave a spin wobble below 0.006 rad/s; 80 ms (~11 segment periods) of measurement then
# give the hub-force mean to a few percent (block standard error reported).
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

    @staticmethod
    def rolling_fields(table, proto, tire_spec, damping=0.0):
        return dict(proto=proto, speed=f64(table["speed_mph"]), settle_s=f64(table["settle_s"]),
                    measure_s=f64(table["measure_s"]),
                    damping=f64(damping if damping > 0 else float(proto.settle_damping)),
                    ramp_s=float(table["ramp_s"]), release_s=float(table["release_s"]),
                    outer_radius=float(tire_spec.geometry.outer_radius))

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


class RollingResistance(Rolling):
    name = "rolling_resistance"
    study_id = "E12"
    description = "E12 rolling resistance: drag and RRC on a moving flat road, checked against dissipated power"
    schema = ROLLING_SCHEMA | {"calibration_loads_kN": Field(list, U.KN, 1, 500, [38.7, 41.4], "kN"),
                               "calibration_targets_N": Field(list, 1, 0, 1e5, [1529.39, 1701.11], "N")}
    traced_names = ("rolling_resistance_N", "rolling_resistance_from_power_N", "rrc")
    quantity_names = ("rolling_resistance_N", "rrc", "rolling_resistance_stderr_N", "rolling_resistance_std_N",
                      "dissipated_power_W", "rubber_power_W", "friction_power_W", "rolling_resistance_from_power_N",
                      "rrc_from_power", "energy_balance_rel_diff", "unaccounted_power_W",
                      "dissipated_power_halves_rel_diff", "vertical_force_N", "window_s",
                      "effective_rolling_radius_m", "spin_rad_per_s", "deflection_m", "speed_m_per_s", "load_N",
                      "target_N", "error_vs_target_rel")

    calibration: tuple = eqx.field(static=True, default=())

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        loads, targets = table["calibration_loads_kN"], table["calibration_targets_N"]
        if len(loads) != len(targets):
            raise ConfigError(f"rolling_resistance.calibration_targets_N: {len(targets)} values, must match "
                              f"calibration_loads_kN ({len(loads)})")
        return cls(calibration=tuple(zip(loads, targets)), **cls.rolling_fields(table, proto, tire_spec))

    def simulate(self, model, params, case):
        return self.roll(model, params, case, 0.0)

    def traced(self, model, params, condition_cases, outputs):
        ms = jax.tree_util.tree_map(lambda a: a[-1], outputs[0]["phases"])
        fx, fz = ms.saved["contact_force"][:-1, 0], ms.saved["contact_force"][:-1, 2]
        d = ms.saved["dissipated"] + ms.saved["friction_work"]
        span = ms.t_end - ms.t0
        drag = -jnp.mean(fx)
        return {"rolling_resistance_N": drag, "rolling_resistance_from_power_N": (d[-1] - d[0]) / span / self.speed,
                "rrc": drag / jnp.mean(fz)}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model, load, speed = tire.model, condition["load_N"], float(self.speed)
        checks = self.check(out, model)
        t, s = self.measure_samples(out)
        q = reduce_rolling(t, s["contact_force"][:, 0], s["contact_force"][:, 2], s["dissipated"], speed,
                           s["friction_work"])
        spin = (s["q"][-1, 4] - s["q"][0, 4]) / (t[-1] - t[0])
        ld = phase(out["phases"], 1)
        q |= {"effective_rolling_radius_m": speed / spin, "spin_rad_per_s": spin, "deflection_m": -float(ld.q_end[2]),
              "speed_m_per_s": speed, "load_N": load}
        target = next((tg for L, tg in self.calibration if abs(L - load) <= 5e-3 * load), None)
        q["target_N"] = target
        q["error_vs_target_rel"] = None if target is None else (q["rolling_resistance_N"] - target) / target
        checks |= {"vertical_force_vs_load_rel_error": abs(q["vertical_force_N"] - load) / load,
                   "drag_drift_relative": signals.steady_mean(t[:-1], -s["contact_force"][:-1, 0]).drift_relative,
                   "spin_std_in_measurement_rad_per_s": float(s["qd"][:, 4].std()),
                   "settle_work_in_measurement_J": float(s["settle_work"][-1] - s["settle_work"][0])}
        names = self.stages()[2:]
        rows = [phase(out["phases"], i + 2) for i in range(len(names))]
        ts = [np.linspace(float(r.t0), float(r.t_end), self.n_save) for r in rows]  # rolling stages run their full span
        cat = lambda f: np.concatenate([f(jax.tree_util.tree_map(np.asarray, r.saved)) for r in rows])  # noqa: E731
        sig = {"time_s": np.concatenate(ts),
               "stage": np.concatenate([np.full(self.n_save, STAGE_CODE[n]) for n in names]),
               "drag_N": cat(lambda sv: -sv["contact_force"][:, 0]),
               "vertical_force_N": cat(lambda sv: sv["contact_force"][:, 2]),
               "contact_moment_y_Nm": cat(lambda sv: sv["contact_moment"][:, 1]),
               "spin_rad_per_s": cat(lambda sv: sv["qd"][:, 4]),
               "rim_z_m": cat(lambda sv: sv["q"][:, 2]),
               "dissipated_J": cat(lambda sv: sv["dissipated"]),
               "friction_work_J": cat(lambda sv: sv["friction_work"]),
               "settle_work_J": cat(lambda sv: sv["settle_work"])}
        info = run_info(out["phases"]) | {"settle_s": float(self.settle_s), "ramp_s": self.ramp_s,
                                          "release_s": self.release_s, "measure_s": float(t[-1] - t[0])}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
