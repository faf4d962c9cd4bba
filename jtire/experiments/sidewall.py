"""Sidewall stiffness and damping with a rigid belt: E05 (in-plane rotation), E07 (lateral
translation), E08 (camber-wise rotation), and the free-decay tools shared with E04 and E09.

Rim locked in all six DOFs, no road (phases.far_road()), the belt (crown part: belt, undertread,
tread) rigid (`physics.rigid_belt`), so only the sidewalls deform. The belt is rigid from the
start, through the inflation too (the study's rigid tread/undertread is a rigid body throughout);
this also makes inflation, hold and release one compiled program, since every phase has the same
drive structure and the same number of saved samples.

    1. inflate with the rim held (settle damping on, checked settled);
    2. hold: ramp the belt load on and settle (the static stiffness k = load / steady motion);
    3. release: ramp the belt load off in `release_ramp` (1 ms: a step for the 25-40 Hz belt
       modes) with the settle damping OFF and record the belt's rigid motion; reduce it with
       jtire.signals.free_decay (two peaks and a damped-sine fit) about the unloaded level,
       C = xi * 2 M omega_n with the experiment's M.

Loads, in the resultant form `Drive.belt_load` takes (force, moment about the belt's mass centre):
    E05: circumferential force F at the belt radius r  -> M_y = F r    (k_btheta = F r / theta_ss)
    E07: F at the top and F at the bottom, same side  -> F_y = 2 F    (k_by = 2 F / y_ss)
    E08: F at the top and F at the bottom, opposite   -> M_x = 2 F r  (k_bgamma = 2 F r / gamma_ss)
r is the belt radius at its centre line (the distance from the axle to the belt where the forces
act; the rigid belt keeps its reference radius, outer radius - tread depth). The load is applied
as its resultant: on a rigid body only the resultant matters, so a point force and a moment give
the same rigid motion. The load does not enter (needs_load = False): the runner never reads it.

Sampling: every decay is saved at solve.N_SAVE (201) samples, the size every other phase uses, so
no decay needs a compilation of its own. Over 0.2 s that is ~35-50 samples per period of the belt
modes; on recorded decays the damping ratio from 201 samples equalled the one from 1601 samples
to 0.1 % (two peaks: parabolic refinement; the fit: all samples).
Internal ISO axes (x forward, y left, z up); stiffnesses and motions are reported as magnitudes.
"""

import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..config import F
from ..physics.rigid_belt import belt_motion
from ..state import TireState
from . import phases
from .result import ExperimentResult

ZERO6 = np.zeros(6)


# ---- free decays (shared with drop.py and static.run_lateral_stiffness) --------------------------
def release_phase(model, params, pressure, dt, proto, y0, t0, road, *, load0, load1, rim_free, ramp,
                  duration, rigid_belt=False, belt=False, gravity=np.zeros(3)):
    """A free-decay phase: loads ramp load0 -> load1 over `ramp` s from t0, settle damping OFF.

    load0/load1: (6,) rim force (belt=False) or belt load (belt=True). Runs the whole `duration`
    (no settle stop) and saves solve.N_SAVE samples from t0 on. Returns (ts (N_SAVE,), PhaseResult).
    """
    t0 = jnp.asarray(t0, float)
    kw = dict(belt_load0=load0, belt_load1=load1) if belt else dict(force0=load0, force1=load1)
    drive = phases.make_drive(pressure, dt, proto, t0=t0, t1=t0 + ramp, rim_free=rim_free, surface=road,
                              damping=0.0, rigid_belt=rigid_belt, gravity=gravity, **kw)
    ts = jnp.linspace(t0, t0 + duration, solve.N_SAVE)
    res = solve.run_phase_jit(model, params, drive, y0, t0, t0 + duration, ts, jnp.asarray(jnp.inf),
                              proto.ke_tol, solve.MAX_STEPS)
    return np.asarray(ts), res


def decay_about_fit(t, x, mass, t_start):
    """free_decay about a level that is not known in advance (friction in the patch may keep the
    rim from returning exactly): the first pass fits the asymptote x_inf, the second measures
    the peaks about it (a tail mean of a still-ringing record would be biased by the phase at
    which the record ends)."""
    first = signals.free_decay(t, x, mass, t_start=t_start)
    return signals.free_decay(t, x, mass, t_start=t_start, x_final=first.x_inf_fit)


