"""E03 total dynamic vertical stiffness k_dv: a rolling tire hits a cleat on a drum.

Sequence (every phase on the same surface type, drum + cleat, and one saved-grid length, so the
experiment compiles one program besides the shared inflation):
1. inflate with the rim held (the shared `phases.inflate`);
2. load onto the still drum: rim z free, the condition's load ramped on, settled (checked);
   the cleat waits at the drum's bottom, out of reach;
3. rim z locked where it settled (x, y and the tilts locked too; the spin about the axle free),
   drum at the set surface speed, tire started at the matching spin (`phases.with_spin` with
   R0 - deflection / 3 as a first rolling radius); rolled with settle damping relative to the rim
   frame, which removes the start-up transient without dragging the rolling tire;
4. damping off, the cleat starting `lead_time` ahead of where it first touches the tire; the free
   response after the cleat has left the contact patch is recorded at `sample_rate`.

Axle force: the tire's force on the rim (`tire_on_rim`, saved by `solve.observe`: beads and the
pressure on the rim closure, what a hub dynamometer reads), exact with every node's inertia in it.
The spectra of the drum's force on the tire F_cz and of the belt's vertical displacement are
reported beside it: a mode has one frequency whatever the output, but each output weights the
modes differently (on the default tire F_cz is dominated by a mode near 110 Hz in which the
contact patch works, while the axle force and the belt's mass centre show the belt's vertical
mode).

The spectrum is `spectra.first_mode`: Hann window, zero padding, interpolated peak, and a modal fit.
k_dv = (2 pi f)^2 m_b with f the interpolated spectral peak (the study's FFT peak, a damped
frequency) and, beside it, with the fitted undamped frequency f_n.
"""

import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import solve, spectra
from .. import units as U
from ..config import F
from ..errors import ConfigError
from ..physics import drum as drum_mod
from ..physics import tread
from ..physics.geometry_ops import V
from . import phases
from .result import ExperimentResult
from .static import DOWN

RIM_SPIN = np.array([0.0, 0, 0, 0, 1, 0])  # rim held except its spin about the axle
M_B = 70.75  # kg, the study's belt mass for k_dv = (2 pi f)^2 m_b
CROSS_ALLOWANCE = 0.06  # s: room in the impact phase for the cleat to cross the patch (2a + cleat < 0.8 m at 50 km/h)


def contact_extent(model, y, surface, t=0.0, n_fine: int = 24):
    """x-range (x_min, x_max) and y-width (m) of the tread surface inside `surface` at time t.

    The tread surface is sampled exactly as `static.footprint` samples it (a periodic cubic
    spline around the circumference, linear across the tread columns, n_fine samples per
    interval), so patches on a drum and on the flat road compare like for like; a sample is in
    contact where the partner's gap is negative. Returns (nan, nan, 0) when nothing touches.
    """
    from scipy.interpolate import CubicSpline

    X = model.assemble(y.x, y.q)
    n_tread, T = len(model.tread_cols_t), model.n_theta
    p = tread.tread_points(X, model.tread_cols, model.tread_depth, 1, model.normal_sign)
    p = np.stack([np.asarray(p.x), np.asarray(p.y), np.asarray(p.z)], -1).reshape(T, n_tread, 3)
    fine = np.linspace(0, T, T * n_fine, endpoint=False)
    P = CubicSpline(np.arange(T + 1), np.concatenate([p, p[:1]], axis=0), axis=0, bc_type="periodic")(fine)
    v = np.linspace(0, 1, n_fine)[None, None, :, None]
    S = ((1 - v) * P[:, :-1, None] + v * P[:, 1:, None]).reshape(-1, 3)
    gap = np.asarray(surface.query(V(*(jnp.asarray(S[:, k]) for k in range(3))), t)[0])
    inside = gap < 0
    if not inside.any():
        return float("nan"), float("nan"), 0.0
    pts = S[inside]
    return float(pts[:, 0].min()), float(pts[:, 0].max()), float(pts[:, 1].max() - pts[:, 1].min())


