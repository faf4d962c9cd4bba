"""E06 longitudinal tire stiffness k_k and tread stiffness k_cx on a 3.4 m drum.

The study's drum spins freely with its own inertia while a rapidly rising torque or speed drives
the wheel. The simulation state has no drum degree of freedom, so here the slip is imposed
kinematically: the drum is INFINITELY HEAVY (its surface speed is held constant) and the wheel's
spin is prescribed, stepped through a list of slips. The force-slip curve is the same function
as long as each point is steady, which is checked (the drift of the force over its window).

Sequence (one compiled program for all phases after the shared inflation):
1. inflate; 2. load onto the still drum (rim z free, load ramped, settled, checked); the rim
   height is then locked where it settled (x, y and tilts locked throughout);
3. free rolling: drum at `speed`, wheel spin free (started at V / (R0 - deflection / 3)), first
   with settle damping relative to the rim frame, then without damping; the effective rolling
   radius is R_e = V / mean(omega_w) over the second half of the undamped part;
4. for each slip kappa (ascending): wheel spin prescribed at omega_w = (1 + kappa) V / R_e,
   entered by a rigid spin increment of the whole wheel (no deformation-rate jolt), then run
   without damping (an optional damped phase first is off by default: damping relative to the rim
   frame slows the build-up of the belt's torsional deflection, and switching it off re-excites
   the belt's torsional mode, measured); F_x, F_z are the means over the second half.

Definitions: kappa = (omega_w R_e - V_drum) / V_drum (> 0 driving); F_x is the drum's force on
the tire along x (ISO, forward), > 0 when driving. k_k is the slope of F_x against kappa: over
the configured range (default 0-10 %, the study's) and over the linear part of it, where F_x stays
within `linear_tol` of the initial slope line; k_k_N_per_slip is the linear-part slope and the
range used is reported. k_cx = k_k / a with a the static contact half length from E01 on the flat
road (`static.run_footprint`, default) or measured on the drum at the same condition.
"""

import time

import jax
import numpy as np

from .. import signals, solve
from .. import units as U
from ..config import F
from ..errors import ConfigError
from ..physics import drum as drum_mod
from . import phases, static
from .drum_cleat import RIM_SPIN, contact_extent, load_on, run_phase, spin_increment
from .result import ExperimentResult
from .static import DOWN

HALF_LENGTH_SOURCES = ("flat", "drum")


def _window_mean(res, t0, t1, key, comp):
    """Steady mean (signals.steady_mean) of saved[key][:, comp] over the second half of a phase."""
    ts = np.linspace(t0, t1, np.asarray(res.saved["ke"]).shape[0])
    y = np.asarray(res.saved[key])[:, comp]
    return signals.steady_mean(ts, y, (0.5 * (t0 + t1), t1))


def _linear_range(kappa, fx, k0, tol, hi):
    """Largest kappa in [0, hi] up to which every level keeps |F - F(0) - k0 kappa| <= tol |k0 kappa|."""
    f0 = float(np.interp(0.0, kappa, fx))
    top = 0.0
    for k, f in zip(kappa, fx):
        if k <= 0 or k > hi + 1e-12:
            continue
        if abs(f - f0 - k0 * k) <= tol * abs(k0 * k):
            top = k
        else:
            break
    return top