def decay_quantities(fd, mass_name: str, c_name: str, c_unit: str) -> dict:
    """Two-peak and fitted damping of a free_decay result as SI-named quantities.

    `c_name` (e.g. "C_by") gets the two-peak value (the study's method) and, when two peaks could
    not be found, the fit's; `<c_name>_2p_<unit>`, `<c_name>_fit_<unit>` carry both.
    """
    c2p, cfit = fd.c_2p, fd.c_fit
    return {
        f"{c_name}_{c_unit}": c2p if fd.two_peak_ok else cfit,
        f"{c_name}_2p_{c_unit}": c2p, f"{c_name}_fit_{c_unit}": cfit,
        "damping_method": "two peaks" if fd.two_peak_ok else "damped-sine fit (no two clear peaks)",
        "xi_2p": fd.xi_2p, "xi_fit": fd.xi_fit, "xi_rel_diff_2p_vs_fit": fd.rel_diff_xi,
        "omega_n_2p_rad_per_s": fd.omega_n_2p, "omega_n_fit_rad_per_s": fd.omega_n_fit,
        "f_d_fit_Hz": fd.omega_d_fit / (2 * np.pi), "log_decrement": fd.delta,
        mass_name: fd.mass, "xi_formula": fd.xi_formula,
    }


def decay_checks(fd, res, prefix="release") -> dict:
    """Validity of a decay: fit quality, enough oscillation, no artificial damping, real loss."""
    s = res.saved
    settle_work = np.asarray(s["settle_work"])
    diss = np.asarray(s["dissipated"])
    return {
        f"{prefix}_two_peak_ok": fd.two_peak_ok, f"{prefix}_two_peak_reason": fd.two_peak_reason,
        f"{prefix}_fit_oscillatory": fd.fit_oscillatory, f"{prefix}_fit_rms_relative": fd.fit_rms_relative,
        f"{prefix}_fit_success": fd.fit_success,
        # the level the decay is measured about agrees with the fit's asymptote (1 % of amplitude)
        f"{prefix}_final_level_matches_fit": fd.tail_settled,
        # the settle damping is off in the release: the artificial work must not grow at all
        f"{prefix}_settle_work_J": float(settle_work[-1] - settle_work[0]),
        f"{prefix}_rubber_dissipated_J": float(diss[-1] - diss[0]),
        f"{prefix}_blew_up": bool(res.blew_up), f"{prefix}_steps": int(res.n_steps),
    }


# ---- rigid-belt phases ---------------------------------------------------------------------------
CASES = {
    # name: (study id, load builder (F, r) -> (6,), signal (saved field, component), k name, c name,
    #        c unit, motion name)
    "inplane_rotation": ("E05", lambda f, r: np.array([0, 0, 0, 0, f * r, 0.0]), ("belt_rot", 1),
                         "k_btheta_Nm_per_rad", "C_btheta", "Nms_per_rad", "theta_ss_rad"),
    "sidewall_translation": ("E07", lambda f, r: np.array([0, 2 * f, 0, 0, 0, 0.0]), ("belt_disp", 1),
                             "k_by_N_per_m", "C_by", "Ns_per_m", "y_ss_m"),
    "sidewall_camber": ("E08", lambda f, r: np.array([0, 0, 0, 2 * f * r, 0, 0.0]), ("belt_rot", 0),
                        "k_bgamma_Nm_per_rad", "C_bgamma", "Nms_per_rad", "gamma_ss_rad"),
}


def _run(model, params, drive, y0, t0, t1, settle_after, proto):
    ts = jnp.linspace(t0, t1, solve.N_SAVE)
    return solve.run_phase_jit(model, params, drive, y0, jnp.asarray(t0), jnp.asarray(t1), ts,
                               jnp.asarray(settle_after), proto.ke_tol, solve.MAX_STEPS)


def inflate_rigid(tire, pressure, proto):
    """Stable step and the inflated, settled state with the belt rigid. Returns (dt, PhaseResult)."""
    model, params = tire.model, tire.params
    dt = solve.stable_step(model, params, pressure, float(proto.settle_damping))
    phases.steps_for(float(proto.inflate_max), dt)
    drive = phases.make_drive(pressure, dt, proto, pressure0=0.0, t0=0.0, t1=proto.inflate_ramp,
                              surface=phases.far_road(), rigid_belt=True, belt_load0=ZERO6, belt_load1=ZERO6)
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    return dt, _run(model, params, drive, y0, 0.0, proto.inflate_max, proto.inflate_ramp, proto)


