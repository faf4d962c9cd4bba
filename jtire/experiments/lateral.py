"""E09 lateral tire stiffness k_l and damping C_l: a lateral force at the rim of the loaded tire.

Method "static" (the default; "auto" is the same): the static load path of E01 (`static_path`:
inflation, first contact, 13 vertical levels to the load) and then the lateral force in two static
levels (F/2, F) with rim y and z free, friction carried from level to level: k_l = F / y, long-term
moduli (one compiled program with E01 and E02 when decay_s = 0). When decay_s > 0 the lateral force
is then ramped off in `release_ramp` and the rim's lateral free decay, an explicit transient from
the held static state (every Maxwell branch relaxed, the tread's shear as the static levels left
it), gives C_l with M = m_wheel (tire + rim mass from the tire config): two peaks and a damped-sine
fit about the fitted final level (friction may keep the rim off its pre-load position, reported).

Method "transient": every phase explicit. Inflate -> load onto the road (rim z free) -> the lateral
force ramped on at the rim centre with rim y and z free (friction holds the patch), settled by
dynamic relaxation: k_l = F / y_ss; then the same release.
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import equilibrium as EQ
from .. import solve
from .. import units as U
from ..schema import Field
from .base import Experiment
from .decay import (decay_about_fit, decay_checks, decay_names, decay_quantities, release_branch, sample_times,
                    wheel_mass)
from .loads import DOWN, LEFT, RIM_YZ
from .phases import flat_road, load_branch, loaded_plan
from .program import (check_phase, contact_check, f64, phase, phase_checks, require_equilibrium, run_info,
                      run_plan_vmapped)
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
    # decay_s > 0; xi_l_fit: the release's fitted zeta under an E09-only name (the rigid ring's tread damper)
    quantity_names = static_names + decay_names("decay_mass_kg", "C_l", "Ns_per_m") + ("xi_l_fit",)

    force: jax.Array
    decay: jax.Array
    release_ramp: jax.Array
    with_decay: bool = eqx.field(static=True)
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)
    method: str = eqx.field(static=True, default="static")

    @property
    def time_stepped(self) -> bool:
        return self.method == "transient" or self.with_decay  # the release decay is a transient

    @classmethod
    def produces(cls, table):
        return cls.quantity_names if table["decay_s"] > 0 else cls.static_names

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        decay, method = table["decay_s"], table["method"]
        method = "static" if method == "auto" else method
        return cls(proto=proto, force=f64(table["force_kN"]), decay=f64(decay),
                   release_ramp=f64(table["release_ramp_ms"]), with_decay=decay > 0, method=method)

    def simulate(self, model, params, case):
        if self.method == "static":
            loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
            st = static_vertical_path(model, params, case.pressure, loads, self.force * jnp.array([0.5, 1.0]))
            if not self.with_decay:
                return {"static": st}
            # the release from the held static state, on the road the static levels stood on
            def release(c):
                return [release_branch(c, surface=flat_road(st["road_height"][-1]),
                                       load0=c.load * DOWN + self.force * LEFT, load1=c.load * DOWN,
                                       rim_free=RIM_YZ, ramp=self.release_ramp, duration=self.decay)]

            outs, _, _ = run_plan_vmapped(model, params, release, case, st["y_lateral"], {}, self.proto.ke_tol,
                                          self.n_save)
            return {"static": st, "phases": outs}
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
        return q, sig, checks, info

    def _with_decay(self, tire, condition, q, checks, info, rel, y_preload):
        """The release decay's quantities, checks and signals added to the held state's result.
        y_preload: the rim's lateral position under the vertical load alone (m)."""
        check_phase("release", rel, tire.model, require_settled=False)
        decay, ramp = float(self.decay), float(self.release_ramp)
        ts = sample_times(rel, decay, self.n_save)
        y = np.asarray(rel.saved["q"])[:, 1] - y_preload
        M = wheel_mass(tire.spec)
        fd = decay_about_fit(ts, y, M, float(ts[0]) + ramp)
        q |= decay_quantities(fd, "decay_mass_kg", "C_l", "Ns_per_m") | {"xi_l_fit": fd.xi_fit}
        checks |= decay_checks(fd, rel) | {
            # friction may keep the rim off its pre-load position; this is how far (m)
            "release_final_level_minus_preload_m": float(fd.x_final),
            "release_contact_lateral_force_end_N": float(np.asarray(rel.saved["contact_force"])[-1, 1])}
        sig = {"time_s": ts - ts[0], "rim_y_m": y, "rim_z_m": np.asarray(rel.saved["q"])[:, 2],
               "contact_force_y_N": np.asarray(rel.saved["contact_force"])[:, 1]}
        info |= {"decay_s": decay, "release_ramp_s": ramp, "decay_samples": int(ts.size)}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        if self.method == "static":
            q, sig, checks, info = self._reduce_static(tire, condition, out["static"])
            if not self.with_decay:
                return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
            info |= run_info(out["phases"])
            return self._with_decay(tire, condition, q, checks, info, phase(out["phases"], 0),
                                    float(np.asarray(out["static"]["q"])[-1, 1]))
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
        info = run_info(out["phases"]) | {"method": "transient"}
        if not self.with_decay:
            return ExperimentResult(self.name, condition, q, checks=checks, info=info)
        return self._with_decay(tire, condition, q, checks, info, phase(out["phases"], 3), float(ld.q_end[1]))