def run_traction(tire, condition, proto, drum_diameter_m, speed_kmh, slips, free_damped_s, free_s, damped_s, measure_s,
                 fit_range, linear_tol, half_length_from):
    """E06 at one condition (SI from the config: m, m/s, s; slips as fractions)."""
    if half_length_from not in HALF_LENGTH_SOURCES:
        raise ConfigError(f"traction.half_length_from = {half_length_from!r}: must be one of {', '.join(HALF_LENGTH_SOURCES)}")
    kap = np.array(sorted(set(float(s) for s in slips)))
    if not (kap.min() < 0 < kap.max() and np.any(kap == 0.0)):
        raise ConfigError("traction.slips_percent: must hold 0 and at least one negative and one positive slip")
    if len(fit_range) != 2 or not fit_range[0] < fit_range[1]:
        raise ConfigError(f"traction.fit_range_percent = {[v * 100 for v in fit_range]}: must be [lo, hi] with lo < hi")
    lo, hi = (float(v) for v in fit_range)
    n_in = int(np.sum((kap >= lo) & (kap <= hi)))
    if n_in < 3:
        raise ConfigError(f"traction.fit_range_percent = {[v * 100 for v in fit_range]}: holds {n_in} of the slips, need at least 3")
    model, params = tire.model, tire.params
    p, load = condition["pressure_Pa"], condition["load_N"]
    R_d, V_s = drum_diameter_m / 2, speed_kmh
    n_save = 301
    dt = solve.stable_step(model, params, p, float(proto.settle_damping))
    wall0 = time.perf_counter()

    inf = phases.inflate(model, params, p, dt, proto, solve.MAX_STEPS)
    solve.check_phase("inflate", inf, model, require_settled=True)
    z_top = float(phases.first_contact_height(model, inf.y))
    R0 = -z_top
    still = drum_mod.drum(R_d, z_top, 0.0)
    ld = load_on(tire, p, load, dt, proto, inf.y, float(inf.t_end), still, n_save)
    defl = -float(ld.y.q[2])
    x_rear, x_front, _ = contact_extent(model, ld.y, still)
    a_drum = 0.5 * (x_front - x_rear)
    rolling = drum_mod.drum(R_d, z_top, V_s)
    f_rim = load * DOWN
    mk = lambda free, vel, damp: phases.make_drive(  # noqa: E731
        p, dt, proto, force0=f_rim, force1=f_rim, rim_free=free, rim_velocity=vel, surface=rolling,
        damping=damp, rim_frame=1.0)
    steps = int(inf.n_steps + ld.n_steps)

    def two_phase(y, t, free, vel, name, damped, dur):
        """Optionally `damped` s with settle damping (rim frame), then `dur` s without."""
        nonlocal steps
        if damped > 0:
            r1 = run_phase(tire, mk(free, vel, proto.settle_damping), y, t, damped, n_save)
            solve.check_phase(f"{name} damped", r1, model, require_settled=False)
            y, t = r1.y, float(r1.t_end)
            steps += int(r1.n_steps)
        r2 = run_phase(tire, mk(free, vel, 0.0), y, t, dur, n_save)
        solve.check_phase(name, r2, model, require_settled=False)
        steps += int(r2.n_steps)
        return r2, t, t + dur

    # 3. free rolling -> effective rolling radius
    omega0 = V_s / (R0 - defl / 3)
    fr, t0, t1 = two_phase(phases.with_spin(model, ld.y, omega0), float(ld.t_end), RIM_SPIN, np.zeros(6), "free",
                           free_damped_s, free_s)
    w_free = _window_mean(fr, t0, t1, "qd", 4)
    R_e = V_s / w_free.mean
    fx_free = _window_mean(fr, t0, t1, "contact_force", 0)
    # 4. slip levels, wheel spin prescribed
    y, t = fr.y, t1
    rows = []
    for k in kap:
        w = (1 + k) * V_s / R_e
        y = spin_increment(y, w - float(y.qd[4]))
        res, t0, t1 = two_phase(y, t, phases.RIM_LOCKED, np.array([0, 0, 0, 0, w, 0.0]), f"slip {k:+.4f}", damped_s,
                               measure_s)
        fx = _window_mean(res, t0, t1, "contact_force", 0)
        fz = _window_mean(res, t0, t1, "contact_force", 2)
        my = _window_mean(res, t0, t1, "contact_moment", 1)
        rows.append((k, w, fx.mean, fx.std, fx.drift_per_s * (fx.t1 - fx.t0), fz.mean, my.mean))
        y, t = res.y, t1
    jax.block_until_ready(y.x.x)
    wall = time.perf_counter() - wall0
    kappa, omega, fx, fx_std, fx_drift, fz, my = (np.array(c) for c in zip(*rows))  # fx_drift: N over the window

    # slopes: central initial slope, its linear range, and the configured range
    i0 = int(np.nonzero(kappa == 0.0)[0][0])
    # check on R_e: free rolling is where the wheel torque vanishes (steady driven levels, My is
    # the contact moment about the axle), interpolated between the levels that bracket it
    j = int(np.clip(np.argmax(my <= 0), 1, my.size - 1))  # first level driving the wheel (My falls with slip)
    w_zero = float(omega[j - 1] - my[j - 1] * (omega[j] - omega[j - 1]) / (my[j] - my[j - 1]))
    k0 = (fx[i0 + 1] - fx[i0 - 1]) / (kappa[i0 + 1] - kappa[i0 - 1])
    top = _linear_range(kappa, fx, k0, linear_tol, hi)
    full = signals.linear_slope(kappa, fx, (lo, hi))
    # the linear part from zero slip; with fewer than three levels in it, the nearest braking
    # level joins (a line through two points has no residual to judge it by)
    lin_hi = max(top, float(kappa[i0 + 1]))
    lin_lo = 0.0 if np.sum((kappa >= 0) & (kappa <= lin_hi)) >= 3 else float(kappa[i0 - 1])
    lin = signals.linear_slope(kappa, fx, (lin_lo, lin_hi))
    fp = None
    if half_length_from == "flat":
        fp = static.run_footprint(tire, condition, proto)
        a = fp.quantities["contact_half_length_m"]
    else:
        a = a_drum
    q = {"k_k_N_per_slip": lin.slope, "k_k_range_lo": lin.x_lo, "k_k_range_hi": lin.x_hi, "k_k_r2": lin.r2,
         "k_k_fit_range_N_per_slip": full.slope, "fit_range_lo": full.x_lo, "fit_range_hi": full.x_hi,
         "fit_range_r2": full.r2, "k_k_initial_N_per_slip": float(k0),
         "k_cx_N_per_m": lin.slope / a, "k_cx_fit_range_N_per_m": full.slope / a,
         "contact_half_length_m": a, "contact_half_length_source": half_length_from,
         "contact_half_length_on_drum_m": a_drum, "effective_rolling_radius_m": R_e,
         "free_rolling_force_x_N": fx_free.mean, "force_x_at_zero_slip_N": float(fx[i0]),
         "max_force_x_N": float(fx.max()), "mean_force_z_N": float(fz.mean()), "deflection_m": defl}
    checks = {"inflate_settled": bool(inf.settled), "load_settled": bool(ld.settled),
              "free_spin_drift_relative": w_free.drift_relative,
              "rolling_radius_zero_torque_m": V_s / w_zero,
              "slip_at_zero_torque": w_zero * R_e / V_s - 1.0,
              "max_force_x_drift_over_window_N": float(np.max(np.abs(fx_drift))),
              "max_force_x_drift_vs_load": float(np.max(np.abs(fx_drift)) / load),
              "force_z_vs_load_max_rel": float(np.max(np.abs(fz - load)) / load)}
    if fp is not None:
        checks |= {f"footprint_{k}": v for k, v in fp.checks.items()}
    info = {"dt_s": dt, "steps": steps, "simulated_s": t, "wall_s_including_compile": wall,
            "drum": "infinitely heavy: surface speed held constant (the state has no drum DOF)",
            "wheel": "spin prescribed per slip level (rim x, y, z and tilts locked at the loaded position)",
            "slip_definition": "kappa = (omega_w R_e - V_drum) / V_drum, R_e from free rolling",
            "drum_radius_m": R_d, "surface_speed_m_s": V_s, "free_rolling_spin_rad_s": w_free.mean,
            "linear_tol": linear_tol, "footprint_wall_s": fp.info["wall_s_including_compile"] if fp else 0.0}
    sig = {"slip": kappa, "wheel_spin_rad_s": omega, "force_x_N": fx, "force_x_std_N": fx_std,
           "force_x_drift_N": fx_drift, "force_z_N": fz, "moment_y_N_m": my}
    return ExperimentResult("traction", condition, q, signals=sig, checks=checks, info=info)