def hold(tire, pressure, proto, dt, inf, load6):
    """Ramp the belt load 0 -> load6 over proto.load_ramp from the inflated state and settle."""
    phases.steps_for(float(proto.load_ramp + proto.settle_max), dt)
    return phases.load_phase(tire.model, tire.params, pressure, dt, proto, inf.y, inf.t_end, phases.far_road(),
                             ZERO6, ZERO6, phases.RIM_LOCKED, proto.load_ramp, proto.load_ramp + proto.settle_max,
                             solve.MAX_STEPS, rigid_belt=True, belt_load0=ZERO6, belt_load1=load6)


def release(tire, pressure, proto, dt, held, load6, duration, ramp, params=None):
    """Ramp the belt load off (settle damping off) and run `duration` s. Returns (ts, PhaseResult)."""
    phases.steps_for(duration, dt)
    return release_phase(tire.model, tire.params if params is None else params, pressure, dt, proto, held.y,
                         held.t_end, phases.far_road(), load0=load6, load1=ZERO6, rim_free=phases.RIM_LOCKED,
                         ramp=ramp, duration=duration, rigid_belt=True, belt=True)


def belt_pose(model, y):
    """(displacement (3,) m, small rotation (3,) rad) of the belt's rigid motion from the reference."""
    d, r = belt_motion(y.x, model.x_ref, model.node_mass, model.belt_mask)
    return np.asarray(d), np.asarray(r)


def belt_radius(model, y) -> float:
    """Largest distance of a belt node from the axle (the belt's centre line), m."""
    mask = np.asarray(model.belt_mask) > 0
    r = np.hypot(np.asarray(y.x.x) - float(y.q[0]), np.asarray(y.x.z) - float(y.q[2]))
    return float(r[mask].max())


def belt_rigidity_error(model, y_a, y_b) -> float:
    """Largest change (m) of any distance between two belt nodes from state y_a to state y_b."""
    mask = np.asarray(model.belt_mask) > 0

    def pts(y):
        return np.stack([np.asarray(y.x.x)[mask], np.asarray(y.x.y)[mask], np.asarray(y.x.z)[mask]], -1)

    a, b = pts(y_a), pts(y_b)
    da = np.linalg.norm(a[:, None] - a[None], axis=-1)
    db = np.linalg.norm(b[:, None] - b[None], axis=-1)
    return float(np.abs(da - db).max())


def coordinate(case: str, pose) -> float:
    """The case's measured motion (m or rad) from a belt pose (disp, rot)."""
    field, k = CASES[case][2]
    return float(pose[0 if field == "belt_disp" else 1][k])


