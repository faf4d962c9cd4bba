"""E10 cornering and aligning-torque stiffness (k_f, k_m) and E11 relaxation length sigma = k_f / k_l.

Method "steady" (default): the loaded, free-rolling tire as a steady-rolling equilibrium at every slip
angle (`experiments.steady.slip_angle_sweep`: continuation outwards from 0), one case per condition;
the forces are the equilibrium's own, with no ripple to average (standard errors 0).

Method "transient": the tire is dragged free-rolling (spin free, no drive torque: a truck pusher axle) on the flat-track
machine (`stages.rolling_plan`): the axle stays, the road moves under it at V (-cos a, +sin a, 0) (ISO)
for an SAE slip angle a. Rim lateral position, camber and steer held; z carries the load. Every slip
angle is a case of its own (case aux = the angle), so a whole sweep, or a whole grid of sweeps, is one
batch of one compiled program. The lateral deflection builds up during the settle and ramp stages
(most of the steady force is there before the damping is off: docs/design-notes.md); only the
undamped window is measured.

Reduction (experiments.md), SAE signs at the boundary (y_SAE = -y, z_SAE = -z):
  lateral force in road axes  F_lat = F_y,SAE cos a - F_x sin a
  aligning moment M_z,SAE = -(contact moment about the vertical through the wheel centre, ISO)
  k_f = -d F_lat / d a over `kf_range` (default 0-2 deg), positive (SAE cornering stiffness)
  k_m = d M_z,SAE / d a over `km_range` (default 0-3 deg), positive for an aligning moment.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals
from .. import units as U
from ..errors import ConfigError
from ..schema import Field, check_range_pair
from .base import Experiment
from .lateral import LateralStiffness
from .loads import lateral_sae
from . import steady as ST
from .result import ExperimentResult
from .stages import Rolling


def reduce_cornering(alpha, fx, fy_iso, mz_iso, kf_range, km_range):
    """k_f (N/rad) and k_m (N m/rad) from steady forces at SAE slip angles alpha (rad): slopes over
    the given (lo, hi) ranges in rad (at least 3 angles each). Returns (quantities, curves)."""
    a = np.asarray(alpha, float)
    lat = lateral_sae(a, np.asarray(fx), np.asarray(fy_iso))
    mz = -np.asarray(mz_iso, float)
    kf = signals.linear_slope(a, lat, kf_range)
    km = signals.linear_slope(a, mz, km_range)
    q = {"k_f_N_per_rad": -kf.slope, "k_m_Nm_per_rad": km.slope, "k_f_fit_r2": kf.r2, "k_m_fit_r2": km.r2,
         "k_f_stderr_N_per_rad": kf.stderr, "k_m_stderr_Nm_per_rad": km.stderr,
         "k_f_range_deg": [float(np.degrees(kf.x_lo)), float(np.degrees(kf.x_hi))],
         "k_m_range_deg": [float(np.degrees(km.x_lo)), float(np.degrees(km.x_hi))],
         "pneumatic_trail_m": km.slope / -kf.slope if kf.slope != 0 else float("nan")}
    return q, {"lateral_force_N": lat, "aligning_moment_Nm": mz}


def _slope_traced(x, y, mask):
    """Least-squares slope of y on x over the points where mask (static bool array) is True."""
    x, y = x[mask], y[mask]
    xc = x - x.mean()
    return jnp.sum(xc * (y - y.mean())) / jnp.sum(xc * xc)


def _range_mask(angles, rng, name):
    m = (np.asarray(angles) >= rng[0] - 1e-12) & (np.asarray(angles) <= rng[1] + 1e-12)
    if m.sum() < 3:
        raise ConfigError(f"{name} = {[round(float(np.degrees(v)), 6) for v in rng]} deg: holds {int(m.sum())} of the "
                          f"slip angles, need at least 3")
    return m


COMMON = {
    "method": Field(str, default="steady", choices=("steady", "transient")),
    "speed_mph": Field(float, U.MPH, 0.5, 60, 15.0, "mph"),
    "settle_s": Field(float, 1, 0.005, 5, 0.25, "s"),
    "ramp_s": Field(float, 1, 0.0, 1, 0.06, "s"),
    "release_s": Field(float, 1, 0.0, 2, 0.03, "s"),
    "measure_s": Field(float, 1, 0.005, 5, 0.05, "s"),
    "settle_damping_per_s": Field(float, 1, 0, 1e4, 0.0, "1/s (0: the solver's settle damping)"),
} | ST.STEADY_FIELDS


class Cornering(Rolling):
    name = "cornering"
    study_id = "E10"
    description = "E10 cornering stiffness k_f and aligning-torque stiffness k_m (slip-angle sweep, one case per angle)"
    schema = COMMON | {"slip_angles_deg": Field(list, U.DEG, -30, 30, [0, 1, 2, 3, 4, 6, 8, 10, 12, 20], "deg", min_len=3),
                       "kf_range_deg": Field(list, U.DEG, -30, 30, [0.0, 2.0], "deg"),
                       "km_range_deg": Field(list, U.DEG, -30, 30, [0.0, 3.0], "deg")}
    aux_names = ("slip_angle",)
    traced_names = ("k_f_N_per_rad", "k_m_Nm_per_rad")
    quantity_names = ("k_f_N_per_rad", "k_m_Nm_per_rad", "k_f_fit_r2", "k_m_fit_r2", "k_f_stderr_N_per_rad",
                      "k_m_stderr_Nm_per_rad", "k_f_range_deg", "k_m_range_deg", "pneumatic_trail_m",
                      "peak_lateral_force_N", "peak_lateral_force_over_load", "speed_m_per_s", "load_N")

    slip_angles: tuple = eqx.field(static=True, default=())
    kf_mask: tuple = eqx.field(static=True, default=())
    km_mask: tuple = eqx.field(static=True, default=())
    kf_range: tuple = eqx.field(static=True, default=())
    km_range: tuple = eqx.field(static=True, default=())

    @classmethod
    def from_table(cls, table, proto, tire_spec, name=None):
        name = name or cls.name
        angles = tuple(table["slip_angles_deg"])
        if len(set(angles)) != len(angles):
            raise ConfigError(f"{name}.slip_angles_deg: lists an angle twice")
        kf = check_range_pair(f"{name}.kf_range_deg", table["kf_range_deg"], "deg", U.DEG)
        km = check_range_pair(f"{name}.km_range_deg", table.get("km_range_deg", table["kf_range_deg"]), "deg", U.DEG)
        kf_mask = tuple(bool(v) for v in _range_mask(angles, kf, f"{name}.kf_range_deg"))
        km_mask = tuple(bool(v) for v in _range_mask(angles, km, f"{name}.km_range_deg"))
        return cls(slip_angles=angles, kf_mask=kf_mask, km_mask=km_mask, kf_range=kf, km_range=km,
                   **cls.rolling_fields(table, proto, tire_spec, table["settle_damping_per_s"], name=name))

    def cases(self, condition):
        if self.method == "steady":  # the whole sweep is one continuation
            return [dict(condition)]
        return [dict(condition, slip_angle=a) for a in self.slip_angles]

    def aux(self, case):
        return np.zeros(0) if self.method == "steady" else super().aux(case)

    def simulate(self, model, params, case):
        if self.method == "steady":
            path = self.loaded(model, params, case)
            n = len(path.obs)
            obs, solved = ST.slip_angle_sweep(path, self.slip_angles, self.speed, case.load, subpoints=self.subpoints)
            loaded = ST.stacked(path, range(n))
            return loaded | {"angles": jax.tree_util.tree_map(lambda *a: jnp.stack(a), *obs),
                             "angle_solved": jnp.asarray([s is not False for s in solved]),
                             **ST.sweep_outputs(path, n)}
        return self.roll(model, params, case, case.aux[0])

    def _means(self, outputs, xp):
        if self.method == "steady":
            ang = outputs[0]["angles"]
            return ang["contact_force"], ang["contact_moment"][:, 2]
        f, m = [], []
        for out in outputs:
            s = out["phases"].saved
            f.append(s["contact_force"][-1][:-1].mean(axis=0))  # measure stage, whole periods (half-open)
            m.append(s["contact_moment"][-1][:-1, 2].mean())
        return xp.stack(f), xp.stack(m)

    def traced(self, model, params, condition_cases, outputs):
        f, mz = self._means(outputs, jnp)
        a = jnp.asarray(self.slip_angles)
        lat = lateral_sae(a, f[:, 0], f[:, 1], jnp)
        return {"k_f_N_per_rad": -_slope_traced(a, lat, np.array(self.kf_mask)),
                "k_m_Nm_per_rad": _slope_traced(a, -mz, np.array(self.km_mask))}

    def reduce(self, tire, condition, outputs):
        if self.method == "steady":
            return self._reduce_steady(condition, outputs[0])
        model, load = tire.model, condition["load_N"]
        checks = {}
        for out, a in zip(outputs, self.slip_angles):
            c = self.check(out, model, where=f"slip angle {np.degrees(a):g} deg: ")
            checks |= {f"{k} (slip {np.degrees(a):g} deg)": v for k, v in c.items() if k.endswith("_settled")}
        a = np.asarray(self.slip_angles)
        series = []
        for out in outputs:
            t, s = self.measure_samples(out)
            series.append((t, s))
        fxyz = np.stack([s["contact_force"][:-1] for _, s in series])  # (n, N-1, 3)
        mzs = np.stack([s["contact_moment"][:-1, 2] for _, s in series])
        means = {"F_x": fxyz[..., 0].mean(1), "F_y": fxyz[..., 1].mean(1), "F_z": fxyz[..., 2].mean(1), "M_z": mzs.mean(1)}
        err = {k: np.array([signals.block_stderr(row) for row in v]) for k, v in
               (("F_x", fxyz[..., 0]), ("F_y", fxyz[..., 1]), ("M_z", mzs))}
        drift = np.array([signals.steady_mean(t[:-1], s["contact_force"][:-1, 1]).drift_relative
                          if abs(s["contact_force"][:-1, 1].mean()) > 1.0 else np.nan for t, s in series])
        spin = np.array([(s["q"][-1, 4] - s["q"][0, 4]) / (t[-1] - t[0]) for t, s in series])
        q, curves = reduce_cornering(a, means["F_x"], means["F_y"], means["M_z"], self.kf_range, self.km_range)
        lat = curves["lateral_force_N"]
        q |= {"peak_lateral_force_N": float(np.max(np.abs(lat))),
              "peak_lateral_force_over_load": float(np.max(np.abs(lat))) / load,
              "speed_m_per_s": float(self.speed), "load_N": load}
        sig = {"slip_angle_deg": np.degrees(a), "lateral_force_N": lat,
               "lateral_force_stderr_N": np.hypot(err["F_y"] * np.cos(a), err["F_x"] * np.sin(a)),
               "F_x_N": means["F_x"], "F_y_SAE_N": -means["F_y"], "M_z_SAE_Nm": curves["aligning_moment_Nm"],
               "M_z_stderr_Nm": err["M_z"], "F_z_N": means["F_z"], "spin_rad_per_s": spin, "F_y_drift_rel": drift}
        checks |= {"max_vertical_force_vs_load_rel_error": float(np.max(np.abs(means["F_z"] - load)) / load),
                   "max_lateral_drift_rel_over_window": float(np.nanmax(np.abs(drift))) if np.any(np.isfinite(drift)) else 0.0}
        info = {"n_slip_angles": len(a), "steps_per_angle": [int(np.asarray(o["phases"].n_steps).sum()) for o in outputs],
                "settle_s": float(self.settle_s), "ramp_s": self.ramp_s, "release_s": self.release_s,
                "measure_s": float(series[0][0][-1] - series[0][0][0])}
        info["steps"] = int(sum(info["steps_per_angle"]))
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)

    def _reduce_steady(self, condition, out):
        load = condition["load_N"]
        checks, info = ST.summary(self.name, out["infos"], ST.level_names(self.load_levels))
        a_all = np.asarray(self.slip_angles)
        solved = np.asarray(out["angle_solved"], bool)
        sw = jax.tree_util.tree_map(np.asarray, out["sweep_infos"])
        name = ST.sweep_name("slip angle", out["sweep_values"], 180 / np.pi, "deg")
        stopped = None
        in_fit = np.asarray(self.kf_mask, bool) | np.asarray(self.km_mask, bool)
        if not solved.all() and (solved | ~in_fit).all():
            # angles beyond the k_f and k_m ranges that Newton could not solve: the curve is reported without
            # them (named in info and by `jtire run`); a failure inside the ranges is the case's error
            k = int(np.argmin(sw.converged))
            stopped = (f"{name(k)}: not converged after {int(sw.iterations[k])} Newton iterations (residual "
                       f"{float(sw.residual_max[k]):.3g} N, tolerance {float(sw.tolerance[k]):.3g} N)")
            sw = jax.tree_util.tree_map(lambda v: v[sw.converged], sw)
        sweep, _ = ST.summary(self.name, sw, name, ST.SWEEP_HINT)
        a = a_all[solved]
        ang = jax.tree_util.tree_map(lambda v: np.asarray(v)[solved], out["angles"])
        f, mz = ang["contact_force"], ang["contact_moment"][:, 2]
        q, curves = reduce_cornering(a, f[:, 0], f[:, 1], mz, self.kf_range, self.km_range)
        lat = curves["lateral_force_N"]
        peak = float(np.max(np.abs(lat))) if stopped is None else None  # the peak may lie among the unsolved
        q |= {"peak_lateral_force_N": peak, "peak_lateral_force_over_load": None if peak is None else peak / load,
              "speed_m_per_s": float(self.speed), "load_N": load}
        zero = np.zeros_like(a)
        sig = {"slip_angle_deg": np.degrees(a), "lateral_force_N": lat, "lateral_force_stderr_N": zero,
               "F_x_N": f[:, 0], "F_y_SAE_N": -f[:, 1], "M_z_SAE_Nm": curves["aligning_moment_Nm"],
               "M_z_stderr_Nm": zero, "F_z_N": f[:, 2], "spin_rad_per_s": ang["omega"], "F_y_drift_rel": zero}
        checks |= {"sweep_converged": sweep["steady_converged"], "sweep_complete": stopped is None,
                   "max_vertical_force_vs_load_rel_error": float(np.max(np.abs(f[:, 2] - load)) / load)}
        info |= {"n_slip_angles": len(a), "levels": info["levels"] + int(len(sw.converged)),
                 "newton_iterations": info["newton_iterations"] + int(sw.iterations.sum()),
                 "steady_subpoints": self.subpoints}
        if stopped is not None:
            info |= {"unsolved_slip_angles_deg": [float(v) for v in np.degrees(a_all[~solved])], "sweep_stopped": stopped}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)


class RelaxationLength(Experiment):
    """E11: sigma = k_f / k_l, k_f from a small-angle sweep (E10's reduction), k_l from the static E09
    at the same condition. A composite: the batch runner runs its `components` and `combine`s them."""

    name = "relaxation_length"
    study_id = "E11"
    description = "E11 relaxation length sigma = k_f / k_l (E10 small angles + static E09)"
    quantity_names = ("sigma_m", "k_f_N_per_rad", "k_l_N_per_m", "k_f_fit_r2", "k_f_range_deg", "lateral_force_N",
                      "lateral_deflection_m")
    schema = COMMON | {"slip_angles_deg": Field(list, U.DEG, -30, 30, [0, 1, 2], "deg", min_len=3),
                       "kf_range_deg": Field(list, U.DEG, -30, 30, [0.0, 2.0], "deg"),
                       "lateral_force_kN": Field(float, U.KN, 0.01, 100, 5.0, "kN")}

    cornering: Cornering
    lateral: LateralStiffness

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        t = {k: v for k, v in table.items() if k != "lateral_force_kN"}
        t["km_range_deg"] = t["kf_range_deg"]
        cor = Cornering.from_table(t, proto, tire_spec, name=cls.name)
        lat = LateralStiffness.from_table({"force_kN": table["lateral_force_kN"], "decay_s": 0.0, "release_ramp_ms": 0.0,
                                           "method": "auto"},
                                          proto, tire_spec)
        return cls(proto=proto, cornering=cor, lateral=lat)

    @property
    def components(self):
        return (self.cornering, self.lateral)

    def combine(self, condition, results):
        kf_res, kl_res = results
        k_f, k_l = kf_res.quantities["k_f_N_per_rad"], kl_res.quantities["k_l_N_per_m"]
        q = {"sigma_m": k_f / k_l, "k_f_N_per_rad": k_f, "k_l_N_per_m": k_l, "k_f_fit_r2": kf_res.quantities["k_f_fit_r2"],
             "k_f_range_deg": kf_res.quantities["k_f_range_deg"], "lateral_force_N": kl_res.quantities["lateral_force_N"],
             "lateral_deflection_m": kl_res.quantities["lateral_deflection_m"]}
        checks = kf_res.checks | {f"lateral_{k}": v for k, v in kl_res.checks.items()}
        info = {"steps": kf_res.info.get("steps", 0) + kl_res.info.get("steps", 0)}
        return ExperimentResult(self.name, condition, q, signals=kf_res.signals, checks=checks, info=info)

    def simulate(self, model, params, case):
        raise NotImplementedError("relaxation_length is a composite: run its components")

    def reduce(self, tire, condition, outputs):
        raise NotImplementedError("relaxation_length is a composite: combine its components' results")
