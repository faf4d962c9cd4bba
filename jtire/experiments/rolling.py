"""E12 rolling resistance on a flat-track machine: the axle stays, the road moves under it.

Sequence (every phase is the shared compiled `solve.run_phase_jit` program, so nothing here
compiles beyond what inflation and loading already did):
  inflate (rim held) -> first contact -> vertical load ramped with rim z free, on a still road
  -> the road starts moving at (-V, 0, 0) with the rim spin free (no drive torque, "dragged") and
     the tire spinning at V / R_est from the first step (`phases.with_spin`: no spin-up)
  -> settle: mass-proportional damping relative to the RIM FRAME (on absolute velocity it would be
     a fake drag on the spinning tire), for `settle_s`
  -> ramp: that damping lowered to zero over `ramp_s` in short constant stages (`release_schedule`:
     switched off at once, it rings the wheel's lightly damped rotational modes)
  -> release: damping off, `release_s`, not measured
  -> measure: damping off, a whole number of segment-passing periods close to `measure_s`.
Axes ISO (x forward, y left, z up): forward rolling is positive spin about +y, the bottom of the
tire moving at -x with the road. `contact_force` is the road's force on the tire, so the drag is
-F_x (positive); the axle feels the opposite force.

Two readings of the rolling resistance (physics notes): the hub force (steady mean of -F_x) and the
lost power over the speed (the model's own losses, smooth: Maxwell branches and tread normal
damping, `dissipated`, plus sliding in the patch, `friction_work`). The hub force is noisy
(polygon effect, the wheel's rotational modes on the tread's shear stiffness): on the default
tire at 38.7-45.4 kN its standard deviation is 45-75 N around a 200-240 N mean, and an 80 ms
mean carries a block standard error of 3-7 N (1.5-3 %).
In steady state the road's power -F_x V equals the rubber's dissipated power plus the friction
(micro-slip) loss in the patch; their relative difference is the energy-balance check. (Before
the friction counter existed the drag exceeded the rubber's P / V alone by +2.4 % at all three
loads: ~30-37 W of slip.)
"""

import dataclasses
import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..config import F
from ..errors import ConfigError
from ..physics.contact import FlatRoad
from . import phases
from .registry import Experiment, register
from .result import ExperimentResult

DOWN = np.array([0.0, 0, -1, 0, 0, 0])
RIM_Z_SPIN = np.array([0.0, 0, 1, 0, 1, 0])  # z free (load held), spin free (no drive torque)
N_BLOCKS = 10  # batch means for the standard error of the hub-force mean


def road_velocity(speed, slip_angle=0.0):
    """(3,) ISO velocity (m/s) of the road under a fixed axle for a wheel travelling at `speed` with
    SAE slip angle `slip_angle` (rad).

    SAE slip angle: positive when the wheel centre travels to the RIGHT of its heading (clockwise
    from the heading seen from above). The wheel's ground velocity is V (cos a, -sin a, 0) in ISO
    (y left), so the road moves at minus that: V (-cos a, +sin a, 0). The tire then slides right
    over the road, friction pushes it left: F_y(ISO) > 0, i.e. F_y(SAE) < 0 for a > 0, the
    SAE-conventional sign (cornering stiffness = -dF_y,SAE / d alpha > 0).
    """
    a = np.asarray(slip_angle, float)
    return np.stack([-speed * np.cos(a), speed * np.sin(a), np.zeros_like(a)], axis=-1)


def rolling_radius_estimate(outer_radius: float, deflection: float) -> float:
    """Initial guess of the effective rolling radius, m: R0 - deflection / 3 (the classic radial
    tire estimate). Only the start spin uses it; the free spin finds the real one during the
    settle stage (default tire at 41.4 kN: 0.4994 m guessed, 0.4933 m found, spin within 0.3 %
    after ~15 ms)."""
    return outer_radius - deflection / 3.0


def segment_period(n_theta: int, omega: float) -> float:
    """Time (s) for one mesh segment to pass the contact patch at spin omega (rad/s): the period
    of the polygon-effect ripple in the hub forces."""
    return 2 * np.pi / (n_theta * abs(omega))


def whole_periods(duration: float, period: float) -> float:
    """`duration` rounded to a whole number (>= 1) of `period`: a uniform-sample mean over it
    cancels the ripple's harmonics exactly (up to the sampling's own aliasing)."""
    return max(1, int(round(duration / period))) * period