def run_belt(case, tire, condition, proto, force, decay, release_ramp, mass):
    """E05 / E07 / E08 at condition["pressure_Pa"] (the load is never read). force: N (E05 the
    circumferential force, E07/E08 the force at each of the two points); decay, release_ramp: s;
    mass: M of C_c = 2 M omega_n (kg or kg m^2; <= 0: the model's own rigid-belt value)."""
    sid, build, (field, comp), k_name, c_name, c_unit, x_name = CASES[case]
    p = condition["pressure_Pa"]
    model = tire.model
    w0 = time.perf_counter()
    dt, inf = inflate_rigid(tire, p, proto)
    solve.check_phase("inflate", inf, model)
    r = belt_radius(model, inf.y)
    load6 = build(force, r)
    held = hold(tire, p, proto, dt, inf, load6)
    solve.check_phase("hold", held, model)
    ts, dec = release(tire, p, proto, dt, held, load6, decay, release_ramp)
    jax.block_until_ready(dec)
    wall = time.perf_counter() - w0
    solve.check_phase("release", dec, model, require_settled=False)

    pose0, pose1 = belt_pose(model, inf.y), belt_pose(model, held.y)
    x_ss = coordinate(case, pose1) - coordinate(case, pose0)
    load = float(np.abs(load6).max())
    k = load / abs(x_ss)
    x = np.asarray(dec.saved[field])[:, comp] - coordinate(case, pose0)
    own = _own_inertia(tire, case)
    M = mass if mass > 0 else own
    # the unloaded level is the inflated pose (no friction, no plasticity: the sidewalls return)
    fd = signals.free_decay(ts, x, M, t_start=float(ts[0]) + release_ramp, x_final=0.0)
    q = {k_name: k, x_name: abs(x_ss), ("load_N" if field == "belt_disp" else "moment_Nm"): load,
         "force_N": force, "belt_radius_m": r}
    q |= decay_quantities(fd, "decay_mass_kg" if field == "belt_disp" else "decay_inertia_kgm2", c_name, c_unit)
    other = np.concatenate([pose1[0] - pose0[0], pose1[1] - pose0[1]])
    other[comp + (0 if field == "belt_disp" else 3)] = 0.0
    checks = {"inflate_settled": bool(inf.settled), "hold_settled": bool(held.settled),
              "hold_t_s": float(held.t_end - inf.t_end),
              "cross_motion_max": float(np.abs(other).max()),  # m or rad; ~0 by symmetry
              "belt_rigidity_error_m": belt_rigidity_error(model, inf.y, dec.y),
              "model_belt_mass_kg": float(np.sum(np.asarray(model.node_mass * model.belt_mask))),
              "model_own_mass_or_inertia": own,
              # single-DOF check: the rigid belt's own mass (inertia) x omega_n^2 against the static
              # k; they differ by the sidewalls' share of the motion and viscoelastic stiffening
              "k_from_frequency_own_mass": own * fd.omega_n_fit**2,
              "k_dynamic_vs_static_rel": own * fd.omega_n_fit**2 / k - 1.0}
    checks |= decay_checks(fd, dec)
    sig = {"time_s": ts - ts[0], x_name.replace("_ss", ""): x,
           "rubber_dissipated_J": np.asarray(dec.saved["dissipated"]) - float(np.asarray(dec.saved["dissipated"])[0])}
    info = {"study_id": sid, "dt_s": dt, "steps": int(inf.n_steps + held.n_steps + dec.n_steps),
            "simulated_s": float(dec.t_end), "wall_s_including_compile": wall, "decay_s": decay,
            "release_ramp_s": release_ramp, "decay_samples": int(ts.size),
            "load_applied_as": "resultant on the rigid belt (force, moment about its mass centre)"}
    return ExperimentResult(case, {"pressure_Pa": p}, q, signals=sig, checks=checks, info=info)


def _own_inertia(tire, case):
    """The rigid belt's mass (E07) or inertia about the rim centre's y (E05) or x (E08) axis."""
    m = tire.mesh.masses()
    return {"inplane_rotation": m["belt_Iy_kgm2"], "sidewall_translation": m["belt_kg"],
            "sidewall_camber": m["belt_Ix_kgm2"]}[case]


def _schema(force_kN, force_help, mass_key, mass_default, mass_help):
    return {
        "force_kN": F(float, U.KN, 0.01, 200, force_kN, force_help),
        "decay_s": F(float, 1, 0.02, 2, 0.2, "s of free decay after the release"),
        "release_ramp_ms": F(float, U.MS, 0, 20, 1.0, "ms (0: a step)"),
        mass_key: F(float, 1, 0, 1e4, mass_default, mass_help + " for C_c = 2 M omega_n (0: the model's own)"),
    }


def _runner(case, mass_key):
    def run(tire, condition, proto, force_kN, decay_s, release_ramp_ms, **mass):
        return run_belt(case, tire, condition, proto, force_kN, decay_s, release_ramp_ms, mass[mass_key])
    return run


# imported here, after the helpers above exist: the registry imports drop.py, which imports them
from .registry import Experiment, register  # noqa: E402

for _case, _mk, _sch, _desc in (
        ("inplane_rotation", "inertia_kgm2",
         _schema(15.0, "kN circumferential on the belt", "inertia_kgm2", 17.4026, "kg m^2, I_by,"),
         "E05 in-plane rotational sidewall stiffness and damping (k_btheta, C_btheta), rigid belt"),
        ("sidewall_translation", "mass_kg",
         _schema(2.0, "kN at each of top and bottom (same direction)", "mass_kg", 70.75, "kg, m_b,"),
         "E07 sidewall translational stiffness and damping (k_by, C_by), rigid belt"),
        ("sidewall_camber", "inertia_kgm2",
         _schema(5.0, "kN at each of top and bottom (opposite directions)", "inertia_kgm2", 10.491, "kg m^2, I_bx,"),
         "E08 sidewall camber-wise stiffness and damping (k_bgamma, C_bgamma), rigid belt")):
    register(Experiment(_case, _runner(_case, _mk), _sch, needs_load=False, description=_desc))

__all__ = ["CASES", "run_belt", "inflate_rigid", "hold", "release", "release_phase", "decay_quantities",
           "decay_checks", "belt_pose", "belt_radius", "belt_rigidity_error", "coordinate"]
