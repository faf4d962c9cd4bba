"""E03 total dynamic vertical stiffness k_dv: a rolling tire hits a cleat on a drum.

Phases (every one on the same surface type, drum + cleat):
1. inflate with the rim held (the drum far below);
2. load onto the still drum: rim z free, the condition's load ramped on, settled (checked); the cleat
   waits at the drum's bottom, out of reach;
3. rim z locked where it settled (x, y and the tilts locked too; the spin about the axle free), drum at
   the set surface speed, tire started at the matching spin (R0 - deflection / 3 as a first rolling
   radius); rolled with settle damping relative to the rim frame, which removes the start-up
   transient without dragging the rolling tire;
4. damping off, the cleat starting `lead_time` ahead of where it first touches the tire (from the
   loaded patch on the drum, `patch.extent_traced`); the free response after the cleat has left the
   contact patch is recorded at `sample_rate`.

Method "static" (the default): phases 1 and 2 are static equilibria on the still drum (`static_path`:
inflation, first contact, 13 load levels to the condition's load, long-term moduli, friction carried
from level to level), and the run starts at phase 3 from that state. Method "transient": phases 1 and
2 by dynamic relaxation (settle damping on, settled when the kinetic energy is below the protocol's
tolerance).

Quasi-static crossing (method "static" only, `enveloping_range_mm` > 0): after the load, the same
static program steps the cleat through the patch, contact position s from -range to +range every
`enveloping_step_mm` (s < 0: the cleat ahead), the rim under the constant load (z free, x and the
spin held), the contact frictionless. The rim's lift is the effective road height w(s) the tire
feels and -F_x / F_z the effective slope (F_x, F_z the contact resultant, the cleat-free level
subtracted); `jtire.enveloping.fit` fits the tandem elliptical cam of the rigid ring to them. Both
ends of the crossing must find the tire off the cleat (else the range is too short: an error). The
rolling start is the loaded state before the crossing.

Axle force: the tire's force on the rim (`tire_on_rim`, what a hub dynamometer reads), exact with
every node's inertia in it. The spectra of the drum's force on the tire and of the belt's vertical
displacement are reported beside it: a mode has one frequency whatever the output, but each output
weights the modes differently. The spectrum is `spectra.first_mode`: Hann window, zero padding,
interpolated peak, and a modal fit. k_dv = (2 pi f)^2 m_b (m_b from the tire config) with f the
interpolated spectral peak (the study's FFT peak, a damped frequency) and, beside it, with the fitted
undamped frequency f_n.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import enveloping
from .. import equilibrium as EQ
from .. import spectra
from .. import units as U
from ..errors import ConfigError, SimulationError
from ..physics.drum import Cleat, Drum, DrumWithCleat
from ..schema import Field, check_range_pair
from ..state import TireState
from .base import Experiment
from .loads import DOWN, RIM_SPIN, RIM_Z
from .patch import surface_gap, x_range_traced
from .phases import first_contact_height, make_drive, with_spin
from .program import (Phase, check_phase, contact_check, f64, phase, phase_checks, require_equilibrium, run_info, run_plan,
                      run_plan_vmapped)
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary

ENVELOPING_NAMES = ("ellips_shift_m", "ellips_length_m", "ellips_height_m", "ellips_order", "enveloping_fit_rms_height_m",
                    "enveloping_max_height_m")  # the tandem cam fitted to the quasi-static crossing
CROSSING_EDGE_M = 1e-6  # m: the crossing's ends must see the tire off the cleat (w below this)
CROSS_ALLOWANCE = 0.06  # s: room in the impact phase for the cleat to cross the patch (2a + cleat < 0.8 m at 50 km/h)


def drum_at(radius, top_z, surface_speed=0.0):
    """Drum of `radius` (m) whose top is at height top_z (m) above x = 0, its surface moving at
    `surface_speed` (m/s; > 0: the top moves towards -x, so a tire on it rolls forward). Traced."""
    r = f64(radius)
    return Drum(radius=r, centre_x=f64(0.0), centre_z=f64(top_z) - r, omega=-f64(surface_speed) / r)


def _drum_path(model, params, pressure, loads, drum_radius, cleat_radius, cleat_height, crossing):
    """Inflation, first contact and the vertical loads `loads` (N) as static levels on the still drum,
    its cleat at the bottom (out of reach); then, when crossing (K,) is not empty, the quasi-static
    crossing at the last load: a cleat-free frictionless level and one level per contact position
    s in crossing (m, module docstring). A Path (`static_path`)."""
    def surface_at(h, s):
        phi = jnp.where(jnp.isnan(s), jnp.pi, -s / drum_radius)  # s: arc along the drum's surface
        return with_cleat(drum_at(drum_radius, h), cleat_radius, cleat_height, phi, 0.0)

    parts = [EQ.vertical_levels(pressure, loads)]
    if crossing.shape[0]:
        args = jnp.concatenate([jnp.full(1, jnp.nan), crossing])
        parts.append(EQ.Levels.make(pressure, rim_force=np.array([0, 0, -1.0, 0, 0, 0]) * loads[-1],
                                    rim_free=np.array([0, 0, 1.0, 0, 0, 0]), friction_on=0.0, surface_arg=args,
                                    n=args.shape[0]))
    return EQ.static_path(model, params, pressure, *parts, surface_at=surface_at)


def with_cleat(d: Drum, radius, height, phi_at, t_at):
    """Union of drum d and a cleat of `radius` standing `height` above it, at angle phi_at (rad from
    the top, + towards +x) at time t_at (s). Traced."""
    phi0 = phi_at - d.omega * t_at
    cleat = Cleat(radius=f64(radius), height=f64(height), drum_radius=d.radius, centre_x=d.centre_x,
                  centre_z=d.centre_z, omega=d.omega, phi0=f64(phi0))
    return DrumWithCleat(drum=d, cleat=cleat)


class DrumCleat(Experiment):
    name = "drum_cleat"
    study_id = "E03"
    description = "E03 drum-cleat: first in-plane mode and k_dv"
    schema = {
        "drum_diameter_m": Field(float, 1, 0.3, 20, 2.5, "m"),
        "speed_kmh": Field(float, U.KMH, 1, 150, 50.0, "km/h"),
        "cleat_diameter_mm": Field(float, U.MM, 5, 1000, 200.0, "mm"),
        "cleat_height_mm": Field(float, U.MM, 1, 1000, 20.0, "mm (above the drum surface; the study gives none)"),
        "roll_settle_s": Field(float, 1, 0.005, 1.0, 0.06, "s"),
        "lead_time_s": Field(float, 1, 0.0, 0.1, 0.005, "s"),
        "record_s": Field(float, 1, 0.05, 1.0, 0.3, "s"),
        "sample_rate_Hz": Field(float, 1, 500, 20000, 4000.0, "Hz"),
        "f_band_Hz": Field(list, 1, 0, 10000, [20.0, 200.0], "Hz"),
        "pad_resolution_Hz": Field(float, 1, 1e-4, 0.2, 0.01, "Hz"),
        "method": Field(str, default="static", choices=("static", "transient")),
        "enveloping_range_mm": Field(float, U.MM, 0, 2000, 300.0, "mm (quasi-static crossing from -range to +range; "
                                     "0: none; method \"static\" only)"),
        "enveloping_step_mm": Field(float, U.MM, 2, 200, 10.0, "mm"),
    }
    traced_names = ()
    quantity_names = ("first_mode_Hz", "k_dv_N_per_m", "first_mode_fit_fn_Hz", "k_dv_fit_N_per_m", "first_mode_fit_fd_Hz",
                      "first_mode_xi", "first_mode_contact_force_Hz", "first_mode_contact_force_fit_fn_Hz",
                      "first_mode_belt_displacement_Hz", "raw_resolution_Hz", "padded_resolution_Hz", "m_b_kg",
                      "deflection_m", "contact_half_length_on_drum_m", "peak_axle_force_N", "static_axle_force_N",
                      *ENVELOPING_NAMES)

    drum_radius: jax.Array
    speed: jax.Array
    cleat_radius: jax.Array
    cleat_height: jax.Array
    roll_settle: jax.Array
    lead_time: jax.Array
    record: float = eqx.field(static=True)
    sample_rate: float = eqx.field(static=True)
    f_band: tuple = eqx.field(static=True)
    pad_resolution: float = eqx.field(static=True)
    n_save: int = eqx.field(static=True)
    method: str = eqx.field(static=True, default="static")  # inflation and loading: "static" or "transient"
    crossing: tuple = eqx.field(static=True, default=())  # contact positions s (m) of the quasi-static crossing

    @staticmethod
    def _crosses(table) -> bool:
        """The table asks for the quasi-static crossing (it needs the static loading)."""
        return table["enveloping_range_mm"] > 0 and table["method"] == "static"

    @classmethod
    def produces(cls, table):
        return cls.quantity_names if cls._crosses(table) else tuple(n for n in cls.quantity_names
                                                                   if n not in ENVELOPING_NAMES)

    @property
    def time_stepped(self) -> bool:
        return True  # the rolling and the impact are transients whichever way the loaded state was reached

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        r_d, v = table["drum_diameter_m"] / 2, table["speed_kmh"]
        r_c, h_c = table["cleat_diameter_mm"] / 2, table["cleat_height_mm"]
        if h_c > 2 * r_c:
            raise ConfigError(f"drum_cleat.cleat_height_mm = {h_c * 1e3:g}: must be in (0, cleat_diameter_mm = {2 * r_c * 1e3:g}]")
        fs = table["sample_rate_Hz"]
        lo, hi = check_range_pair("drum_cleat.f_band_Hz", table["f_band_Hz"], "Hz")
        if lo < 0 or hi > fs / 2:
            raise ConfigError(f"drum_cleat.f_band_Hz = [{lo:g}, {hi:g}]: must lie in [0, sample_rate_Hz / 2 = {fs / 2:g}] Hz")
        t_imp = table["lead_time_s"] + CROSS_ALLOWANCE + table["record_s"]
        omega_d = v / r_d
        if omega_d * (table["roll_settle_s"] + t_imp) > 2 * math.pi - 1.0:
            raise ConfigError(f"drum_cleat.roll_settle_s + record_s = {table['roll_settle_s'] + table['record_s']:g} s: the "
                              f"cleat would come round twice; keep the rolling shorter than one drum turn "
                              f"({2 * math.pi / omega_d:.3g} s) less 1.2 rad")
        rng, step = table["enveloping_range_mm"], table["enveloping_step_mm"]
        n_cross = int(round(2 * rng / step)) + 1 if cls._crosses(table) else 0
        if n_cross > 401:
            raise ConfigError(f"drum_cleat.enveloping_step_mm = {step * 1e3:g}: at most 400 steps over the range "
                              f"(2 x {rng * 1e3:g} mm); raise the step to >= {2 * rng / 400 * 1e3:.3g} mm")
        crossing = tuple(float(x) for x in np.linspace(-rng, rng, n_cross)) if n_cross else ()
        return cls(proto=proto, drum_radius=f64(r_d), speed=f64(v), cleat_radius=f64(r_c), cleat_height=f64(h_c),
                   roll_settle=f64(table["roll_settle_s"]), lead_time=f64(table["lead_time_s"]),
                   record=float(table["record_s"]), sample_rate=float(fs), f_band=(lo, hi),
                   pad_resolution=float(table["pad_resolution_Hz"]), n_save=int(round(t_imp * fs)) + 1,
                   method=table["method"], crossing=crossing)

    def t_impact(self):
        return self.lead_time + CROSS_ALLOWANCE + self.record

    def simulate(self, model, params, case):
        proto = self.proto
        R_d, r_c, h_c, V = self.drum_radius, self.cleat_radius, self.cleat_height, self.speed

        def branches(case):
            """inflate, load, roll, impact: the phases of `case` (traced)."""
            f_rim = case.load * DOWN

            def inflate(y, t, mem):
                far = with_cleat(drum_at(R_d, -10.0), r_c, h_c, jnp.pi, t)
                d = make_drive(case.pressure, case.dt, pressure0=0.0, t0=t, t1=t + proto.inflate_ramp, surface=far,
                               damping=proto.settle_damping)
                return Phase(d, y, proto.inflate_max, proto.inflate_ramp), mem

            def load(y, t, mem):
                z_top = first_contact_height(model, y)
                mem = dict(mem, z_top=z_top)
                still = with_cleat(drum_at(R_d, z_top), r_c, h_c, jnp.pi, t)
                d = make_drive(case.pressure, case.dt, force1=f_rim, t0=t, t1=t + proto.load_ramp, rim_free=RIM_Z,
                               surface=still, damping=proto.settle_damping)
                return Phase(d, y, proto.load_ramp + proto.settle_max, proto.load_ramp), mem

            def roll(y, t, mem):
                z_top = mem["z_top"]
                R0 = -z_top  # inflated outer radius (rim centre at the origin)
                x_rear, x_front = x_range_traced(model, y, surface_gap(drum_at(R_d, z_top)))
                # where the cleat first touches the tire: the tread leaves the drum as a parabola of relative
                # curvature 1/R0 + 1/R_d, so a cleat of height h reaches it sqrt(2 h / k) beyond the patch edge,
                # plus the cleat's own half chord
                reach = jnp.sqrt(2 * h_c / (1 / R0 + 1 / R_d)) + jnp.sqrt(jnp.maximum(r_c**2 - (r_c - h_c) ** 2, 0.0))
                orbit = R_d + h_c - r_c
                phi_touch = jnp.arcsin(jnp.minimum((x_front + reach) / orbit, 1.0))
                phi_leave = jnp.arcsin(jnp.maximum((x_rear - reach) / orbit, -1.0))
                omega_d = V / R_d
                phi_imp = phi_touch + omega_d * self.lead_time  # cleat angle at the start of the impact phase
                mem = dict(mem, phi_imp=phi_imp, phi_leave=phi_leave, a=0.5 * (x_front - x_rear), defl=-y.q[2])
                surf = with_cleat(drum_at(R_d, z_top, V), r_c, h_c, phi_imp + omega_d * self.roll_settle, t)
                d = make_drive(case.pressure, case.dt, force0=f_rim, force1=f_rim, rim_free=RIM_SPIN, surface=surf,
                               damping=proto.settle_damping, rim_frame=1.0)
                y = with_spin(y, V / (R0 + y.q[2] / 3))
                return Phase(d, y, self.roll_settle, jnp.inf), mem

            def impact(y, t, mem):
                surf = with_cleat(drum_at(R_d, mem["z_top"], V), r_c, h_c, mem["phi_imp"], t)
                d = make_drive(case.pressure, case.dt, force0=f_rim, force1=f_rim, rim_free=RIM_SPIN, surface=surf,
                               damping=0.0, rim_frame=1.0)
                mem = dict(mem, t_imp0=t)
                return Phase(d, y, self.t_impact(), jnp.inf), mem

            return [inflate, load, roll, impact]

        mem0 = {k: 0.0 for k in ("z_top", "phi_imp", "phi_leave", "a", "defl", "t_imp0")}
        if self.method == "static":
            loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
            crossing = jnp.asarray(self.crossing, jnp.float64).reshape(-1)
            path = _drum_path_jit(model, params, case.pressure, loads, R_d, r_c, h_c, crossing)
            iL = STATIC_LOADS + 1  # the last load level; the crossing's levels follow it
            loaded = jax.tree_util.tree_map(lambda a: a[iL], path.ys)
            mem0["z_top"] = path.road_height[iL]
            outs, _, mem = run_plan_vmapped(model, params, lambda c: branches(c)[2:], case, loaded, mem0, proto.ke_tol,
                                            self.n_save)
            return {"phases": outs, "mem": mem, "static_infos": path.infos, "static_contact": path.contact[iL],
                    "static_loads": loads, "crossing_z": path.q[iL + 1:, 2], "crossing_contact": path.contact[iL + 1:]}
        y0 = TireState.at_rest(model, len(params.relaxation_times))
        outs, y, mem = run_plan(model, params, branches(case), y0, mem0, proto.ke_tol, self.n_save)
        return {"phases": outs, "mem": mem}

    def _loaded(self, out, model, load):
        """(the roll and impact phases, checks, info) after checking how the loaded state was reached."""
        if self.method == "static":
            loads = np.asarray(out["static_loads"])
            n = len(loads) + 2
            infos = out["static_infos"]
            check_static_path("drum_cleat", {"loads": loads, "infos": jax.tree_util.tree_map(lambda a: a[:n], infos)})
            EQ.check_static(jax.tree_util.tree_map(lambda a: a[n:], infos), lambda k: (
                "drum_cleat: quasi-static crossing, cleat-free level" if k == 0 else
                f"drum_cleat: quasi-static crossing at s = {1e3 * self.crossing[k - 1]:.4g} mm"),
                hint="try a smaller drum_cleat.enveloping_step_mm, or enveloping_range_mm = 0 (no crossing)")
            fz = float(np.asarray(out["static_contact"])[2])
            require_equilibrium("drum_cleat: loaded on the still drum", fz, load)
            checks, info = static_summary(out["static_infos"])
            info["levels"] = int(len(loads) + 2)
            ph = [phase(out["phases"], i) for i in range(2)]
            return ph[0], ph[1], checks | {"load_contact_vs_load_rel_error": abs(fz - load) / load}, info
        names = ("inflate", "load", "roll", "impact")
        ph = [phase(out["phases"], i) for i in range(4)]
        for i, (n, p) in enumerate(zip(names, ph)):
            check_phase(n, p, model, require_settled=i < 2)
        fz_ld, err_ld, _ = contact_check(ph[1].saved, load)
        require_equilibrium("drum_cleat: loaded on the still drum", fz_ld, load)
        checks = phase_checks("inflate", ph[0], model) | phase_checks("load", ph[1], model)
        return ph[2], ph[3], checks | {"load_contact_vs_load_rel_error": err_ld}, {"method": "transient"}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model, load = tire.model, condition["load_N"]
        roll, imp, checks0, info0 = self._loaded(out, model, load)
        check_phase("roll", roll, model, require_settled=False)
        check_phase("impact", imp, model, require_settled=False)
        mem = {k: float(v) for k, v in out["mem"].items()}
        V, R_d = float(self.speed), float(self.drum_radius)
        t = float(imp.t0)
        n = self.n_save
        ts = np.linspace(t, t + float(self.t_impact()), n)
        t_touch = t + float(self.lead_time)
        t_leave = t + (mem["phi_imp"] - mem["phi_leave"]) / (V / R_d)
        t_centre = t + mem["phi_imp"] / (V / R_d)  # the cleat under the rim centre (phi = 0)
        s = jax.tree_util.tree_map(np.asarray, imp.saved)
        fc, bz, f_axle, spin = s["contact_force"][:, 2], s["belt_disp"][:, 2], s["tire_on_rim"][:, 2], s["qd"][:, 4]
        band = self.f_band
        sp = spectra.first_mode(ts, f_axle, f_band=band, pad_to_resolution=self.pad_resolution, t_start=t_leave)
        sp_c = spectra.first_mode(ts, fc, f_band=band, pad_to_resolution=self.pad_resolution, t_start=t_leave)
        sp_b = spectra.first_mode(ts, bz, f_band=band, pad_to_resolution=self.pad_resolution, t_start=t_leave, fit=False)
        m_b = tire.spec.masses.belt
        f1 = sp.f_peak_Hz
        pre = ts < t_touch
        roll_spin = np.asarray(roll.saved["qd"])[:, 4]
        q = {"first_mode_Hz": f1, "k_dv_N_per_m": (2 * math.pi * f1) ** 2 * m_b,
             "first_mode_fit_fn_Hz": sp.fn_fit_Hz, "k_dv_fit_N_per_m": (2 * math.pi * sp.fn_fit_Hz) ** 2 * m_b,
             "first_mode_fit_fd_Hz": sp.f_fit_Hz, "first_mode_xi": sp.xi_fit,
             "first_mode_contact_force_Hz": sp_c.f_peak_Hz, "first_mode_contact_force_fit_fn_Hz": sp_c.fn_fit_Hz,
             "first_mode_belt_displacement_Hz": sp_b.f_peak_Hz,
             "raw_resolution_Hz": sp.raw_resolution_Hz, "padded_resolution_Hz": sp.padded_resolution_Hz,
             "m_b_kg": m_b, "deflection_m": mem["defl"], "contact_half_length_on_drum_m": mem["a"],
             "peak_axle_force_N": float(np.max(f_axle)), "static_axle_force_N": float(np.mean(f_axle[pre]))}
        env_checks, env_info = {}, {}
        if self.crossing:  # only ever set with the static method
            q_env, env_checks, env_info = self._crossing(out, mem)
            q |= q_env
        checks = checks0 | env_checks | {
            "spectrum_peak_at_band_edge": sp.peak_at_band_edge, "fit_rms_relative": sp.fit_rms_relative,
            "fit_vs_peak_rel_diff": sp.rel_diff_f,
            "contact_vs_axle_mode_rel_diff": (sp_c.f_peak_Hz - f1) / f1,
            "belt_vs_axle_mode_rel_diff": (sp_b.f_peak_Hz - f1) / f1,
            "roll_spin_end_rad_s": float(roll_spin[-1]),
            "roll_spin_drift_last_quarter_rel": float(np.ptp(roll_spin[-n // 4:]) / abs(roll_spin[-1])),
            "rolling_radius_from_spin_m": float(V / np.mean(spin[pre])), "free_samples": sp.n}
        info = info0 | run_info(out["phases"]) | {
            "axle_force": "tire_on_rim z: the tire's force on the rim (beads and rim closure pressure)",
            "drum_radius_m": R_d, "surface_speed_m_s": V, "cleat_radius_m": float(self.cleat_radius),
            "cleat_height_m": float(self.cleat_height), "cleat_height_note": "not given by the study: a config choice",
            "t_cleat_touch_s": t_touch, "t_cleat_leave_s": t_leave, "t_cleat_centre_s": t_centre,
            "spectrum_from_s": t_leave,
            "sample_rate_Hz": self.sample_rate, "f_band_Hz": list(band),
            "spectrum": sp.as_dict(), "spectrum_contact_force": sp_c.as_dict()} | env_info
        sig = {"time_s": ts - t_touch, "axle_force_N": f_axle, "axle_force_x_N": s["tire_on_rim"][:, 0],
               "contact_force_z_N": fc, "contact_force_x_N": s["contact_force"][:, 0], "belt_disp_z_m": bz,
               "spin_rad_s": spin}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)


    def _crossing(self, out, mem):
        """(quantities, checks, info) of the quasi-static crossing: effective height and slope at each
        contact position and the tandem cam fitted to them (module docstring)."""
        z = np.asarray(out["crossing_z"])
        c = np.asarray(out["crossing_contact"])
        s = np.asarray(self.crossing)
        w = z[1:] - z[0]  # the rim's lift under the constant load
        if max(abs(w[0]), abs(w[-1])) > CROSSING_EDGE_M:
            raise SimulationError(
                f"drum_cleat: quasi-static crossing: the cleat still lifts the tire by {1e3 * max(w[0], w[-1]):.3g} mm at "
                f"s = +-{1e3 * s[-1]:.4g} mm, the crossing's ends: raise drum_cleat.enveloping_range_mm (up to 2000)")
        fz = c[1:, 2]
        slope = -(c[1:, 0] - c[0, 0]) / fz
        r_c, h_c = float(self.cleat_radius), float(self.cleat_height)
        f = enveloping.fit(s, w, slope, r_c, h_c, a=mem["a"], R0=-mem["z_top"])
        q = {"ellips_shift_m": f.l_s, "ellips_length_m": f.a_e, "ellips_height_m": f.b_e, "ellips_order": f.c_e,
             "enveloping_fit_rms_height_m": f.rms_height_m, "enveloping_max_height_m": f.max_height_m}
        checks = {"enveloping_fit_rms_height_rel": f.rms_height_m / max(f.max_height_m, 1e-12),
                  "enveloping_fit_rms_slope": f.rms_slope, "enveloping_fit_on_bound": ", ".join(f.on_bound) or "none",
                  "enveloping_contact_F_z_rel_spread": float(np.ptp(fz) / np.mean(fz))}
        info = {"enveloping": {"s_m": s.tolist(), "w_m": w.tolist(), "slope": slope.tolist(),
                               "F_x_N": c[1:, 0].tolist(), "F_z_N": fz.tolist(), "fit": f.as_dict(),
                               "what": "quasi-static crossing: rim under the constant load, frictionless, cleat "
                                       "stepped through the patch; w = rim lift, slope = -F_x/F_z"}}
        return q, checks, info


_drum_path_jit = eqx.filter_jit(_drum_path)  # one compiled static program for every drum and cleat