def run_phase(tire, drive, y0, t0, duration, n_save, settle_after=math.inf, ke_tol=1.0):
    """One phase on this experiment's saved grid (n_save samples over [t0, t0 + duration])."""
    ts = jnp.linspace(t0, t0 + duration, n_save)
    return solve.run_phase_jit(tire.model, tire.params, drive, y0, jnp.asarray(float(t0)),
                               jnp.asarray(float(t0 + duration)), ts, jnp.asarray(float(settle_after)),
                               jnp.asarray(float(ke_tol)), solve.MAX_STEPS)


def load_on(tire, pressure, load, dt, proto, y_inf, t0, surface, n_save):
    """Rim z free, vertical load ramped onto `surface` (a still partner) and settled (checked)."""
    ramp, hold = float(proto.load_ramp), float(proto.settle_max)
    drv = phases.make_drive(pressure, dt, proto, force0=np.zeros(6), force1=load * DOWN, t0=t0, t1=t0 + ramp,
                            rim_free=phases.RIM_Z, surface=surface)
    res = run_phase(tire, drv, y_inf, t0, ramp + hold, n_save, t0 + ramp, float(proto.ke_tol))
    solve.check_phase("load", res, tire.model, require_settled=True)
    return res


def spin_increment(y, d_omega):
    """State y with the whole wheel (rim and nodes) spun d_omega (rad/s) faster about the axle,
    a rigid increment: it adds no deformation rate, so a new wheel speed starts without a jolt."""
    from ..physics import rim

    dq = jnp.zeros(6).at[4].set(d_omega)
    return eqx.tree_at(lambda s: (s.qd, s.v), y, (y.qd + dq, y.v + rim.frame_velocity(y.q, dq, y.x)))


def _saved_np(res, key):
    return np.asarray(res.saved[key])


