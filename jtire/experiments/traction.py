"""E06 longitudinal slip stiffness k_k and tread stiffness k_cx on a 3.4 m drum that spins with its own
inertia, the tire driven by a rapidly rising wheel torque (experiments.md).

Phases (one surface type, the free drum `physics.drum.FreeDrum`, whose spin is a state variable):
1. inflate (the drum far below); 2. load onto the still, held drum (rim z free, load ramped, settled,
   checked); the rim height is then locked where it settled (x, y and tilts locked throughout);
3. spin-up: the drum held at the surface speed V, the wheel's spin free (started at V / (R0 - defl / 3)),
   settle damping relative to the rim frame; 4. free rolling without damping: the effective rolling
   radius R_e = V / mean(omega_w) over its second half;
5. drive: the drum released (it now spins under the contact torque with its inertia I_d) and a wheel
   torque ramped from 0 to `torque_over_load` x F_z x R0 over `ramp_s`. The force-slip curve is read
   along the ramp from the two angular velocities:
       kappa = (omega_w R_e - omega_d R_d) / (omega_d R_d)      (> 0 driving)
   and F_x, the drum's force on the tire along x (ISO, forward).
k_k is the slope of F_x against kappa over `fit_range` (default 0-10 %, the study's) and over the linear
part of it (F_x within `linear_tol` of the initial slope line); k_k_N_per_slip is the linear-part slope.
k_cx = k_k / a, a the static contact half length on the drum at the same condition (measured on the loaded
state; the flat-road E01 value is the other choice: the table reports which).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals
from .. import units as U
from ..errors import ConfigError
from ..physics.drum import FreeDrum
from ..schema import Field, check_range_pair
from ..state import TireState
from .base import Experiment
from .loads import DOWN, RIM_SPIN, RIM_Z
from .patch import surface_gap, x_range_traced
from .phases import first_contact_height, make_drive, with_spin
from .program import Phase, check_phase, contact_check, f64, phase, phase_checks, require_equilibrium, run_info, run_plan
from . import steady as ST
from ..equilibrium import rolling as ER
from ..equilibrium.residual import unpack
from .result import ExperimentResult


def free_drum(radius, top_z, inertia, free):
    """A drum of `radius` (m) with its top at height top_z (m), inertia (kg m^2) about its axle; free = 1:
    it spins under the contact torque, 0: its spin is held (the state's drum speed). Traced."""
    r = f64(radius)
    return FreeDrum(radius=r, centre_x=f64(0.0), centre_z=f64(top_z) - r, inertia=f64(inertia), free=f64(free))


def _linear_range(kappa, fx, k0, tol, hi):
    """Largest kappa in (0, hi] up to which every sample keeps |F - F(0) - k0 kappa| <= tol |k0 kappa|."""
    f0 = float(np.interp(0.0, kappa, fx))
    top = 0.0
    for k, f in zip(kappa, fx):
        if k <= 0:
            continue
        if k > hi + 1e-12:
            break
        if abs(f - f0 - k0 * k) <= tol * abs(k0 * k):
            top = k
        else:
            break
    return top


def fit_slip_curve(kappa, fx, fit_range, linear_tol, raise_what):
    """k_k (N per unit slip) of a force-slip curve: the slope over the linear part of `fit_range` (F_x
    within linear_tol of the initial slope line) and over the whole range; the curve up to where it
    first leaves the range (after that a driven wheel may spin up)."""
    lo, hi = fit_range
    order = np.argsort(kappa)
    k_sorted, f_sorted = kappa[order], fx[order]
    n_in = int(np.sum((kappa >= lo) & (kappa <= hi)))
    if n_in < 3:
        raise ConfigError(f"traction: only {n_in} points of the force-slip curve fall in fit_range_percent = "
                          f"[{lo * 100:g}, {hi * 100:g}] (kappa reached {100 * kappa.max():.3g} %): raise {raise_what}")
    full = signals.linear_slope(kappa, fx, (lo, hi))
    small = (kappa >= 0) & (kappa <= min(hi, 0.02))
    k0 = signals.linear_slope(kappa[small], fx[small]).slope if small.sum() >= 3 else full.slope
    top = _linear_range(k_sorted, f_sorted, k0, linear_tol, hi)
    lin = signals.linear_slope(kappa, fx, (lo, max(top, lo + 0.2 * (hi - lo))))
    return {"k_k_N_per_slip": lin.slope, "k_k_range_lo": lin.x_lo, "k_k_range_hi": lin.x_hi, "k_k_r2": lin.r2,
            "k_k_fit_range_N_per_slip": full.slope, "fit_range_lo": full.x_lo, "fit_range_hi": full.x_hi,
            "fit_range_r2": full.r2, "k_k_initial_N_per_slip": float(k0)}


class Traction(Experiment):
    name = "traction"
    study_id = "E06"
    description = "E06 longitudinal slip stiffness k_k and tread stiffness k_cx (free drum, rising wheel torque)"
    schema = {
        "method": Field(str, default="steady", choices=("steady", "transient")),
        "surface": Field(str, default="drum", choices=("drum", "flat")),  # steady: on the drum or a flat road
        "slip_max_percent": Field(float, 0.01, 1, 50, 15.0, "% (steady: the largest slip solved)"),
        "slip_levels": Field(int, 1, 3, 100, 15, "slips solved from 0 to slip_max_percent (steady)"),
        "drum_diameter_m": Field(float, 1, 0.3, 20, 3.4, "m"),
        "drum_inertia_kgm2": Field(float, 1, 1, 1e6, 5000.0, "kg m^2 (the study gives none: a 3.4 m steel road wheel)"),
        "speed_kmh": Field(float, U.KMH, 1, 150, 36.0, "km/h"),
        "spin_up_s": Field(float, 1, 0.005, 1.0, 0.04, "s"),
        "free_s": Field(float, 1, 0.01, 1.0, 0.15, "s"),
        "ramp_s": Field(float, 1, 0.02, 5.0, 0.3, "s"),
        "torque_over_load": Field(float, 1, 0.01, 2.0, 0.35, "m (peak wheel torque / (F_z R0))"),
        "fit_range_percent": Field(list, 0.01, -50, 50, [0.0, 10.0], "%"),
        "linear_tol": Field(float, 1, 0.01, 1.0, 0.1, "(relative)"),
        "n_samples": Field(int, 1, 101, 4001, 601, "samples along the torque ramp"),
    } | ST.STEADY_FIELDS
    traced_names = ()
    COMMON = ("k_k_N_per_slip", "k_k_range_lo", "k_k_range_hi", "k_k_r2", "k_k_fit_range_N_per_slip",
              "fit_range_lo", "fit_range_hi", "fit_range_r2", "k_k_initial_N_per_slip", "k_cx_N_per_m",
              "k_cx_fit_range_N_per_m", "contact_half_length_m", "contact_half_length_source",
              "effective_rolling_radius_m", "max_slip", "max_force_x_N", "peak_wheel_torque_Nm",
              "mean_force_z_N", "deflection_m")
    quantity_names = COMMON + ("free_rolling_force_x_N",)  # the default (steady) method's

    @classmethod
    def produces(cls, table):
        return cls.quantity_names if table["method"] == "steady" else cls.COMMON + ("drum_speed_change_rel",)

    drum_radius: jax.Array
    drum_inertia: jax.Array
    speed: jax.Array
    spin_up: jax.Array
    free: jax.Array
    ramp: jax.Array
    torque_over_load: jax.Array
    fit_range: tuple = eqx.field(static=True)
    linear_tol: float = eqx.field(static=True)
    outer_radius: float = eqx.field(static=True)
    n_save: int = eqx.field(static=True)
    method: str = eqx.field(static=True, default="transient")
    surface: str = eqx.field(static=True, default="drum")
    slips: tuple = eqx.field(static=True, default=())  # steady: the longitudinal slips solved
    subpoints: int = eqx.field(static=True, default=8)
    load_levels: int = eqx.field(static=True, default=2)

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        fr = check_range_pair("traction.fit_range_percent", table["fit_range_percent"], "%", 0.01)
        return cls(proto=proto, drum_radius=f64(table["drum_diameter_m"] / 2), drum_inertia=f64(table["drum_inertia_kgm2"]),
                   speed=f64(table["speed_kmh"]), spin_up=f64(table["spin_up_s"]), free=f64(table["free_s"]),
                   ramp=f64(table["ramp_s"]), torque_over_load=f64(table["torque_over_load"]), fit_range=fr,
                   linear_tol=float(table["linear_tol"]), outer_radius=float(tire_spec.geometry.outer_radius),
                   n_save=int(table["n_samples"]), method=table["method"], surface=table["surface"],
                   slips=tuple(float(v) for v in np.linspace(0.0, table["slip_max_percent"], table["slip_levels"] + 1)),
                   subpoints=ST.check_subpoints(cls.name, table, tire_spec), load_levels=int(table["steady_load_levels"]))

    def road(self):
        return ER.Road("drum", float(self.drum_radius)) if self.surface == "drum" else ER.Road()

    def _simulate_steady(self, model, params, case):
        """Loaded free rolling on the drum (or road) at the surface speed, then each slip with the wheel's
        spin prescribed: Omega = (1 + kappa) Omega_free, the drum (road) speed held."""
        path = ST.loaded(model, params, case, self.road(), self.speed, subpoints=self.subpoints,
                         n_load=self.load_levels, outer_radius=self.outer_radius)
        n = len(path.obs)
        w_free = path.q[4]
        x = unpack(model, path.u, False)[0]
        state = eqx.tree_at(lambda y: (y.x, y.q), TireState.at_rest(model, 0), (x, path.q.at[4].set(0.0)))
        surface = self.road().surface(path.height, ER.road_velocity(self.speed))
        x_rear, x_front = x_range_traced(model, state, surface_gap(surface))
        obs = [path.obs[-1]]

        def setup_at(k):
            return ER.setup_of(case.pressure, surface, omega=(1 + k) * w_free, rim_free=ER.LOADED_SPIN_HELD,
                               load=case.load, subpoints=self.subpoints)

        obs += ST.sweep_through(path, setup_at, self.slips[0], self.slips[1:], lambda b: f"slip {100 * b:.3g} %")[0]
        out = ST.stacked(path, range(n))
        return out | {"slips": jax.tree_util.tree_map(lambda *a: jnp.stack(a), *obs), "a": 0.5 * (x_front - x_rear),
                      **ST.sweep_outputs(path, n)}

    def _reduce_steady(self, tire, condition, out):
        load, V = condition["load_N"], float(self.speed)
        checks, info = ST.summary(self.name, out["infos"], ST.level_names(self.load_levels))
        ST.summary(self.name, out["sweep_infos"], ST.sweep_name("slip", out["sweep_values"], 100, "%"), ST.SWEEP_HINT)
        sl = jax.tree_util.tree_map(np.asarray, out["slips"])
        kappa = np.asarray(self.slips)
        fx, fz, w = sl["contact_force"][:, 0], sl["contact_force"][:, 2], sl["omega"]
        fit = fit_slip_curve(kappa, fx, self.fit_range, self.linear_tol, "slip_max_percent")
        a = float(out["a"])
        q = fit | {"k_cx_N_per_m": fit["k_k_N_per_slip"] / a, "k_cx_fit_range_N_per_m": fit["k_k_fit_range_N_per_slip"] / a,
                   "contact_half_length_m": a, "contact_half_length_source": f"{self.surface} (free rolling)",
                   "effective_rolling_radius_m": V / float(w[0]), "max_slip": float(kappa.max()),
                   "max_force_x_N": float(fx.max()), "peak_wheel_torque_Nm": float(np.max(-sl["tire_on_rim"][:, 4])),
                   "mean_force_z_N": float(fz.mean()), "deflection_m": -float(sl["q"][0, 2]),
                   "free_rolling_force_x_N": float(fx[0])}
        checks |= {"force_z_vs_load_max_rel": float(np.max(np.abs(fz - load)) / load)}
        info |= {"surface": self.surface, "surface_speed_m_s": V, "steady_subpoints": self.subpoints,
                 "slip_definition": "kappa = Omega / Omega_free - 1 at the surface speed held (R_e from free rolling)"}
        if self.surface == "drum":
            info["drum_radius_m"] = float(self.drum_radius)
        sig = {"slip": kappa, "force_x_N": fx, "force_z_N": fz, "wheel_spin_rad_s": w,
               "wheel_torque_Nm": -sl["tire_on_rim"][:, 4]}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)

    def simulate(self, model, params, case):
        if self.method == "steady":
            return self._simulate_steady(model, params, case)
        proto, R_d, I_d, V = self.proto, self.drum_radius, self.drum_inertia, self.speed
        f_rim = case.load * DOWN

        def drum_drive(y, t, mem, free, damping, torque=0.0, t1=None):
            return make_drive(case.pressure, case.dt, force0=f_rim, force1=f_rim + jnp.zeros(6).at[4].set(torque),
                              t0=t, t1=t if t1 is None else t1, rim_free=RIM_SPIN,
                              surface=free_drum(R_d, mem["z_top"], I_d, free), damping=damping, rim_frame=1.0)

        def inflate(y, t, mem):
            d = make_drive(case.pressure, case.dt, pressure0=0.0, t0=t, t1=t + proto.inflate_ramp,
                           surface=free_drum(R_d, -10.0, I_d, 0.0), damping=proto.settle_damping)
            return Phase(d, y, proto.inflate_max, proto.inflate_ramp), mem

        def load(y, t, mem):
            mem = dict(mem, z_top=first_contact_height(model, y))
            d = make_drive(case.pressure, case.dt, force1=f_rim, t0=t, t1=t + proto.load_ramp, rim_free=RIM_Z,
                           surface=free_drum(R_d, mem["z_top"], I_d, 0.0), damping=proto.settle_damping)
            return Phase(d, y, proto.load_ramp + proto.settle_max, proto.load_ramp), mem

        def spin_up(y, t, mem):
            x_rear, x_front = x_range_traced(model, y, surface_gap(free_drum(R_d, mem["z_top"], I_d, 0.0).spinning(0.0)))
            mem = dict(mem, a=0.5 * (x_front - x_rear), defl=-y.q[2])
            y = with_spin(y, V / (self.outer_radius + y.q[2] / 3))
            y = eqx.tree_at(lambda s: s.drum, y, jnp.stack([y.drum[0], -V / R_d]))  # top moving to -x
            return Phase(drum_drive(y, t, mem, 0.0, proto.settle_damping), y, self.spin_up, jnp.inf), mem

        def free_roll(y, t, mem):
            return Phase(drum_drive(y, t, mem, 0.0, 0.0), y, self.free, jnp.inf), mem

        def drive(y, t, mem):
            torque = self.torque_over_load * case.load * self.outer_radius
            mem = dict(mem, torque=torque)
            # the drum turns at -omega about +y (top towards -x): a driving wheel torque is + about +y
            return Phase(drum_drive(y, t, mem, 1.0, 0.0, torque, t + self.ramp), y, self.ramp, jnp.inf), mem

        y0 = TireState.at_rest(model, len(params.relaxation_times))
        mem0 = {"z_top": 0.0, "a": 0.0, "defl": 0.0, "torque": 0.0}
        outs, y, mem = run_plan(model, params, [inflate, load, spin_up, free_roll, drive], y0, mem0, proto.ke_tol,
                                self.n_save)
        return {"phases": outs, "mem": mem}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        if self.method == "steady":
            return self._reduce_steady(tire, condition, out)
        model, load = tire.model, condition["load_N"]
        names = ("inflate", "load", "spin-up", "free rolling", "drive")
        ph = [phase(out["phases"], i) for i in range(5)]
        for i, (n, p) in enumerate(zip(names, ph)):
            check_phase(n, p, model, require_settled=i < 2)
        fz_ld, _, _ = contact_check(ph[1].saved, load)
        require_equilibrium("traction: loaded on the still drum", fz_ld, load)
        mem = {k: float(v) for k, v in out["mem"].items()}
        V, R_d = float(self.speed), float(self.drum_radius)
        fr = jax.tree_util.tree_map(np.asarray, ph[3].saved)
        tf = np.linspace(float(ph[3].t0), float(ph[3].t_end), self.n_save)
        w_free = signals.steady_mean(tf, fr["qd"][:, 4], (0.5 * (tf[0] + tf[-1]), tf[-1]))
        R_e = V / w_free.mean
        dr = jax.tree_util.tree_map(np.asarray, ph[4].saved)
        t = np.linspace(float(ph[4].t0), float(ph[4].t_end), self.n_save)
        w_wheel, w_drum = dr["qd"][:, 4], -dr["drum"][:, 1]  # drum speed as a positive surface-speed rate
        kappa = (w_wheel * R_e - w_drum * R_d) / (w_drum * R_d)
        fx, fz = dr["contact_force"][:, 0], dr["contact_force"][:, 2]
        fit = fit_slip_curve(kappa, fx, self.fit_range, self.linear_tol, "torque_over_load or n_samples")
        a = mem["a"]
        q = fit | {"k_cx_N_per_m": fit["k_k_N_per_slip"] / a, "k_cx_fit_range_N_per_m": fit["k_k_fit_range_N_per_slip"] / a,
             "contact_half_length_m": a, "contact_half_length_source": "drum (loaded state)",
             "effective_rolling_radius_m": R_e, "max_slip": float(kappa.max()), "max_force_x_N": float(fx.max()),
             "peak_wheel_torque_Nm": mem["torque"], "mean_force_z_N": float(fz.mean()), "deflection_m": mem["defl"],
             "drum_speed_change_rel": float(w_drum[-1] / w_drum[0] - 1.0)}
        checks = phase_checks("inflate", ph[0], model) | phase_checks("load", ph[1], model) | {
            "free_spin_drift_relative": w_free.drift_relative,
            "force_z_vs_load_max_rel": float(np.max(np.abs(fz - load)) / load),
            "free_rolling_force_x_N": float(fr["contact_force"][:, 0].mean())}
        info = run_info(out["phases"]) | {
            "drum": "free: spins under the contact torque with its inertia", "drum_radius_m": R_d,
            "drum_inertia_kgm2": float(self.drum_inertia), "surface_speed_m_s": V, "ramp_s": float(self.ramp),
            "slip_definition": "kappa = (omega_w R_e - omega_d R_d) / (omega_d R_d), R_e from free rolling",
            "linear_tol": self.linear_tol}
        sig = {"time_s": t - t[0], "slip": kappa, "force_x_N": fx, "force_z_N": fz, "wheel_spin_rad_s": w_wheel,
               "drum_spin_rad_s": w_drum, "wheel_torque_Nm": dr["rim_force"][:, 4]}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
