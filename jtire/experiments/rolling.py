"""E12 rolling resistance on a flat-track machine: the axle stays, the road moves under it.

Method "steady" (default): the loaded, free-rolling tire as a steady-rolling equilibrium
(`experiments.steady`): the drag is the hub force, checked against the lost power over the speed (the
two differ by the flow's discretization; beyond `steady.ENERGY_BALANCE_TOL` it is an error). No
settling, no ripple, derivatives by the implicit function theorem.

Method "transient": the sequence is `stages.rolling_plan` (inflate, load, settle with rim-frame damping, damping ramped
off, release, measure over whole segment-passing periods) at slip angle 0. Two readings of the
rolling resistance (physics notes): the hub force (steady mean of -F_x; `contact_force` is the road's
force on the tire, so the drag is -F_x) and the lost power over the speed (the model's own losses,
smooth: Maxwell branches and tread normal damping, `dissipated`, plus sliding in the patch,
`friction_work`). No rolling-resistance coefficient is prescribed anywhere. The hub force is noisy
(polygon effect, the wheel's rotational modes on the tread's shear stiffness), so its mean over the
window carries a block standard error of a few percent (docs/design-notes.md). In steady state the
road's power -F_x V equals the lost power; their relative difference is the energy-balance check.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals
from .. import units as U
from ..errors import ConfigError
from ..schema import Field
from . import steady as ST
from .program import phase, run_info
from .result import ExperimentResult
from .stages import ROLLING_SCHEMA, STAGE_CODE, Rolling

METHOD = {"method": Field(str, default="steady", choices=("steady", "transient"))}

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
        "rolling_resistance_stderr_N": signals.block_stderr(-fx[:-1]),
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


class RollingResistance(Rolling):
    name = "rolling_resistance"
    study_id = "E12"
    description = "E12 rolling resistance: drag and RRC on a moving flat road, checked against dissipated power"
    schema = METHOD | ROLLING_SCHEMA | ST.STEADY_FIELDS | {
        "calibration_loads_kN": Field(list, U.KN, 1, 500, [38.7, 41.4], "kN"),
        "calibration_targets_N": Field(list, 1, 0, 1e5, [1529.39, 1701.11], "N")}
    traced_names = ("rolling_resistance_N", "rolling_resistance_from_power_N", "rrc")
    COMMON = ("rolling_resistance_N", "rrc", "dissipated_power_W", "rubber_power_W", "friction_power_W",
              "rolling_resistance_from_power_N", "rrc_from_power", "energy_balance_rel_diff", "vertical_force_N",
              "effective_rolling_radius_m", "spin_rad_per_s", "deflection_m", "speed_m_per_s", "load_N", "target_N",
              "error_vs_target_rel")
    TRANSIENT = ("rolling_resistance_stderr_N", "rolling_resistance_std_N", "unaccounted_power_W",
                 "dissipated_power_halves_rel_diff", "window_s")
    STEADY = ("viscoelastic_power_W", "tread_damping_power_W", "nodal_damping_power_W")
    quantity_names = COMMON + STEADY

    calibration: tuple = eqx.field(static=True, default=())

    @classmethod
    def produces(cls, table):
        return cls.COMMON + (cls.STEADY if table["method"] == "steady" else cls.TRANSIENT)

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        loads, targets = table["calibration_loads_kN"], table["calibration_targets_N"]
        if len(loads) != len(targets):
            raise ConfigError(f"rolling_resistance.calibration_targets_N: {len(targets)} values, must match "
                              f"calibration_loads_kN ({len(loads)})")
        return cls(calibration=tuple(zip(loads, targets)), **cls.rolling_fields(table, proto, tire_spec,
                                                                                 name=cls.name))

    def simulate(self, model, params, case):
        if self.method == "steady":
            return ST.stacked(self.loaded(model, params, case))
        return self.roll(model, params, case, 0.0)

    def traced(self, model, params, condition_cases, outputs):
        if self.method == "steady":
            lv = jax.tree_util.tree_map(lambda a: a[-1], outputs[0]["levels"])
            drag = -lv["tire_on_rim"][0]
            power = ST.lost_power(lv)
            return {"rolling_resistance_N": drag, "rolling_resistance_from_power_N": power / self.speed,
                    "rrc": drag / lv["contact_force"][2]}
        ms = jax.tree_util.tree_map(lambda a: a[-1], outputs[0]["phases"])
        fx, fz = ms.saved["contact_force"][:-1, 0], ms.saved["contact_force"][:-1, 2]
        d = ms.saved["dissipated"] + ms.saved["friction_work"]
        span = ms.t_end - ms.t0
        drag = -jnp.mean(fx)
        return {"rolling_resistance_N": drag, "rolling_resistance_from_power_N": (d[-1] - d[0]) / span / self.speed,
                "rrc": drag / jnp.mean(fz)}

    def _target(self, load, q):
        target = next((tg for L, tg in self.calibration if abs(L - load) <= 5e-3 * load), None)
        q["target_N"] = target
        q["error_vs_target_rel"] = None if target is None else (q["rolling_resistance_N"] - target) / target
        return q

    def reduce(self, tire, condition, outputs):
        if self.method == "steady":
            return self._reduce_steady(tire, condition, outputs[0])
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
        q = self._target(load, q)
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

    def _reduce_steady(self, tire, condition, out):
        load, speed = condition["load_N"], float(self.speed)
        names = ST.level_names(self.load_levels)
        checks, info = ST.summary(self.name, out["infos"], names)
        lv = ST.level(out, -1)
        drag, fz, omega = -float(lv["tire_on_rim"][0]), float(lv["contact_force"][2]), float(lv["omega"])
        q = {"rolling_resistance_N": drag, "rrc": drag / fz}
        q |= ST.losses(lv)
        f_power = q["dissipated_power_W"] / speed
        q |= {"rolling_resistance_from_power_N": f_power, "rrc_from_power": f_power / fz,
              "energy_balance_rel_diff": ST.require_energy_balance(self.name, drag, q["dissipated_power_W"], speed,
                                                                   tire.spec.n_theta),
              "vertical_force_N": fz, "effective_rolling_radius_m": speed / omega, "spin_rad_per_s": omega,
              "deflection_m": -float(lv["q"][2]), "speed_m_per_s": speed, "load_N": load}
        q = self._target(load, q)
        checks |= {"vertical_force_vs_load_rel_error": abs(fz - load) / load,
                   "hub_vs_contact_force_x_N": abs(float(lv["tire_on_rim"][0]) - float(lv["contact_force"][0]))}
        lvs = jax.tree_util.tree_map(np.asarray, out["levels"])
        sig = {"level": np.arange(len(names)), "vertical_force_N": lvs["contact_force"][:, 2],
               "drag_N": -lvs["tire_on_rim"][:, 0], "spin_rad_per_s": lvs["omega"], "rim_z_m": lvs["q"][:, 2],
               "lost_power_W": ST.lost_power(lvs)}
        info |= {"level_names": names, "steady_subpoints": self.subpoints}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