def loaded_state(tire, pressure, load, proto, dt):
    """Inflate, touch the road, ramp the load with rim z free, settle. Returns (inf, z_road, ld)
    after checking both phases settled (SimulationError otherwise)."""
    m, prm = tire.model, tire.params
    ns = phases.steps_for(max(float(proto.inflate_max), float(proto.load_ramp + proto.settle_max)), dt)
    inf = phases.inflate(m, prm, pressure, dt, proto, ns)
    solve.check_phase("inflate", inf, m)
    z0 = phases.first_contact_height(m, inf.y)
    ld = phases.load_phase(m, prm, pressure, dt, proto, inf.y, inf.t_end, phases.flat_road(z0), jnp.zeros(6),
                           load * DOWN, phases.RIM_Z, float(proto.load_ramp),
                           float(proto.load_ramp + proto.settle_max), ns)
    solve.check_phase("load", ld, m)
    return inf, z0, ld


def rolling_drive(pressure, dt, proto, load, z_road, road_vel, damping):
    """The drive of a rolling phase: road at z_road moving at road_vel (3,), load held on the rim,
    rim z and spin free, damping (1/s) relative to the rim frame."""
    road = FlatRoad(height=jnp.asarray(z_road, float), velocity=jnp.asarray(road_vel, float))
    return phases.make_drive(pressure, dt, proto, force0=load * DOWN, force1=load * DOWN, rim_free=RIM_Z_SPIN,
                             surface=road, damping=damping, rim_frame=1.0)


def roll(model, params, drive, y0, t0, duration, proto):
    """One rolling phase of `duration` s from t0 (no early stop). Returns (PhaseResult, ts (N_SAVE,))."""
    t0 = jnp.asarray(t0, float)
    t1 = t0 + jnp.asarray(duration, float)
    ts = jnp.linspace(t0, t1, solve.N_SAVE)
    res = solve.run_phase_jit(model, params, drive, y0, t0, t1, ts, jnp.asarray(jnp.inf, float), proto.ke_tol,
                              solve.MAX_STEPS)
    return res, np.asarray(ts)


def block_stderr(y, n_blocks: int = N_BLOCKS) -> float:
    """Standard error of the mean of a correlated series by batch means (n_blocks equal blocks)."""
    y = np.asarray(y, float)
    n = len(y) // n_blocks
    if n < 2:
        raise ConfigError(f"series of {len(y)} samples: need at least {2 * n_blocks} for {n_blocks} blocks")
    means = y[: n * n_blocks].reshape(n_blocks, n).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(n_blocks))


def reduce_rolling(t, fx, fz, dissipated, speed, friction=None):
    """Rolling resistance from one measurement window.

    t, fx, fz, dissipated, friction: (n,) samples at uniform times spanning a whole number of
    ripple periods, endpoint included (s, N, N, J, J; friction None = no sliding loss); speed m/s.
    The hub-force mean uses samples [0, n-1) (uniform over one half-open span of whole periods);
    the lost powers are exact energies over the span, (D[-1] - D[0]) / T. Returns a dict of SI
    quantities.
    """
    t, fx, fz, d_rub = (np.asarray(a, float) for a in (t, fx, fz, dissipated))
    d_fric = np.zeros_like(t) if friction is None else np.asarray(friction, float)
    d = d_rub + d_fric
    drag = signals.steady_mean(t[:-1], -fx[:-1])
    span = t[-1] - t[0]
    p_diss = (d[-1] - d[0]) / span
    p_fric = (d_fric[-1] - d_fric[0]) / span
    half = len(t) // 2
    p1 = (d[half] - d[0]) / (t[half] - t[0])
    p2 = (d[-1] - d[half]) / (t[-1] - t[half])
    f_power = p_diss / speed
    fz_mean = float(fz[:-1].mean())
    diff = drag.mean - f_power
    return {
        "rolling_resistance_N": drag.mean,
        "rrc": drag.mean / fz_mean,
        "rolling_resistance_stderr_N": block_stderr(-fx[:-1]),
        "rolling_resistance_std_N": drag.std,
        "dissipated_power_W": p_diss,  # rubber + sliding
        "rubber_power_W": p_diss - p_fric,
        "friction_power_W": p_fric,
        "rolling_resistance_from_power_N": f_power,
        "rrc_from_power": f_power / fz_mean,
        "energy_balance_rel_diff": diff / f_power if f_power > 0 else None,  # None: nothing dissipated
        "unaccounted_power_W": diff * speed,  # hub-force noise + O(dt) bristle storage
        "dissipated_power_halves_rel_diff": (p2 - p1) / p_diss if p_diss > 0 else 0.0,
        "vertical_force_N": fz_mean,
        "window_s": span,
    }


RAMP_STAGE_S = 0.005  # s per step of the damping ramp: a third of the rim's torsional period (~17 ms),
# so the staircase acts on the lightly damped rotational modes like a smooth ramp
STAGE_CODE = {"settle": 0, "ramp": 1, "release": 2, "measure": 3}