def run_drum_cleat(tire, condition, proto, drum_diameter_m, speed_kmh, cleat_diameter_mm, cleat_height_mm,
                   roll_settle_s, lead_time_s, record_s, sample_rate_Hz, f_band_Hz, pad_resolution_Hz):
    """E03 at one condition. Lengths in m, speed m/s, times s, rates Hz (SI from the config).

    Signals (n_save samples at sample_rate over the impact phase): time_s from the cleat's first
    touch (estimated from the loaded patch, see `reach` below), axle_force_N, contact_force_z_N,
    belt_disp_z_m (belt mass centre), spin_rad_s (wheel). The spectrum starts where the cleat
    has left the patch (info t_cleat_leave_s).
    """
    p, load = condition["pressure_Pa"], condition["load_N"]
    R_d, V_s = drum_diameter_m / 2, speed_kmh
    r_c, h_c = cleat_diameter_mm / 2, cleat_height_mm
    if h_c > 2 * r_c:
        raise ConfigError(f"drum_cleat.cleat_height_mm = {h_c * 1e3:g}: must be in (0, cleat_diameter_mm = {2 * r_c * 1e3:g}]")
    if len(f_band_Hz) != 2 or not (0 <= f_band_Hz[0] < f_band_Hz[1] <= sample_rate_Hz / 2):
        raise ConfigError(f"drum_cleat.f_band_Hz = {list(f_band_Hz)}: must be [lo, hi] with 0 <= lo < hi <= sample_rate_Hz / 2")
    lo, hi = (float(v) for v in f_band_Hz)
    omega_d = V_s / R_d
    t_imp = lead_time_s + CROSS_ALLOWANCE + record_s
    if omega_d * (roll_settle_s + t_imp) > 2 * math.pi - 1.0:
        raise ConfigError(f"drum_cleat.roll_settle_s + record_s = {roll_settle_s + record_s:g} s: the cleat would come "
                          f"round twice; keep the rolling shorter than one drum turn ({2 * math.pi / omega_d:.3g} s) less 1.2 rad")
    n_save = int(round(t_imp * sample_rate_Hz)) + 1
    model, params = tire.model, tire.params
    dt = solve.stable_step(model, params, p, float(proto.settle_damping))
    wall0 = time.perf_counter()

    inf = phases.inflate(model, params, p, dt, proto, solve.MAX_STEPS)
    solve.check_phase("inflate", inf, model, require_settled=True)
    z_top = float(phases.first_contact_height(model, inf.y))
    R0 = -z_top  # inflated outer radius (rim centre at the origin)
    still = drum_mod.drum(R_d, z_top, 0.0)
    t = float(inf.t_end)
    ld = load_on(tire, p, load, dt, proto, inf.y, t, drum_mod.drum_with_cleat(still, r_c, h_c, math.pi), n_save)
    t = float(ld.t_end)
    defl = -float(ld.y.q[2])
    x_rear, x_front, _ = contact_extent(model, ld.y, still)
    a = 0.5 * (x_front - x_rear)

    # where the cleat first and last touches the tire: the tread leaves the drum as a parabola of
    # relative curvature 1/R0 + 1/R_d, so a cleat of height h reaches it sqrt(2 h / k) beyond the
    # patch edge, plus the cleat's own half chord
    reach = math.sqrt(2 * h_c / (1 / R0 + 1 / R_d)) + drum_mod.cleat_half_chord(r_c, h_c)
    orbit = R_d + h_c - r_c
    phi_touch = math.asin(min((x_front + reach) / orbit, 1.0))
    phi_leave = math.asin(max((x_rear - reach) / orbit, -1.0))
    phi_imp = phi_touch + omega_d * lead_time_s  # cleat angle at the start of the impact phase
    rolling = drum_mod.drum(R_d, z_top, V_s)
    omega_w = V_s / (R0 - defl / 3)
    f_rim = load * DOWN
    # 3. roll with settle damping relative to the rim frame, the cleat far ahead on the drum
    roll_surf = drum_mod.drum_with_cleat(rolling, r_c, h_c, phi_imp + omega_d * roll_settle_s, t)
    drv = phases.make_drive(p, dt, proto, force0=f_rim, force1=f_rim, rim_free=RIM_SPIN, surface=roll_surf,
                            damping=proto.settle_damping, rim_frame=1.0)
    roll = run_phase(tire, drv, phases.with_spin(model, ld.y, omega_w), t, roll_settle_s, n_save)
    solve.check_phase("roll", roll, model, require_settled=False)
    t = float(roll.t_end)
    # 4. impact, no artificial damping
    imp_surf = drum_mod.drum_with_cleat(rolling, r_c, h_c, phi_imp, t)
    drv = phases.make_drive(p, dt, proto, force0=f_rim, force1=f_rim, rim_free=RIM_SPIN, surface=imp_surf,
                            damping=0.0, rim_frame=1.0)
    imp = jax.block_until_ready(run_phase(tire, drv, roll.y, t, t_imp, n_save))
    solve.check_phase("impact", imp, model, require_settled=False)
    wall = time.perf_counter() - wall0

    ts = np.linspace(t, t + t_imp, n_save)
    t_touch, t_leave = t + lead_time_s, t + (phi_imp - phi_leave) / omega_d
    fc = _saved_np(imp, "contact_force")[:, 2]
    bz = _saved_np(imp, "belt_disp")[:, 2]
    f_axle = _saved_np(imp, "tire_on_rim")[:, 2]
    spin = _saved_np(imp, "qd")[:, 4]
    band = (lo, hi)
    sp = spectra.first_mode(ts, f_axle, f_band=band, pad_to_resolution=pad_resolution_Hz, t_start=t_leave)
    sp_c = spectra.first_mode(ts, fc, f_band=band, pad_to_resolution=pad_resolution_Hz, t_start=t_leave)
    sp_b = spectra.first_mode(ts, bz, f_band=band, pad_to_resolution=pad_resolution_Hz, t_start=t_leave, fit=False)
    f1 = sp.f_peak_Hz
    pre = ts < t_touch
    roll_spin = _saved_np(roll, "qd")[:, 4]
    q = {"first_mode_Hz": f1, "k_dv_N_per_m": (2 * math.pi * f1) ** 2 * M_B,
         "first_mode_fit_fn_Hz": sp.fn_fit_Hz, "k_dv_fit_N_per_m": (2 * math.pi * sp.fn_fit_Hz) ** 2 * M_B,
         "first_mode_fit_fd_Hz": sp.f_fit_Hz, "first_mode_xi": sp.xi_fit,
         "first_mode_contact_force_Hz": sp_c.f_peak_Hz, "first_mode_contact_force_fit_fn_Hz": sp_c.fn_fit_Hz,
         "first_mode_belt_displacement_Hz": sp_b.f_peak_Hz,
         "raw_resolution_Hz": sp.raw_resolution_Hz, "padded_resolution_Hz": sp.padded_resolution_Hz,
         "m_b_kg": M_B, "deflection_m": defl, "contact_half_length_on_drum_m": a,
         "peak_axle_force_N": float(np.max(f_axle)), "static_axle_force_N": float(np.mean(f_axle[pre]))}
    checks = {"inflate_settled": bool(inf.settled), "load_settled": bool(ld.settled),
              "load_contact_vs_load_rel_error": abs(float(_saved_np(ld, "contact_force")[_last(ld), 2]) - load) / load,
              "spectrum_peak_at_band_edge": sp.peak_at_band_edge, "fit_rms_relative": sp.fit_rms_relative,
              "fit_vs_peak_rel_diff": sp.rel_diff_f,
              "contact_vs_axle_mode_rel_diff": (sp_c.f_peak_Hz - f1) / f1,
              "belt_vs_axle_mode_rel_diff": (sp_b.f_peak_Hz - f1) / f1,
              "roll_spin_end_rad_s": float(roll_spin[-1]),
              "roll_spin_drift_last_quarter_rel": float(np.ptp(roll_spin[-n_save // 4:]) / abs(roll_spin[-1])),
              "rolling_radius_from_spin_m": float(V_s / np.mean(spin[pre])),
              "free_samples": sp.n}
    info = {"dt_s": dt, "steps": int(inf.n_steps + ld.n_steps + roll.n_steps + imp.n_steps),
            "simulated_s": float(imp.t_end), "wall_s_including_compile": wall,
            "axle_force": "tire_on_rim z: the tire's force on the rim (beads and rim closure pressure)",
            "drum_radius_m": R_d, "surface_speed_m_s": V_s,
            "cleat_radius_m": r_c, "cleat_height_m": h_c, "cleat_height_note": "not given by the study: a config choice",
            "t_cleat_touch_s": t_touch, "t_cleat_leave_s": t_leave, "spectrum_from_s": t_leave,
            "sample_rate_Hz": sample_rate_Hz, "f_band_Hz": [lo, hi], "initial_spin_rad_s": omega_w,
            "spectrum": sp.as_dict(), "spectrum_contact_force": sp_c.as_dict()}
    sig = {"time_s": ts - t_touch, "axle_force_N": f_axle, "contact_force_z_N": fc,
           "belt_disp_z_m": bz, "spin_rad_s": spin}
    return ExperimentResult("drum_cleat", condition, q, signals=sig, checks=checks, info=info)


def _last(res):
    ok = np.isfinite(np.asarray(res.saved["ke"]))
    return int(np.nonzero(ok)[0][-1])


SCHEMA = {
    "drum_diameter_m": F(float, 1, 0.3, 20, 2.5, "m"),
    "speed_kmh": F(float, U.KMH, 1, 150, 50.0, "km/h"),
    "cleat_diameter_mm": F(float, U.MM, 5, 1000, 200.0, "mm"),
    "cleat_height_mm": F(float, U.MM, 1, 1000, 20.0, "mm (above the drum surface; the study gives none)"),
    "roll_settle_s": F(float, 1, 0.005, 1.0, 0.06, "s"),
    "lead_time_s": F(float, 1, 0.0, 0.1, 0.005, "s"),
    "record_s": F(float, 1, 0.05, 1.0, 0.3, "s"),
    "sample_rate_Hz": F(float, 1, 500, 20000, 4000.0, "Hz"),
    "f_band_Hz": F(list, 1, 0, 10000, [20.0, 200.0], "Hz"),
    "pad_resolution_Hz": F(float, 1, 1e-4, 0.2, 0.01, "Hz"),
}

# imported last: the registry imports this module (and its siblings) when it loads, so by then
# every name above must exist
from .registry import Experiment, register  # noqa: E402

register(Experiment("drum_cleat", lambda tire, c, p, **kw: run_drum_cleat(tire, c, p, **kw), SCHEMA,
                    description="E03 drum-cleat: first in-plane mode and k_dv"))
