"""E10 cornering and aligning-torque stiffness (k_f, k_m) and E11 relaxation length sigma = k_f / k_l.

The tire is dragged free-rolling (spin free, no drive torque: a truck pusher axle) on the
flat-track machine of `rolling`: the axle stays, the road moves under it at V (-cos a, +sin a, 0)
(ISO axes) for an SAE slip angle a (`rolling.road_velocity`: positive a = the wheel travels to the
right of its heading; the road then pushes the tire to the left, F_y,SAE < 0). The rim's lateral
position, camber and steer are held; z carries the load, the spin is free.

All slip angles run in ONE compiled program: the rolling phase is `jax.vmap`ped over the road
velocities and jitted once (`roll_batch_jit`; a test counts its traces with
`eqx.debug.assert_max_traces`). The sequence per angle is that of E12 (`rolling.rolling_stages`):
settle with damping relative to the rim frame, ramp it to zero, release (not measured), measure
over whole segment-passing periods. All angles start from one loaded state; the lateral deflection
builds up during settle and ramp (measured at 2 deg: ~85 % of the steady force after 0.1 s = 0.67 m
rolled; with the default 0.25 s settle the lateral force drifts by at most ~2 % over the window). The settling damping resists the lateral
deflection that travels through the rim frame, so the force grows by a few percent during the ramp:
only the undamped window is measured.
On a 2-core CPU vmap gives no speed-up over a loop (physics notes); it compiles one program for the
whole sweep and runs it in parallel on an accelerator.

Reduction (experiments.md), in SAE signs at the boundary (y_SAE = -y, z_SAE = -z):
  lateral force in road axes  F_lat = F_y,SAE cos a - F_x sin a
  aligning moment M_z,SAE = -(contact moment about the vertical through the wheel centre, ISO)
  k_f = -d F_lat / d a over `kf_range` (default 0-2 deg), positive (SAE cornering stiffness)
  k_m = d M_z,SAE / d a over `km_range` (default 0-3 deg), positive for an aligning moment.
"""

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..config import F
from ..errors import ConfigError
from . import phases, rolling, static
from .registry import Experiment, register
from .result import ExperimentResult


def _roll_batch(model, params, drives, y0s, t0, t1, ts, ke_tol):
    """`solve.run_phase` vmapped over a batch of drives and start states (leading axis)."""
    def one(drive, y0):
        return solve.run_phase(model, params, drive, y0, t0, t1, ts, jnp.asarray(jnp.inf, float), ke_tol,
                               solve.MAX_STEPS)

    return jax.vmap(one)(drives, y0s)


# traces are counted (not limited) so a test can prove that a sweep compiles once
roll_batch_traced = eqx.debug.assert_max_traces(_roll_batch, max_traces=None)
roll_batch_jit = eqx.filter_jit(roll_batch_traced)


def _stack(trees):
    return jax.tree.map(lambda *a: jnp.stack(a), *trees)


def _broadcast(tree, n: int):
    return jax.tree.map(lambda a: jnp.broadcast_to(a, (n,) + jnp.shape(a)), tree)


def _case(tree, i: int):
    return jax.tree.map(lambda a: a[i], tree)


def _roll(model, params, drives, ys, t0, duration, proto):
    t0 = jnp.asarray(t0, float)
    t1 = t0 + jnp.asarray(duration, float)
    ts = jnp.linspace(t0, t1, solve.N_SAVE)
    return roll_batch_jit(model, params, drives, ys, t0, t1, ts, proto.ke_tol), np.asarray(ts)


def _check(name, res, model, angles):
    for i, a in enumerate(angles):
        solve.check_phase(f"{name} (slip angle {np.degrees(a):g} deg)", _case(res, i), model, require_settled=False)