def release_schedule(c0: float, ramp_s: float) -> list:
    """[(damping 1/s, duration s)]: c0 lowered to zero along a smoothstep over ramp_s in steps of
    RAMP_STAGE_S (damping sampled at each step's midpoint). Switching the settling damping off at
    once releases the torque it carried between rim and belt: measured on the default tire, that
    rang the wheel's rotational modes (spin +-0.11 rad/s, hub force +-400 N, decaying over
    ~0.1 s); ramped over 60 ms the spin wobble stayed below 0.006 rad/s."""
    n = int(round(ramp_s / RAMP_STAGE_S)) if ramp_s > 0 else 0
    if n == 0:
        return []
    x = (np.arange(n) + 0.5) / n
    return [(float(c0 * (1 - x_ * x_ * (3 - 2 * x_))), ramp_s / n) for x_ in x]


def rolling_stages(drive_for, roll_fn, y0, t0, c0, settle_s, ramp_s, release_s, measure_s, n_theta, check):
    """settle (damping c0) -> ramp (c0 -> 0) -> release (no damping) -> measure (no damping, whole
    segment-passing periods closest to measure_s).

    drive_for(c) -> Drive (or a batch of them); roll_fn(drive, y, t0, duration) -> (PhaseResult,
    ts); check(name, result) raises on a failed phase. Returns [(stage, PhaseResult, ts)].
    """
    plan = ([("settle", c0, settle_s)] + [("ramp", c, d) for c, d in release_schedule(c0, ramp_s)]
            + ([("release", 0.0, release_s)] if release_s > 0 else []))
    out, y, t = [], y0, t0
    for name, c, d in plan:
        res, ts = roll_fn(drive_for(c), y, t, d)
        check(name, res)
        out.append((name, res, ts))
        y, t = res.y, jnp.ravel(res.t_end)[0]
    omega = float(np.mean(np.asarray(y.qd)[..., 4]))
    res, ts = roll_fn(drive_for(0.0), y, t, whole_periods(measure_s, segment_period(n_theta, omega)))
    check("measure", res)
    return out + [("measure", res, ts)]


def run_rolling(tire, pressure, load, proto, speed, settle_s, ramp_s, release_s, measure_s, params=None,
                loaded=None):
    """The whole E12 sequence at one load; returns (quantities, signals, checks, info).

    params: override tire.params (e.g. `params.without_damping()` for the lossless check).
    loaded: (dt, inf, z_road, ld) from an earlier `loaded_state` with the same params and load, to
    time or repeat the rolling part alone (benchmarks).
    """
    m = tire.model
    prm = tire.params if params is None else params
    t_start = time.perf_counter()
    if loaded is None:
        dt = solve.stable_step(m, prm, pressure, float(proto.settle_damping))
        for v in (settle_s, ramp_s, release_s, measure_s):
            phases.steps_for(v, dt)
        inf, z0, ld = loaded_state(dataclasses.replace(tire, params=prm), pressure, load, proto, dt)
    else:
        dt, inf, z0, ld = loaded
    t_roll = time.perf_counter()
    deflection = -float(ld.y.q[2])
    r_est = rolling_radius_estimate(tire.spec.geometry.outer_radius, deflection)
    road = road_velocity(speed)
    stages = rolling_stages(
        lambda c: rolling_drive(pressure, dt, proto, load, z0, road, c),
        lambda drv, y, t0, d: roll(m, prm, drv, y, t0, d, proto),
        phases.with_spin(m, ld.y, speed / r_est), ld.t_end, float(proto.settle_damping), settle_s, ramp_s,
        release_s, measure_s, m.n_theta, lambda name, res: solve.check_phase(name, res, m, require_settled=False))
    _, ms, ts_m = stages[-1]
    jax.block_until_ready(ms)
    t_end = time.perf_counter()
    s = {k: np.asarray(v) for k, v in ms.saved.items()}
    q = reduce_rolling(ts_m, s["contact_force"][:, 0], s["contact_force"][:, 2], s["dissipated"], speed,
                       s["friction_work"])
    spin = (s["q"][-1, 4] - s["q"][0, 4]) / (ts_m[-1] - ts_m[0])
    q |= {"effective_rolling_radius_m": speed / spin, "spin_rad_per_s": spin, "deflection_m": deflection,
          "speed_m_per_s": speed, "load_N": load}
    checks = {"inflate_settled": bool(inf.settled), "load_settled": bool(ld.settled),
              "vertical_force_vs_load_rel_error": abs(q["vertical_force_N"] - load) / load,
              "drag_drift_relative": signals.steady_mean(ts_m[:-1], -s["contact_force"][:-1, 0]).drift_relative,
              "spin_std_in_measurement_rad_per_s": float(s["qd"][:, 4].std()),
              "settle_work_in_measurement_J": float(s["settle_work"][-1] - s["settle_work"][0])}
    cat = lambda f: np.concatenate([f(r.saved, ts) for _, r, ts in stages])  # noqa: E731
    sig = {
        "time_s": np.concatenate([ts for _, _, ts in stages]),
        "stage": np.concatenate([np.full(len(ts), STAGE_CODE[n]) for n, _, ts in stages]),
        "drag_N": cat(lambda sv, ts: -np.asarray(sv["contact_force"])[:, 0]),
        "vertical_force_N": cat(lambda sv, ts: np.asarray(sv["contact_force"])[:, 2]),
        "contact_moment_y_Nm": cat(lambda sv, ts: np.asarray(sv["contact_moment"])[:, 1]),
        "spin_rad_per_s": cat(lambda sv, ts: np.asarray(sv["qd"])[:, 4]),
        "rim_z_m": cat(lambda sv, ts: np.asarray(sv["q"])[:, 2]),
        "dissipated_J": cat(lambda sv, ts: np.asarray(sv["dissipated"])),
        "friction_work_J": cat(lambda sv, ts: np.asarray(sv["friction_work"])),
        "settle_work_J": cat(lambda sv, ts: np.asarray(sv["settle_work"])),
    }
    steps_roll = sum(int(r.n_steps) for _, r, _ in stages)
    info = {"dt_s": dt, "steps": int(inf.n_steps) + int(ld.n_steps) + steps_roll, "rolling_steps": steps_roll,
            "simulated_s": float(ms.t_end), "rolling_simulated_s": float(ms.t_end - ld.t_end),
            "settle_s": settle_s, "ramp_s": ramp_s, "release_s": release_s, "measure_s": float(ts_m[-1] - ts_m[0]),
            "wall_s_including_compile": t_end - t_start, "wall_s_rolling": t_end - t_roll,
            "start_rolling_radius_m": r_est}
    return q, sig, checks, info


