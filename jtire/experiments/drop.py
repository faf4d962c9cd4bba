"""E04 total vertical damping C_tot: the drop test.

    1. inflate with the rim held;
    2. the road is placed `drop_height` (20 mm) below the lowest tread point; the vertical load acts
       on the rim as a force (the condition's load, as in E02), the rim is released with only its
       vertical DOF free and the settle damping OFF: the wheel falls, hits the road, bounces and rings
       down on its own damping (the rubber's Maxwell branches and the tread);
    3. the wheel at rest under the same load: k_sv = load / deflection from first contact (the E02
       secant at the condition's load);
    4. the rim's vertical motion from the first contact on is reduced with `decay` (two peaks and a
       damped-sine fit) about the rest position, M = m_tot (tire + rim, from the tire config), and
       C_tot = 2 xi sqrt(m_tot k_sv). From 20 mm under the rated load the wheel leaves the road on the
       first rebounds (a non-linear decay), so the same reduction is also given for the record after
       the last lift-off (`*_in_contact_*`, None when too little of the record is left).

Method "static" (the default): steps 1 and 3 are static equilibria (`static_path`, E02's load path to
the condition's load, long-term moduli), the drop (2) the explicit transient from the inflated static
state. Method "transient": 1 by dynamic relaxation, and 3 the drop continued with the settle damping
on until the wheel rests (it then rests on the tread shear the bounces left).

Load vs gravity: the study applies "the vertical load to the rim", the axle load of the condition, as
in E02 where k_sv is measured with a rim force alone; gravity on the wheel's own 111 kg adds ~1.1 kN
(2.4 % of the rated load). `gravity = false` (default) matches E02; `gravity = true` adds g to the rim
and every node (the static contact force then includes the wheel's weight); the static levels carry
no gravity, so it needs method = "transient".
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..errors import ConfigError
from ..schema import Field
from ..state import TireState
from .base import Experiment
from .decay import decay_checks, decay_names, decay_quantities, release_branch, sample_times, wheel_mass
from .loads import DOWN, RIM_Z
from .phases import FAR, first_contact_height, flat_road, inflate_branch, make_drive
from .program import (Phase, check_phase, contact_check, f64, phase, require_equilibrium, run_info, run_plan,
                      run_plan_vmapped)
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary, static_vertical_path


class DropTest(Experiment):
    name = "drop_test"
    study_id = "E04"
    description = "E04 total vertical damping C_tot (drop test)"
    schema = {"drop_height_mm": Field(float, U.MM, 0, 200, 20.0, "mm between the lowest tread point and the road"),
              "duration_s": Field(float, 1, 0.05, 3, 0.4, "s of drop and free decay"),
              "sample_rate_Hz": Field(float, 1, 500, 20000, 2500,
                                      "Hz of the saved record (the belt mode, 40-300 Hz, needs >= 600)"),
              "gravity": Field(bool, default=False),
              "method": Field(str, default="static", choices=("static", "transient"))}
    quantity_names = (("C_tot_Ns_per_m", "C_tot_2p_Ns_per_m", "C_tot_fit_Ns_per_m", "k_sv_N_per_m", "k_sv_source",
                       "static_deflection_m", "static_load_N", "m_tot_kg")
                      + decay_names("decay_mass_kg", "C_tot_from_omega", "Ns_per_m")[1:]  # C: the rows above
                      + ("k_from_frequency_N_per_m", "t_in_contact_from_s", "xi_in_contact_2p", "xi_in_contact_fit",
                         "C_tot_in_contact_2p_Ns_per_m", "C_tot_in_contact_fit_Ns_per_m",
                         "omega_n_in_contact_fit_rad_per_s"))

    drop_height: jax.Array
    duration: jax.Array
    gravity: bool = eqx.field(static=True)
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)
    method: str = eqx.field(static=True, default="static")  # inflation and rest: "static" or "transient"

    @property
    def time_stepped(self) -> bool:
        return True  # the drop is a transient whichever way the inflated state was reached

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        if table["gravity"] and table["method"] == "static":
            raise ConfigError("drop_test.gravity = true: the static levels carry no gravity; set "
                              "drop_test.method = \"transient\" (allowed with gravity: transient)")
        n_save = int(round(table["duration_s"] * table["sample_rate_Hz"])) + 1
        return cls(proto=proto, drop_height=f64(table["drop_height_mm"]), duration=f64(table["duration_s"]),
                   gravity=table["gravity"], method=table["method"], n_save=n_save)

    def _g(self):
        return np.array([0.0, 0.0, -U.G0]) if self.gravity else np.zeros(3)

    def simulate(self, model, params, case):
        if self.method == "static":
            return self._simulate_static(model, params, case)
        proto, g = self.proto, self._g()

        def fall(y, t, mem):
            mem = dict(mem, z_road=first_contact_height(model, y) - self.drop_height)
            return release_branch(case, surface=flat_road(mem["z_road"]), load0=case.load * DOWN, load1=case.load * DOWN,
                                  rim_free=RIM_Z, ramp=0.0, duration=self.duration, gravity=g)(y, t, mem)

        def rest(y, t, mem):
            d = make_drive(case.pressure, case.dt, force0=case.load * DOWN, force1=case.load * DOWN, t0=t, t1=t,
                           rim_free=RIM_Z, surface=flat_road(mem["z_road"]), damping=proto.settle_damping, gravity=g)
            return Phase(d, y, proto.settle_max, 0.0), mem

        branches = [inflate_branch(case, proto, flat_road(-FAR), gravity=np.zeros(3)), fall, rest]
        y0 = TireState.at_rest(model, len(params.relaxation_times))
        outs, y, mem = run_plan(model, params, branches, y0, {"z_road": 0.0}, proto.ke_tol, self.n_save)
        return {"phases": outs}

    def _simulate_static(self, model, params, case):
        """E02's static load path (inflation, first contact, STATIC_LOADS levels to the load: the rest
        state), then the drop from the inflated state with the road `drop_height` below the first
        contact the static path found."""
        loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
        st = static_vertical_path(model, params, case.pressure, loads)
        z_road = st["road_height"][-1] - self.drop_height

        def fall(c):
            return [release_branch(c, surface=flat_road(z_road), load0=c.load * DOWN, load1=c.load * DOWN,
                                   rim_free=RIM_Z, ramp=0.0, duration=self.duration, gravity=self._g())]

        outs, _, _ = run_plan_vmapped(model, params, fall, case, st["y_inflated"], {}, self.proto.ke_tol, self.n_save)
        return {"static": st, "phases": outs}

    def _rest_static(self, out, load):
        """(rest height in the drop's frame, contact force at rest, checks, info) of the static method."""
        st = out["static"]
        check_static_path("drop_test (rest under the load)", st)
        checks, info = static_summary(st["infos"])
        info["levels"] = int(len(np.asarray(st["loads"])) + 2)
        z_rest = float(np.asarray(st["q"])[-1, 2]) - float(self.drop_height)
        return z_rest, float(np.asarray(st["contact"])[-1, 2]), checks, info

    def _rest_transient(self, out, model, load):
        inf, rest = phase(out["phases"], 0), phase(out["phases"], 2)
        check_phase("inflate", inf, model)
        check_phase("settle after the drop", rest, model)
        fz_rest, _, _ = contact_check(rest.saved, load)
        checks = {"inflate_settled": bool(inf.settled), "settle_settled": bool(rest.settled)}
        return float(rest.q_end[2]), fz_rest, checks, {"method": "transient"}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model, load = tire.model, condition["load_N"]
        static = self.method == "static"
        fall = phase(out["phases"], 0 if static else 1)
        check_phase("drop", fall, model, require_settled=False)
        drop_height, duration = float(self.drop_height), float(self.duration)
        ts = sample_times(fall, duration, self.n_save)
        s = jax.tree_util.tree_map(np.asarray, fall.saved)
        z = s["q"][:, 2]
        touching = s["n_contact"] > 0
        if not touching.any():
            raise ConfigError(f"drop_test.duration_s = {duration:g}: the wheel never reached the road (raise it)")
        i_c = int(np.argmax(touching))
        t_contact = float(ts[i_c])
        own = float(model.rim_mass + np.sum(np.asarray(model.node_mass)))
        M = wheel_mass(tire.spec)
        fz_applied = load + (own * U.G0 if self.gravity else 0.0)
        z_static, fz_rest, checks0, info0 = (self._rest_static(out, fz_applied) if static
                                             else self._rest_transient(out, model, fz_applied))
        deflection = -z_static - drop_height  # rim travel beyond first contact (E02's deflection)
        require_equilibrium("drop_test: at rest after the drop", fz_rest, fz_applied)
        k_sv = fz_applied / deflection

        def reduce_from(t_start):
            return signals.free_decay(ts, z, M, t_start=t_start, x_final=z_static)

        fd = reduce_from(t_contact)
        c_fit = 2 * fd.xi_fit * np.sqrt(M * k_sv)
        c_2p = 2 * fd.xi_2p * np.sqrt(M * k_sv) if fd.two_peak_ok else None
        q = {"C_tot_Ns_per_m": c_2p if fd.two_peak_ok else c_fit, "C_tot_2p_Ns_per_m": c_2p, "C_tot_fit_Ns_per_m": c_fit,
             "k_sv_N_per_m": k_sv,
             "k_sv_source": "static load path to the load (E02's secant)" if static else "rest at the end of the drop",
             "static_deflection_m": deflection,
             "static_load_N": fz_applied, "m_tot_kg": M}
        dq = decay_quantities(fd, "decay_mass_kg", "C_tot_from_omega", "Ns_per_m")
        dq.pop("C_tot_from_omega_Ns_per_m")
        q |= dq
        # the rigid-ring relation k_sv = m_tot omega_n^2 holds only if the wheel moves as one mass
        q["k_from_frequency_N_per_m"] = M * fd.omega_n_fit**2
        airborne = touching[i_c:] == 0
        # the same reduction after the last lift-off, where the wheel stays on the road (nearly linear)
        i_in = i_c + (int(np.nonzero(airborne)[0][-1]) + 1 if airborne.any() else 0)
        fd_in = reduce_from(float(ts[i_in])) if ts.size - i_in >= 16 else None
        q |= {"t_in_contact_from_s": float(ts[i_in] - ts[0]) if fd_in is not None else None,
              "xi_in_contact_2p": fd_in.xi_2p if fd_in is not None else None,
              "xi_in_contact_fit": fd_in.xi_fit if fd_in is not None else None,
              "C_tot_in_contact_2p_Ns_per_m": (2 * fd_in.xi_2p * np.sqrt(M * k_sv)
                                               if fd_in is not None and fd_in.two_peak_ok else None),
              "C_tot_in_contact_fit_Ns_per_m": 2 * fd_in.xi_fit * np.sqrt(M * k_sv) if fd_in is not None else None,
              "omega_n_in_contact_fit_rad_per_s": fd_in.omega_n_fit if fd_in is not None else None}
        checks = checks0 | {"drop_height_m": drop_height,
                  "first_contact_t_s": t_contact - float(ts[0]),
                  "airborne_after_first_contact_fraction": float(airborne.mean()),
                  "max_deflection_m": float(-z[i_c:].min() - drop_height),
                  "gravity": bool(self.gravity), "model_wheel_mass_kg": own,
                  "static_contact_force_N": fz_rest,
                  "static_contact_vs_load_rel_error": abs(fz_rest - fz_applied) / fz_applied}
        checks |= decay_checks(fd, fall, prefix="drop")
        if fd_in is not None:
            checks |= {"in_contact_two_peak_ok": fd_in.two_peak_ok, "in_contact_fit_rms_relative": fd_in.fit_rms_relative,
                       "in_contact_fit_oscillatory": fd_in.fit_oscillatory}
        sig = {"time_s": ts - ts[0], "rim_z_m": z, "contact_force_z_N": s["contact_force"][:, 2],
               "n_contact": s["n_contact"], "rubber_dissipated_J": s["dissipated"] - s["dissipated"][0]}
        info = info0 | run_info(out["phases"]) | {"study_id": self.study_id, "duration_s": duration,
                                          "load_applied_as": "rim force (condition load)" + (" + gravity" if self.gravity else "")}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
