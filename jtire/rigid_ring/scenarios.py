"""The rigid ring run through the shell model's validation tests (docs/rigid-ring.md §8), same inputs.

Each scenario takes the condition's `Derived` record (params.derive), simulates, reduces the
signals with the project's own tools (jtire.signals.free_decay, jtire.spectra.first_mode) and
returns a ScenarioResult: `quantities` (reduced numbers, SI), `implied` (what the parameters imply:
closed forms and the linearized model's modes), `signals` (equal-length arrays, SI, SAE signs
where named so). Gravity is off by default, as in the shell's E02/E04 (the load is a rim force).
"""

import dataclasses
import math

import jax.numpy as jnp
import numpy as np

from .. import enveloping, slip_reading, spectra
from .. import signals as sig
from ..errors import ConfigError, SimulationError
from ..physics.drum import cleat_half_chord
from .model import (
    CONTACT,
    CONTACTS,
    E_NODES,
    IDX,
    N_STATE,
    U_NODES,
    Drive,
    RigidRing,
    linearize,
    modes,
    simulate,
)
from .params import Derived, RigidRingParams


@dataclasses.dataclass
class ScenarioResult:
    name: str
    quantities: dict
    implied: dict
    signals: dict
    info: dict


def _model(d: Derived, lateral: str, group: str, what: str, contact: str = CONTACT) -> RigidRing:
    if lateral not in ("ring", "reduced"):
        raise ConfigError(f"lateral = {lateral!r}: must be 'ring' or 'reduced'")
    if contact not in CONTACTS:
        raise ConfigError(f"contact = {contact!r}: must be one of {', '.join(map(repr, CONTACTS))}")
    d.require(group, what)
    return RigidRing(RigidRingParams.from_derived(d), lateral, contact)


def vertical_equilibrium(d: Derived, load_N: float, gravity: float = 0.0, z_road: float = 0.0) -> dict:
    """Static z_a, z_b (m) under a rim force load_N (+ gravity on the masses): contact force
    F_c = load + m_tot g, belt z_b = z_road + R0 - rho_r(F_c) (the residual spring's law),
    z_a = z_b - (F_c - m_b g) / k_bz."""
    t = d.tire
    fc = load_N + t.m_tot_kg * gravity
    zb = z_road + t.unloaded_radius_m - d.residual_deflection(fc)
    return {"z_b": zb, "z_a": zb - (fc - t.m_b_kg * gravity) / d.k_bz, "F_c": fc}


def _state(**kw):
    """The state vector from named positions, velocities (v_<name>) and tread deflections u, e (a
    uniform deflection: the string's nodes take it too, the static state of either contact)."""
    y = np.zeros(N_STATE)
    for k, v in kw.items():
        if k.startswith("v_"):
            y[IDX[k[2:]] + 10] = v
        else:
            y[IDX[k]] = v
            if k in ("u", "e"):
                y[list(U_NODES if k == "u" else E_NODES)] = v
    return jnp.asarray(y)


def _check(ys, what):
    ys = np.asarray(ys)
    if not np.all(np.isfinite(ys)):
        bad = int(np.argmax(~np.all(np.isfinite(ys), axis=1)))
        raise SimulationError(f"rigid ring {what}: non-finite state at sample {bad}")
    return ys


def _np(outs):
    return {k: np.asarray(v) for k, v in outs.items()}


