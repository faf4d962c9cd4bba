"""E09 lateral tire stiffness k_l and damping C_l: a lateral force at the rim of the loaded tire.

Method "static" (the default when decay_s = 0, the static part only): the static load path of E01
(`static_path`: inflation, first contact, 13 vertical levels to the load) and then the lateral
force in two static levels (F/2, F) with rim y and z free, friction carried from level to level:
k_l = F / y, long-term moduli. One compiled program with E01 and E02.

Method "transient" (the default when decay_s > 0: the release decay needs a time history). Phases:
inflate -> load onto the road (rim z free) -> the lateral force `force` ramped on at the rim
centre with rim y and z free (friction holds the patch), settled: k_l = F / y_ss. Then, when
decay_s > 0, the lateral force is ramped off in `release_ramp` with the settle damping off and the
rim's lateral free decay gives C_l with M = m_wheel (tire + rim mass from the tire config): two
peaks and a damped-sine fit about the fitted final level (friction may keep the rim off its
pre-load position, reported).
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import equilibrium as EQ
from .. import solve
from .. import units as U
from ..errors import ConfigError
from ..schema import Field
from .base import Experiment
from .decay import (decay_about_fit, decay_checks, decay_names, decay_quantities, release_branch, sample_times,
                    wheel_mass)
from .loads import DOWN, LEFT, RIM_YZ
from .phases import flat_road, load_branch, loaded_plan
from .program import check_phase, contact_check, f64, phase, phase_checks, require_equilibrium, run_info
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary, static_vertical_path


def _static_y(st):
    """The rim's lateral travel (m, +y) from the last vertical level to the last lateral level of a
    static path (traceable; numpy on the host)."""
    return st["lateral_q"][-1, 1] - st["q"][-1, 1]


def lateral_branches(model, case, proto, force):
    """The lateral load phase after `footprint.loaded_plan`'s load phase (road at mem["z_road"])."""
    return [load_branch(model, case, proto, lambda mem: flat_road(mem["z_road"]), case.load * DOWN + force * LEFT,
                        RIM_YZ, force0=case.load * DOWN)]


