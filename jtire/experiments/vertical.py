"""E02 total static vertical stiffness k_sv: the rim load 0 -> max_load on a flat road.

k_sv is the secant load / deflection at the stated load (calibration variant: 50 kN at 120 psi must
give 39.0625 mm); beside it the tangent dF/d(deflection) at that load (k_sv_tangent: what small
motions about the loaded state see) and the slope of a linear fit of load against deflection over
`fit_range`. Deflection is the rim's travel from first contact.

Two methods (`method` in the table):
- "static" (default): static equilibrium at `n_levels` load levels up to max_load and at the stated
  load (`jtire.equilibrium`: Newton on the static residual with long-term moduli, friction carried
  from level to level). A static quantity has no rate: nothing to tune, no viscoelastic lag, each
  level converged to a stated force residual (checked; a level that does not converge is an error
  naming it), and derivatives by the implicit function theorem.
- "transient": the explicit dynamics with the load ramped over `ramp_s` and settled at max_load (the
  ramp's viscoelastic lag is checked against the settled state).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..errors import ConfigError
from ..schema import Field, check_range_pair
from .base import Experiment
from .phases import loaded_plan
from .program import check_phase, contact_check, f64, phase, phase_checks, require_equilibrium, run_info
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary, static_vertical_path


class VerticalStiffness(Experiment):
    name = "vertical_stiffness"
    study_id = "E02"
    description = "E02 total static vertical stiffness k_sv"
    schema = {"method": Field(str, default="static", choices=("static", "transient")),
              "n_levels": Field(int, 1, 4, 60, STATIC_LOADS - 1, "load levels of the static load path (static method)"),
              "max_load_kN": Field(float, U.KN, 1, 500, 60.0, "kN"),
              "stated_load_kN": Field(float, U.KN, 0, 500, 0.0, "kN (0: the condition's load)"),
              "ramp_s": Field(float, 1, 0.02, 5, 0.9, "s"),  # a shorter ramp reads stiff: the viscoelastic lag (docs/design-notes.md)
              "fit_range_kN": Field(list, U.KN, 0, 500, [10.0, 60.0], "kN")}
    traced_names = ("k_sv_N_per_m", "deflection_m")
    quantity_names = ("k_sv_N_per_m", "k_sv_tangent_N_per_m", "k_sv_fit_N_per_m", "deflection_m", "stated_load_N", "max_load_N", "fit_r2",
                      "settled_deflection_at_max_load_m")

    max_load: jax.Array
    stated_load: jax.Array  # N; 0: the condition's load
    ramp: jax.Array
    fit_range: tuple = eqx.field(static=True)
    method: str = eqx.field(static=True, default="static")
    n_levels: int = eqx.field(static=True, default=STATIC_LOADS - 1)
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        mx, st = table["max_load_kN"], table["stated_load_kN"]
        if st > mx:
            raise ConfigError(f"vertical_stiffness.stated_load_kN = {st / 1e3:g}: must be at most max_load_kN = {mx / 1e3:g}")
        lo, hi = check_range_pair("vertical_stiffness.fit_range_kN", table["fit_range_kN"], "kN", U.KN)
        if hi > mx:
            raise ConfigError(f"vertical_stiffness.fit_range_kN = [{lo / 1e3:g}, {hi / 1e3:g}]: must end at or below "
                              f"max_load_kN = {mx / 1e3:g}")
        return cls(proto=proto, max_load=f64(mx), stated_load=f64(st), ramp=f64(table["ramp_s"]), fit_range=(lo, hi),
                   method=table["method"], n_levels=int(table["n_levels"]))

    def check_condition(self, condition):
        """The stated load (or the condition's) must lie on the ramp."""
        stated = self._stated(condition)
        if not 0 < stated <= float(self.max_load):
            raise ConfigError(f"vertical_stiffness: the stated load {stated / 1e3:g} kN must be in (0, max_load_kN = "
                              f"{float(self.max_load) / 1e3:g}] (set stated_load_kN or lower the condition's load)")

    def _stated(self, condition):
        st = float(self.stated_load)
        return condition["load_N"] if st <= 0 else st

    def simulate(self, model, params, case):
        if self.method == "static":
            return self._simulate_static(model, params, case)
        outs, y, mem = loaded_plan(model, params, case, self.proto, self.max_load, self.n_save, ramp=self.ramp)
        return {"phases": outs, "z_road": mem["z_road"]}

    def _ramp_samples(self, ld):
        t = np.linspace(float(ld.t0), float(ld.t0) + float(self.ramp) + float(self.proto.settle_max), self.n_save)
        return t

    # ---- static method -------------------------------------------------------------------------
    def _levels(self, stated):
        """Load levels (N, ascending): n_levels evenly up to max_load, and the stated load."""
        grid = self.max_load * jnp.arange(1, self.n_levels + 1) / self.n_levels
        return jnp.sort(jnp.concatenate([grid, jnp.atleast_1d(stated)]))

    def _tangent(self, defl, load, stated):
        """dF/d(deflection) at the stated load (N/m), over +- two static level spacings: the
        stiffness small motions about the loaded state see (the rigid ring's dynamic springs). None
        when fewer than three points lie there (the ring then falls back to the secant, and says so)."""
        try:
            return signals.tangent(defl, load, stated, 2.0 * float(self.max_load) / int(self.n_levels))
        except ConfigError:
            return None

    def _simulate_static(self, model, params, case):
        stated = jnp.where(self.stated_load > 0, self.stated_load, case.load)
        loads = self._levels(stated)
        return static_vertical_path(model, params, case.pressure, loads) | {"stated": stated}

    def _traced_static(self, out):
        loads, defl = out["loads"], -out["q"][2:, 2]
        k = jnp.argmin(jnp.abs(loads - out["stated"]))
        return {"k_sv_N_per_m": out["stated"] / defl[k], "deflection_m": defl[k]}

    def _reduce_static(self, tire, condition, out):
        loads = np.asarray(out["loads"])
        stated = self._stated(condition)
        check_static_path("vertical_stiffness", out)
        defl = -np.asarray(out["q"])[2:, 2]
        fz = np.asarray(out["contact"])[2:, 2]
        k = int(np.argmin(np.abs(loads - stated)))
        lo, hi = self.fit_range
        sel = (loads >= lo - 1e-6) & (loads <= hi + 1e-6)
        if sel.sum() < 3:
            raise ConfigError(f"vertical_stiffness.fit_range_kN = [{lo / 1e3:g}, {hi / 1e3:g}]: holds {int(sel.sum())} of "
                              f"the static load levels (needs 3; raise n_levels)")
        fit = signals.linear_slope(defl[sel], loads[sel])
        require_equilibrium("vertical_stiffness: at the maximum load", float(fz[-1]), float(loads[-1]))
        checks, info = static_summary(out["infos"])
        checks["contact_vs_load_max_rel_error"] = float(np.max(np.abs(fz - loads) / loads))
        q = {"k_sv_N_per_m": stated / defl[k], "k_sv_tangent_N_per_m": self._tangent(defl, loads, stated),
             "k_sv_fit_N_per_m": fit.slope, "deflection_m": float(defl[k]),
             "stated_load_N": stated, "max_load_N": float(loads[-1]), "fit_r2": fit.r2,
             "settled_deflection_at_max_load_m": float(defl[-1])}
        sig = {"load_N": loads, "contact_force_N": fz, "deflection_m": defl}
        info["levels"] = int(len(loads) + 2)
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)

    def traced(self, model, params, condition_cases, outputs):
        if self.method == "static":
            return self._traced_static(outputs[0])
        ld = jax.tree_util.tree_map(lambda a: a[1], outputs[0]["phases"])
        stated = jnp.where(self.stated_load > 0, self.stated_load, condition_cases[0]["load_N"])
        t = jnp.linspace(ld.t0, ld.t0 + self.ramp + self.proto.settle_max, self.n_save)
        load = -ld.saved["rim_force"][:, 2]
        defl = -ld.saved["q"][:, 2]
        in_ramp = jnp.isfinite(load) & (t <= ld.t0 + self.ramp)
        reach = in_ramp & (load >= stated)
        i = jnp.clip(jnp.argmax(reach), 1, self.n_save - 1)
        w = (stated - load[i - 1]) / (load[i] - load[i - 1])
        d = defl[i - 1] + w * (defl[i] - defl[i - 1])
        return {"k_sv_N_per_m": stated / d, "deflection_m": d}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model = tire.model
        self.check_condition(condition)
        if self.method == "static":
            return self._reduce_static(tire, condition, out)
        stated = self._stated(condition)
        inf, ld = phase(out["phases"], 0), phase(out["phases"], 1)
        check_phase("inflate", inf, model)
        check_phase("load", ld, model)
        checks = phase_checks("inflate", inf, model) | phase_checks("load", ld, model)
        s = ld.saved
        t = self._ramp_samples(ld)
        valid = np.isfinite(np.asarray(s["ke"]))
        ramp = float(self.ramp)
        in_ramp = valid & (t <= float(ld.t0) + ramp)
        defl = -np.asarray(s["q"])[:, 2]
        load = -np.asarray(s["rim_force"])[:, 2]
        fz = np.asarray(s["contact_force"])[:, 2]
        d_r, l_r, f_r = defl[in_ramp], load[in_ramp], fz[in_ramp]
        sec = signals.secant(d_r, l_r, stated, along="y")
        lo, hi = self.fit_range
        mask = (l_r >= lo) & (l_r <= hi)
        fit = signals.linear_slope(d_r[mask], l_r[mask])
        d_static = -float(ld.q_end[2])
        l_static = float(self.max_load)
        fz_end, _, _ = contact_check(s, l_static)
        require_equilibrium("vertical_stiffness: settled at the maximum load", fz_end, l_static)
        d_ramp_at_max = float(np.interp(l_static, l_r, d_r))
        upper = l_r > 0.25 * l_static  # the first quarter of a smoothstep ramp is where the rim accelerates
        checks |= {"quasi_static_deflection_rel_error": abs(d_ramp_at_max - d_static) / d_static,
                   "contact_vs_load_max_rel_error_in_ramp": float(np.max(np.abs(f_r - l_r)[upper] / l_r[upper])),
                   "contact_vs_load_rel_error_settled": abs(fz_end - l_static) / l_static}
        q = {"k_sv_N_per_m": sec.secant, "k_sv_tangent_N_per_m": self._tangent(d_r, l_r, stated),
             "k_sv_fit_N_per_m": fit.slope, "deflection_m": sec.x_at,
             "stated_load_N": stated, "max_load_N": l_static, "fit_r2": fit.r2,
             "settled_deflection_at_max_load_m": d_static}
        sig = {"time_s": t[in_ramp], "load_N": l_r, "contact_force_N": f_r, "deflection_m": d_r}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=run_info(out["phases"]))