def drop_test(d: Derived, drop_height=0.02, duration=0.4, gravity=0.0, n_save=4001, f_band=(40.0, 300.0)):
    """Rim z free, released `drop_height` above the road under the condition's load as a rim force.
    Reduces rim z(t) from first contact (free_decay, M = m_tot) and the contact force's spectrum
    in f_band (Hz; above the bounce, where the belt's vertical mode should show)."""
    m = _model(d, "reduced", "vertical", "drop test")
    t = d.tire
    fz = d.load_N
    zb0 = t.unloaded_radius_m + drop_height
    drive = Drive.make(free=("z_a",), rim_force=np.eye(10)[IDX["z_a"]] * -fz, gravity=gravity)
    ts = np.linspace(0.0, duration, n_save)
    ys = _check(simulate(m, drive, _state(z_a=zb0, z_b=zb0), duration, ts), "drop test")
    out = _np(m.outputs(jnp.asarray(ts), jnp.asarray(ys), drive))
    za, fzc = ys[:, IDX["z_a"]], out["F_z"]
    touch = np.flatnonzero(fzc > 0)
    if touch.size == 0:
        raise SimulationError(f"rigid ring drop test: no contact within {duration} s")
    i0 = int(touch[0])
    eq = vertical_equilibrium(d, fz, gravity)
    fd = sig.free_decay(ts, za, t.m_tot_kg, t_start=ts[i0], x_final=eq["z_a"])
    # lift-offs after the first contact: the decay is then not that of a linear oscillator
    air = np.flatnonzero((fzc[i0:] <= 0) & (np.arange(ts.size - i0) > 0)) + i0
    last_air = int(air[-1]) if air.size else None
    fd_in = None
    if last_air is not None and ts.size - last_air > 200:
        fd_in = sig.free_decay(ts, za, t.m_tot_kg, t_start=ts[last_air + 1], x_final=eq["z_a"])
    sp = spectra.first_mode(ts, fzc, f_band=f_band, t_start=ts[i0], fit=False)
    jac = linearize(m, drive, _state(z_a=eq["z_a"], z_b=eq["z_b"]))
    fn, zeta = modes(jac, ("z_a", "z_b"))
    k_sv, m_tot = d.k_sv, t.m_tot_kg
    # static deflection: where the wheel rests under the load (docs/rigid-ring.md §8: F_z0/k_sv), as
    # the shell's drop reports it (its rest after the drop); the decay fit's asymptote is no rest
    # position when the record is mostly lift-offs (it falls short: docs/design-notes.md)
    q = {"static_deflection_m": t.unloaded_radius_m - eq["z_a"],
         "static_deflection_fit_m": t.unloaded_radius_m - fd.x_inf_fit,
         "static_deflection_equilibrium_m": t.unloaded_radius_m - eq["z_a"],
         "bounce_f_d_Hz": fd.omega_d_fit / (2 * math.pi), "bounce_f_n_Hz": fd.omega_n_fit / (2 * math.pi),
         "bounce_zeta_fit": fd.xi_fit, "bounce_zeta_2p": fd.xi_2p,
         "bounce_f_d_2p_Hz": None if fd.omega_d_2p is None else fd.omega_d_2p / (2 * math.pi),
         "bounce_zeta_in_contact": None if fd_in is None else fd_in.xi_fit,
         "bounce_f_n_in_contact_Hz": None if fd_in is None else fd_in.omega_n_fit / (2 * math.pi),
         "C_tot_fit_Ns_per_m": 2 * fd.xi_fit * math.sqrt(m_tot * k_sv),
         "peak_F_z_N": float(fzc.max()), "first_contact_s": float(ts[i0]), "lost_contact": bool(air.size),
         "last_lift_off_s": None if last_air is None else float(ts[last_air]),
         "F_z_spectrum_peak_Hz": sp.interior_peak_Hz()}  # None: no mode inside the band
    implied = {"static_deflection_m": fz / k_sv, "bounce_f_n_quasi_static_Hz": math.sqrt(k_sv / m_tot) / (2 * math.pi),
               "zeta_quasi_static": d.C_tot / (2 * math.sqrt(k_sv * m_tot)),
               "bounce_f_n_Hz": float(fn[0]), "bounce_zeta": float(zeta[0]),
               "belt_mode_f_n_Hz": float(fn[-1]), "belt_mode_zeta": float(zeta[-1])}
    signals = {"time_s": ts, "rim_z_m": za, "belt_z_m": ys[:, IDX["z_b"]], "contact_force_z_N": fzc,
               "rim_z_from_rest_m": za - eq["z_a"]}  # from where the wheel rests under the load
    return ScenarioResult("drop_test", q, implied, signals, {"drop_height_m": drop_height, "gravity": gravity,
                                                             "two_peak_reason": fd.two_peak_reason})