class LateralStiffness(Experiment):
    name = "lateral_stiffness"
    study_id = "E09"
    description = "E09 lateral stiffness k_l and damping C_l (release decay)"
    schema = {"force_kN": Field(float, U.KN, 0.01, 100, 5.0, "kN"),
              "decay_s": Field(float, 1, 0, 3, 0.3, "s of free decay after the release (0: static part only)"),
              "release_ramp_ms": Field(float, U.MS, 0, 20, 1.0, "ms (0: a step)"),
              "method": Field(str, default="auto", choices=("auto", "static", "transient"))}
    traced_names = ("k_l_N_per_m", "lateral_deflection_m")
    static_names: ClassVar[tuple] = ("k_l_N_per_m", "lateral_deflection_m", "lateral_force_N")
    quantity_names = static_names + decay_names("decay_mass_kg", "C_l", "Ns_per_m")  # decay_s > 0

    force: jax.Array
    decay: jax.Array
    release_ramp: jax.Array
    with_decay: bool = eqx.field(static=True)
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)
    method: str = eqx.field(static=True, default="transient")

    @classmethod
    def produces(cls, table):
        return cls.quantity_names if table["decay_s"] > 0 else cls.static_names

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        decay, method = table["decay_s"], table["method"]
        if method == "static" and decay > 0:
            raise ConfigError(f"lateral_stiffness.method = \"static\" with decay_s = {decay:g}: a static solve has no "
                              f"release decay (set decay_s = 0, or method = \"transient\" or \"auto\")")
        if method == "auto":
            method = "transient" if decay > 0 else "static"
        return cls(proto=proto, force=f64(table["force_kN"]), decay=f64(decay),
                   release_ramp=f64(table["release_ramp_ms"]), with_decay=decay > 0, method=method)

    def simulate(self, model, params, case):
        if self.method == "static":
            loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
            return {"static": static_vertical_path(model, params, case.pressure, loads,
                                                   self.force * jnp.array([0.5, 1.0]))}
        extra = lateral_branches(model, case, self.proto, self.force)
        if self.with_decay:
            extra.append(lambda y, t, mem: release_branch(
                case, surface=flat_road(mem["z_road"]), load0=case.load * DOWN + self.force * LEFT,
                load1=case.load * DOWN, rim_free=RIM_YZ, ramp=self.release_ramp, duration=self.decay)(y, t, mem))
        outs, y, mem = loaded_plan(model, params, case, self.proto, case.load, self.n_save, extra=extra)
        return {"phases": outs, "z_road": mem["z_road"]}

    def traced(self, model, params, condition_cases, outputs):
        if self.method == "static":
            y_ss = abs(_static_y(outputs[0]["static"]))
        else:
            ph = outputs[0]["phases"]
            y_ss = abs(ph.q_end[2, 1] - ph.q_end[1, 1])
        return {"k_l_N_per_m": self.force / y_ss, "lateral_deflection_m": y_ss}

    def _reduce_static(self, tire, condition, st):
        load, force = condition["load_N"], float(self.force)
        check_static_path("lateral_stiffness", st)
        lat = np.asarray(st["lateral"])
        EQ.check_static(st["lateral_infos"], lambda k: f"lateral_stiffness: lateral level {lat[k] / 1e3:.4g} kN")
        fz = float(np.asarray(st["contact"])[-1, 2])
        require_equilibrium("lateral_stiffness: vertical load", fz, load)
        f_lat = np.asarray(st["lateral_contact"])[-1]
        require_equilibrium("lateral_stiffness: lateral level (lateral force)", abs(float(f_lat[1])), force)
        y_ss = float(_static_y(st))
        checks, info = static_summary(st["infos"], st["lateral_infos"])
        checks |= {"contact_force_N": fz, "contact_vs_load_rel_error": abs(fz - load) / load,
                   "contact_lateral_force_N": float(f_lat[1]),
                   "contact_vs_lateral_rel_error": abs(abs(float(f_lat[1])) - force) / force,
                   "vertical_deflection_m": -float(np.asarray(st["q"])[-1, 2])}
        q = {"k_l_N_per_m": force / abs(y_ss), "lateral_deflection_m": abs(y_ss), "lateral_force_N": force}
        sig = {"lateral_force_N": lat, "rim_y_m": np.asarray(st["lateral_q"])[:, 1] - np.asarray(st["q"])[-1, 1]}
        info["levels"] = int(len(np.asarray(st["loads"])) + 2 + len(lat))
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        if self.method == "static":
            return self._reduce_static(tire, condition, out["static"])
        model, load, force = tire.model, condition["load_N"], float(self.force)
        inf, ld, lat = (phase(out["phases"], i) for i in range(3))
        for name, ph in (("inflate", inf), ("load", ld), ("lateral", lat)):
            check_phase(name, ph, model)
        checks = phase_checks("inflate", inf, model) | phase_checks("load", ld, model) | phase_checks("lateral", lat, model)
        fz, _, _ = contact_check(ld.saved, load)
        require_equilibrium("lateral_stiffness: load phase", fz, load)
        _, _, fy = contact_check(lat.saved, load)
        require_equilibrium("lateral_stiffness: lateral phase (lateral force)", abs(fy), force)
        y_ss = float(lat.q_end[1] - ld.q_end[1])
        checks |= {"contact_lateral_force_N": fy, "contact_vs_lateral_rel_error": abs(abs(fy) - force) / force,
                   "vertical_deflection_m": -float(ld.q_end[2])}
        q = {"k_l_N_per_m": force / abs(y_ss), "lateral_deflection_m": abs(y_ss), "lateral_force_N": force}
        info = run_info(out["phases"])
        if not self.with_decay:
            return ExperimentResult(self.name, condition, q, checks=checks, info=info)
        rel = phase(out["phases"], 3)
        check_phase("release", rel, model, require_settled=False)
        decay, ramp = float(self.decay), float(self.release_ramp)
        ts = sample_times(rel, decay, self.n_save)
        y = np.asarray(rel.saved["q"])[:, 1] - float(ld.q_end[1])
        M = wheel_mass(tire.spec)
        fd = decay_about_fit(ts, y, M, float(ts[0]) + ramp)
        q |= decay_quantities(fd, "decay_mass_kg", "C_l", "Ns_per_m")
        checks |= decay_checks(fd, rel) | {
            # friction may keep the rim off its pre-load position; this is how far (m)
            "release_final_level_minus_preload_m": float(fd.x_final),
            "release_contact_lateral_force_end_N": float(np.asarray(rel.saved["contact_force"])[-1, 1])}
        sig = {"time_s": ts - ts[0], "rim_y_m": y, "rim_z_m": np.asarray(rel.saved["q"])[:, 2],
               "contact_force_y_N": np.asarray(rel.saved["contact_force"])[:, 1]}
        info |= {"decay_s": decay, "release_ramp_s": ramp, "decay_samples": int(ts.size)}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