PCT = 0.01
SCHEMA = {
    "drum_diameter_m": F(float, 1, 0.3, 20, 3.4, "m"),
    "speed_kmh": F(float, U.KMH, 1, 150, 36.0, "km/h"),
    "slips_percent": F(list, PCT, -50, 50, [-2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 5.0, 7.5, 10.0], "%"),
    "free_damped_s": F(float, 1, 0.001, 1.0, 0.04, "s"),
    "free_s": F(float, 1, 0.01, 1.0, 0.2, "s"),
    "damped_s": F(float, 1, 0.0, 1.0, 0.0, "s (0: none)"),
    "measure_s": F(float, 1, 0.01, 1.0, 0.2, "s"),
    "fit_range_percent": F(list, PCT, -50, 50, [0.0, 10.0], "%"),
    "linear_tol": F(float, 1, 0.01, 1.0, 0.1, "(relative)"),
    "half_length_from": F(str, default="flat"),
}


def _run(tire, c, p, slips_percent, fit_range_percent, **kw):
    return run_traction(tire, c, p, slips=slips_percent, fit_range=fit_range_percent, **kw)


# imported last: the registry imports this module (and its siblings) when it loads, so by then
# every name above must exist
from .registry import Experiment, register  # noqa: E402

register(Experiment("traction", _run, SCHEMA, description="E06 longitudinal slip stiffness k_k and tread stiffness k_cx"))