def drum_cleat(d: Derived, speed=50 / 3.6, cleat_diameter=0.2, cleat_height=0.02, lead_s=0.01, record_s=0.3,
               sample_rate=4000.0, f_band=(20.0, 200.0), contact=CONTACT):
    """Rim x and z locked, spin free, rolling at `speed` over a round cleat: through E03's tandem cam
    when the condition has one (d.ellips, the effective road of `jtire.enveloping`: the force
    waveform and its peak-to-peak are comparable), else a point contact on the cleat's profile
    (frequencies and decay comparable, the waveform not). The cleat reaches the tire `lead_s` after
    the start. Reduces the spindle F_z and F_x after the cleat (jtire.spectra.first_mode:
    padded-spectrum peak and a damped-mode fit)."""
    m = _model(d, "reduced", "inplane", "drum-cleat", contact)
    fz = d.load_N
    eq = vertical_equilibrium(d, fz)
    r_c = cleat_diameter / 2
    reach = cleat_half_chord(r_c, cleat_height) if d.ellips is None else enveloping.reach(d.ellips[0], d.ellips[1], r_c,
                                                                                           cleat_height)
    s_c = speed * lead_s + reach
    t_free = (s_c + reach) / speed
    t1 = t_free + record_s
    drive = Drive.make(free=("theta_a",), V=speed, r_cleat=r_c, h_cleat=cleat_height, s_cleat=s_c, ellips=d.ellips)
    omega = speed / d.r_e
    y0 = _state(z_a=eq["z_a"], z_b=eq["z_b"], v_theta_a=omega, v_theta_b=omega)
    ts = np.arange(0.0, t1, 1.0 / sample_rate)
    # steps no longer than a sample: from the quiet start the controller would grow past the cleat
    ys = _check(simulate(m, drive, y0, ts[-1], ts, dtmax=1.0 / sample_rate), "drum-cleat")
    out = _np(m.outputs(jnp.asarray(ts), jnp.asarray(ys), drive))
    fz_sp, fx_sp = out["tire_on_rim_z"], out["tire_on_rim_x"]
    sz = spectra.first_mode(ts, fz_sp, f_band=f_band, t_start=t_free)
    sx = spectra.first_mode(ts, fx_sp, f_band=f_band, t_start=t_free)
    jac = linearize(m, drive, y0)
    fn, zeta = modes(jac, ("x_b", "z_b", "theta_b", "theta_a"), ("u",))
    after = ts >= t_free
    q = {"F_z_f_peak_Hz": sz.f_peak_Hz, "F_z_f_n_fit_Hz": sz.fn_fit_Hz, "F_z_zeta_fit": sz.xi_fit,
         "F_x_f_peak_Hz": sx.f_peak_Hz, "F_x_f_n_fit_Hz": sx.fn_fit_Hz, "F_x_zeta_fit": sx.xi_fit,
         "F_z_peak_to_peak_N": float(np.ptp(fz_sp)), "F_x_peak_to_peak_N": float(np.ptp(fx_sp)),
         "F_z_peak_to_peak_after_cleat_N": float(np.ptp(fz_sp[after])),
         "k_dv_from_F_z_N_per_m": (2 * math.pi * sz.f_peak_Hz) ** 2 * d.tire.m_b_kg}
    implied = {"modes_f_n_Hz": fn.tolist(), "modes_zeta": zeta.tolist(),
               "belt_vertical_f_n_Hz": math.sqrt((d.k_bz + d.k_vr) / d.tire.m_b_kg) / (2 * math.pi),
               "belt_vertical_zeta": (d.C_bz + d.C_vr) / (2 * math.sqrt((d.k_bz + d.k_vr) * d.tire.m_b_kg)),
               "f_dv_measured_Hz": d.f_dv}
    signals = {"time_s": ts, "spindle_F_z_N": fz_sp, "spindle_F_x_N": fx_sp, "road_z_m": out["z_road"],
               "contact_force_z_N": out["F_z"], "contact_force_x_N": out["F_x"]}
    return ScenarioResult("drum_cleat", q, implied, signals,
                          {"speed_m_s": speed, "cleat_diameter_m": cleat_diameter, "cleat_height_m": cleat_height,
                           "ellips": d.ellips, "contact": contact, "enveloping": "none (point contact follows the cleat profile)"
                           if d.ellips is None else
                           "tandem cam (l_s, a_e, b_e, c_e) = ({:.4g}, {:.4g}, {:.4g}, {:.4g}) from E03".format(*d.ellips),
                           "t_free_s": t_free, "t_touch_s": _first_rise(ts, out["z_road"]),
                           "t_centre_s": s_c / speed})