def calibration_target(load, calibration_loads, calibration_targets):
    """The target drag (N) of the calibration load within 0.5 % of `load` (N), or None."""
    if len(calibration_loads) != len(calibration_targets):
        raise ConfigError(f"rolling_resistance.calibration_targets_N: {len(calibration_targets)} values, "
                          f"must match calibration_loads_kN ({len(calibration_loads)})")
    return next((t for L, t in zip(calibration_loads, calibration_targets) if abs(L - load) <= 5e-3 * load), None)


def run_rolling_resistance(tire, condition, proto, speed, settle_s, ramp_s, release_s, measure_s, calibration_loads,
                           calibration_targets):
    """E12 at the condition's load: drag, RRC, dissipated-power check; target error where the load
    is one of the calibration loads (within 0.5 %)."""
    p, load = condition["pressure_Pa"], condition["load_N"]
    calibration_target(load, calibration_loads, calibration_targets)  # validate before simulating
    q, sig, checks, info = run_rolling(tire, p, load, proto, speed, settle_s, ramp_s, release_s, measure_s)
    target = calibration_target(load, calibration_loads, calibration_targets)
    q["target_N"] = target
    q["error_vs_target_rel"] = None if target is None else (q["rolling_resistance_N"] - target) / target
    return ExperimentResult("rolling_resistance", condition, q, signals=sig, checks=checks, info=info)


# Stage lengths (defaults measured on the default tire at 41.4 kN, 15 mph): the dissipated power is
# within 1 % of its final value after 40 ms of damped rolling; the ramp (60 ms) and 20 ms of free
# rolling leave a spin wobble below 0.006 rad/s; 80 ms (~11 segment periods) of measurement then
# give the hub-force mean to a few percent (block standard error reported).
ROLLING_SCHEMA = {
    "speed_mph": F(float, U.MPH, 0.5, 60, 15.0, "mph"),
    "settle_s": F(float, 1, 0.005, 2, 0.04, "s"),
    "ramp_s": F(float, 1, 0.0, 1, 0.06, "s"),
    "release_s": F(float, 1, 0.0, 2, 0.02, "s"),
    "measure_s": F(float, 1, 0.005, 5, 0.08, "s"),
}

register(Experiment(
    "rolling_resistance",
    lambda tire, c, p, speed_mph, settle_s, ramp_s, release_s, measure_s, calibration_loads_kN, calibration_targets_N:
        run_rolling_resistance(tire, c, p, speed_mph, settle_s, ramp_s, release_s, measure_s, calibration_loads_kN,
                               calibration_targets_N),
    ROLLING_SCHEMA | {"calibration_loads_kN": F(list, U.KN, 1, 500, [38.7, 41.4], "kN"),
                      "calibration_targets_N": F(list, 1, 0, 1e5, [1529.39, 1701.11], "N")},
    description="E12 rolling resistance: drag and RRC on a moving flat road, checked against dissipated power"))