def slip_sweep(tire, pressure, load, proto, speed, slip_angles, settle_s, ramp_s, release_s, measure_s,
               settle_damping):
    """Steady free rolling at every SAE slip angle (rad) of `slip_angles`, vmapped.

    Returns (means: dict of (n,) arrays, F_x, F_y, F_z, M_z in ISO (N, N m) over the measurement
    window, their block standard errors, the lateral drift over the window and the spin; info).
    settle_damping: 1/s, relative to the rim frame (<= 0: the protocol's).
    """
    m, prm = tire.model, tire.params
    angles = np.asarray(slip_angles, float)
    n = len(angles)
    if n < 1:
        raise ConfigError("cornering.slip_angles_deg: must hold at least one angle")
    dt = solve.stable_step(m, prm, pressure, float(proto.settle_damping))
    for v in (settle_s, ramp_s, release_s, measure_s):
        phases.steps_for(v, dt)
    c0 = float(proto.settle_damping) if settle_damping <= 0 else float(settle_damping)
    t_start = time.perf_counter()
    inf, z0, ld = rolling.loaded_state(tire, pressure, load, proto, dt)
    t_roll = time.perf_counter()
    deflection = -float(ld.y.q[2])
    r_est = rolling.rolling_radius_estimate(tire.spec.geometry.outer_radius, deflection)
    vel = rolling.road_velocity(speed, angles)
    stages = rolling.rolling_stages(
        lambda c: _stack([rolling.rolling_drive(pressure, dt, proto, load, z0, v, c) for v in vel]),
        lambda drv, y, t0, d: _roll(m, prm, drv, y, t0, d, proto),
        _broadcast(phases.with_spin(m, ld.y, speed / r_est), n), ld.t_end, c0, settle_s, ramp_s, release_s,
        measure_s, m.n_theta, lambda name, res: _check(name, res, m, angles))
    _, ms, ts = stages[-1]
    jax.block_until_ready(ms)
    t_end = time.perf_counter()
    f = np.asarray(ms.saved["contact_force"])[:, :-1]  # (n, N_SAVE - 1, 3): whole periods, half-open
    mo = np.asarray(ms.saved["contact_moment"])[:, :-1]
    series = {"F_x": f[..., 0], "F_y": f[..., 1], "F_z": f[..., 2], "M_z": mo[..., 2]}
    out = {k: v.mean(axis=1) for k, v in series.items()}
    out |= {f"{k}_stderr": np.array([rolling.block_stderr(row) for row in v]) for k, v in series.items()}
    # steadiness: drift of the lateral force over the window relative to its mean
    # (undefined where the mean vanishes: at 0 deg the mirror-symmetric tire has F_y ~ 1e-11 N)
    out["F_y_drift_rel"] = np.array([signals.steady_mean(ts[:-1], row).drift_relative if abs(row.mean()) > 1.0
                                     else np.nan for row in series["F_y"]])
    q_spin = np.asarray(ms.saved["q"])[:, :, 4]
    out["spin"] = (q_spin[:, -1] - q_spin[:, 0]) / (ts[-1] - ts[0])
    steps = sum(int(np.asarray(r.n_steps)[0]) for _, r, _ in stages)
    info = {"dt_s": dt, "steps": int(inf.n_steps) + int(ld.n_steps) + steps, "rolling_steps_per_angle": steps,
            "simulated_s": float(np.asarray(ms.t_end)[0]), "settle_s": settle_s, "ramp_s": ramp_s,
            "release_s": release_s, "measure_s": float(ts[-1] - ts[0]), "settle_damping_per_s": c0,
            "n_slip_angles": n, "wall_s_including_compile": t_end - t_start, "wall_s_rolling": t_end - t_roll,
            "deflection_m": deflection, "vmapped": True}
    return out, info


def lateral_sae(alpha, fx, fy_iso):
    """Lateral force in road axes, SAE signs: F_y,SAE cos a - F_x sin a (N), F_y,SAE = -F_y,ISO."""
    a = np.asarray(alpha, float)
    return -np.asarray(fy_iso) * np.cos(a) - np.asarray(fx) * np.sin(a)