def _first_rise(t, z, eps=1e-7):
    """Time (s) the road under the contact first rises (the tire meets the cleat); t[0] if never."""
    up = np.asarray(z) - z[0] > eps
    return float(t[int(np.argmax(up))]) if up.any() else float(t[0])


def lateral_static(d: Derived, force: float, lateral: str) -> dict:
    """Static lateral state under a rim force (N, +y), standing, rim camber held, patch at y = 0."""
    if lateral == "reduced":
        ya = force / d.k_l
        return {"y_a": ya, "y_b": 0.0, "gamma_b": 0.0, "e": ya}
    e = force / d.k_cy
    gb = -d.r_b * force / d.k_bgamma
    yb = e - d.r_b * gb
    return {"y_a": yb + force / d.k_by, "y_b": yb, "gamma_b": gb, "e": e}


def lateral_release(d: Derived, force=5e3, lateral="reduced", duration=0.5, n_save=4001):
    """Standing at the condition's load (rim z locked at its static height), the rim pushed by
    `force` (N) and released at t = 0 from the static deflection; rim y free, camber held.
    Reduces rim y(t) with free_decay (M = m_tot)."""
    grp = "lateral_ring" if lateral == "ring" else "lateral_reduced"
    m = _model(d, lateral, grp, "lateral release")
    d.require("vertical", "lateral release")
    eq = vertical_equilibrium(d, d.load_N)
    st = lateral_static(d, force, lateral)
    drive = Drive.make(free=("y_a",))
    # a static push relaxes the Maxwell branches: their states sit at the springs' deflections
    y0 = _state(z_a=eq["z_a"], z_b=eq["z_b"], y_a=st["y_a"], y_b=st["y_b"], gamma_b=st["gamma_b"], e=st["e"],
                q_by=st["y_b"] - st["y_a"], q_bgamma=st["gamma_b"])
    ts = np.linspace(0.0, duration, n_save)
    ys = _check(simulate(m, drive, y0, duration, ts), "lateral release")
    ya = ys[:, IDX["y_a"]]
    fd = sig.free_decay(ts, ya, d.tire.m_tot_kg, x_final=0.0)
    jac = linearize(m, drive, _state(z_a=eq["z_a"], z_b=eq["z_b"]))
    coords = ("y_a",) if lateral == "reduced" else ("y_a", "y_b", "gamma_b")
    fn, zeta = modes(jac, coords, ("e",), () if lateral == "reduced" else ("q_by", "q_bgamma"))
    m_tot = d.tire.m_tot_kg
    q = {"k_l_static_N_per_m": force / st["y_a"], "f_d_Hz": fd.omega_d_fit / (2 * math.pi),
         "f_n_Hz": fd.omega_n_fit / (2 * math.pi), "zeta_fit": fd.xi_fit, "zeta_2p": fd.xi_2p,
         "C_l_fit_Ns_per_m": fd.c_fit}
    implied = {"k_l_N_per_m": d.k_l, "f_n_sdof_Hz": math.sqrt(d.k_l / m_tot) / (2 * math.pi),
               "zeta_sdof": d.C_l / (2 * math.sqrt(d.k_l * m_tot)), "f_n_linear_Hz": float(fn[0]),
               "zeta_linear": float(zeta[0]), "k_l_ring_N_per_m": d.k_l_ring}
    return ScenarioResult("lateral_release", q, implied, {"time_s": ts, "rim_y_m": ya},
                          {"force_N": force, "lateral": lateral})


def slip_step(d: Derived, speed=15.0, alpha_deg=2.0, lateral="reduced", t_step=0.01, t_ramp=0.005,
              distance_sigmas=8.0, n_save=4001, contact=CONTACT, tail_m=None,
              distance_m=None):
    """Rolling at `speed` under the condition's load (rim z free with the load force, y/camber/steer
    held), slip angle stepped 0 -> alpha_deg (SAE) by a half-cosine over t_ramp. Distance s = V t
    counted from the middle of the ramp. Returns steady F_y, M_z (SAE), the distance to 63 % of the
    steady F_y, the overshoot, and the implied values (k_f sin a, k_m sin a, sigma): `jtire.slip_reading`, its
    steady values over the record's last tail_m metres (None: its last 5 %). The record rolls distance_m
    after the step (None: distance_sigmas relaxation lengths)."""
    grp = "lateral_ring" if lateral == "ring" else "lateral_reduced"
    m = _model(d, lateral, grp, "slip-angle step", contact)
    d.require("inplane", "slip-angle step")
    eq = vertical_equilibrium(d, d.load_N)
    a_sae = math.radians(alpha_deg)
    rolled = distance_sigmas * d.sigma if distance_m is None else float(distance_m)
    duration = t_step + t_ramp + rolled / speed
    drive = Drive.make(free=("z_a", "theta_a"), rim_force=np.eye(10)[IDX["z_a"]] * -d.load_N, V=speed,
                       alpha_iso=-a_sae, t_alpha=t_step, t_ramp=t_ramp)
    omega = speed / d.r_e
    y0 = _state(z_a=eq["z_a"], z_b=eq["z_b"], v_theta_a=omega, v_theta_b=omega)
    ts = np.linspace(0.0, duration, n_save)
    ys = _check(simulate(m, drive, y0, duration, ts), "slip-angle step")
    out = _np(m.outputs(jnp.asarray(ts), jnp.asarray(ys), drive))
    fy_sae, mz_sae = -out["F_y"], -out["M_z"]
    s = speed * (ts - (t_step + 0.5 * t_ramp))
    q = slip_reading.readings(s, fy_sae, mz_sae, tail_m)
    # reduced model with the lag: the force k_l e + C_l de/dt obeys dF/dt = k_l (V_cy - V F / k_f)
    # exactly, a first-order lag over the distance sigma = k_f / k_l, plus a small jump C_l V_cy at
    # the step (so s63 comes out slightly below sigma); with the string, Pacejka's stretched string
    # (s63 ~ 0.8 sigma, modes.string_step_s63); the ring adds its belt masses
    implied = {"F_y_steady_SAE_N": -d.k_f * math.sin(a_sae), "M_z_steady_SAE_Nm": d.k_m * math.sin(a_sae),
               "sigma_m": d.sigma}
    signals = {"time_s": ts, "distance_m": s, "F_y_SAE_N": fy_sae, "M_z_SAE_Nm": mz_sae,
               "slip_angle_SAE_deg": -np.degrees(out["alpha_iso"])}
    return ScenarioResult("slip_step", q, implied, signals, {"speed_m_s": speed, "alpha_deg": alpha_deg,
                                                             "lateral": lateral, "contact": contact,
                                                             "t_step_s": t_step})