def reduce_cornering(alpha, fx, fy_iso, mz_iso, kf_range, km_range):
    """k_f (N/rad) and k_m (N m/rad) from steady forces at SAE slip angles alpha (rad): slopes over
    the given (lo, hi) ranges in rad (at least 3 angles each). Returns (quantities, curves)."""
    a = np.asarray(alpha, float)
    lat = lateral_sae(a, fx, fy_iso)
    mz = -np.asarray(mz_iso, float)
    kf = signals.linear_slope(a, lat, kf_range)
    km = signals.linear_slope(a, mz, km_range)
    q = {"k_f_N_per_rad": -kf.slope, "k_m_Nm_per_rad": km.slope, "k_f_fit_r2": kf.r2, "k_m_fit_r2": km.r2,
         "k_f_stderr_N_per_rad": kf.stderr, "k_m_stderr_Nm_per_rad": km.stderr,
         "k_f_range_deg": [float(np.degrees(kf.x_lo)), float(np.degrees(kf.x_hi))],
         "k_m_range_deg": [float(np.degrees(km.x_lo)), float(np.degrees(km.x_hi))],
         "pneumatic_trail_m": km.slope / -kf.slope if kf.slope != 0 else float("nan")}
    return q, {"lateral_force_N": lat, "aligning_moment_Nm": mz}


def _cornering_result(tire, condition, proto, speed, slip_angles, stages, settle_damping, kf_range, km_range, name):
    """stages: (settle_s, ramp_s, release_s, measure_s)."""
    p, load = condition["pressure_Pa"], condition["load_N"]
    means, info = slip_sweep(tire, p, load, proto, speed, slip_angles, *stages, settle_damping)
    a = np.asarray(slip_angles, float)
    q, curves = reduce_cornering(a, means["F_x"], means["F_y"], means["M_z"], kf_range, km_range)
    lat_err = np.hypot(means["F_y_stderr"] * np.cos(a), means["F_x_stderr"] * np.sin(a))
    q |= {"peak_lateral_force_N": float(np.max(np.abs(curves["lateral_force_N"]))),
          "peak_lateral_force_over_load": float(np.max(np.abs(curves["lateral_force_N"]))) / load,
          "speed_m_per_s": speed, "load_N": load}
    sig = {"slip_angle_deg": np.degrees(a), "lateral_force_N": curves["lateral_force_N"],
           "lateral_force_stderr_N": lat_err, "F_x_N": means["F_x"], "F_y_SAE_N": -means["F_y"],
           "M_z_SAE_Nm": curves["aligning_moment_Nm"], "M_z_stderr_Nm": means["M_z_stderr"],
           "F_z_N": means["F_z"], "spin_rad_per_s": means["spin"], "F_y_drift_rel": means["F_y_drift_rel"]}
    drift = np.abs(means["F_y_drift_rel"])
    checks = {"max_vertical_force_vs_load_rel_error": float(np.max(np.abs(means["F_z"] - load)) / load),
              "max_lateral_drift_rel_over_window": float(np.nanmax(drift)) if np.any(np.isfinite(drift)) else 0.0}
    return ExperimentResult(name, condition, q, signals=sig, checks=checks, info=info)


def run_cornering(tire, condition, proto, speed, slip_angles, stages, settle_damping, kf_range, km_range):
    """E10: the slip-angle sweep, k_f, k_m and the full curves. stages: (settle_s, ramp_s,
    release_s, measure_s)."""
    return _cornering_result(tire, condition, proto, speed, slip_angles, stages, settle_damping, kf_range, km_range,
                             "cornering")


def run_relaxation_length(tire, condition, proto, speed, slip_angles, stages, settle_damping, kf_range,
                          lateral_force):
    """E11: sigma = k_f / k_l, k_f from a small-angle sweep (E10's reduction), k_l from the static
    E09 (`static.run_lateral_stiffness`, force `lateral_force` N) at the same condition."""
    kf_res = _cornering_result(tire, condition, proto, speed, slip_angles, stages, settle_damping, kf_range,
                               kf_range, "relaxation_length")
    # k_l only: the free decay that gives C_l (decay > 0) is not needed here
    kl_res = static.run_lateral_stiffness(tire, condition, proto, lateral_force, decay=0.0)
    k_f, k_l = kf_res.quantities["k_f_N_per_rad"], kl_res.quantities["k_l_N_per_m"]
    q = {"sigma_m": k_f / k_l, "k_f_N_per_rad": k_f, "k_l_N_per_m": k_l, "k_f_fit_r2": kf_res.quantities["k_f_fit_r2"],
         "k_f_range_deg": kf_res.quantities["k_f_range_deg"], "lateral_force_N": lateral_force,
         "lateral_deflection_m": kl_res.quantities["lateral_deflection_m"]}
    checks = kf_res.checks | {f"lateral_{k}": v for k, v in kl_res.checks.items()}
    info = kf_res.info | {"lateral_stiffness_wall_s": kl_res.info["wall_s_including_compile"]}
    return ExperimentResult("relaxation_length", condition, q, signals=kf_res.signals, checks=checks, info=info)


def _range(name, r):
    if len(r) != 2 or not r[0] < r[1]:
        raise ConfigError(f"{name} = {[float(np.degrees(v)) for v in r]}: must be [lo, hi] deg with lo < hi")
    return r


def _stages(kw):
    return tuple(kw.pop(k) for k in ("settle_s", "ramp_s", "release_s", "measure_s"))


def _cornering_runner(tire, c, p, **kw):
    kf = _range("cornering.kf_range_deg", kw.pop("kf_range_deg"))
    km = _range("cornering.km_range_deg", kw.pop("km_range_deg"))
    return run_cornering(tire, c, p, kw.pop("speed_mph"), kw.pop("slip_angles_deg"), _stages(kw),
                         kw.pop("settle_damping_per_s"), kf, km)


def _relaxation_runner(tire, c, p, **kw):
    kf = _range("relaxation_length.kf_range_deg", kw.pop("kf_range_deg"))
    return run_relaxation_length(tire, c, p, kw.pop("speed_mph"), kw.pop("slip_angles_deg"), _stages(kw),
                                 kw.pop("settle_damping_per_s"), kf, kw.pop("lateral_force_kN"))


# The lateral deflection builds up over a rolled distance of a few relaxation lengths (~0.5 m
# expected for this tire): the settle stage is therefore longer than E12's; ramp and release as
# E12 (`rolling.ROLLING_SCHEMA`, not referenced here: the registry imports both modules while
# `rolling` is still initializing).
_COMMON = {
    "speed_mph": F(float, U.MPH, 0.5, 60, 15.0, "mph"),
    "settle_s": F(float, 1, 0.005, 5, 0.25, "s"),
    "ramp_s": F(float, 1, 0.0, 1, 0.06, "s"),
    "release_s": F(float, 1, 0.0, 2, 0.03, "s"),
    "measure_s": F(float, 1, 0.005, 5, 0.05, "s"),
    "settle_damping_per_s": F(float, 1, 0, 1e4, 0.0, "1/s (0: the solver's settle damping)"),
}

register(Experiment(
    "cornering", _cornering_runner,
    _COMMON | {"slip_angles_deg": F(list, U.DEG, -30, 30, [0, 1, 2, 3, 4, 6, 8, 10, 12, 20], "deg"),
               "kf_range_deg": F(list, U.DEG, -30, 30, [0.0, 2.0], "deg"),
               "km_range_deg": F(list, U.DEG, -30, 30, [0.0, 3.0], "deg")},
    description="E10 cornering stiffness k_f and aligning-torque stiffness k_m (vmapped slip-angle sweep)"))

register(Experiment(
    "relaxation_length", _relaxation_runner,
    _COMMON | {"slip_angles_deg": F(list, U.DEG, -30, 30, [0, 1, 2], "deg"),
               "kf_range_deg": F(list, U.DEG, -30, 30, [0.0, 2.0], "deg"),
               "lateral_force_kN": F(float, U.KN, 0.01, 100, 5.0, "kN")},
    description="E11 relaxation length sigma = k_f / k_l (E10 small angles + static E09)"))
