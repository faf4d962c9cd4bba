"""Static experiments on a flat rigid road: E01 footprint, E02 vertical stiffness, E09 lateral.

Each is one jitted program (inflate -> first contact -> load ramp -> settle [-> lateral ramp ->
settle]) with conditions as array arguments, so a load or pressure sweep vmaps over it and
compiles once. Reductions run on the host afterwards (jtire.signals). Signs: internal ISO axes (z
up); deflections and stiffnesses are reported as positive magnitudes.
"""

import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from ..physics import tread
from . import phases
from .result import ExperimentResult

DOWN = np.array([0.0, 0, -1, 0, 0, 0])
LEFT = np.array([0.0, 1, 0, 0, 0, 0])


def _loaded(model, params, pressure, load, dt, proto, ramp, hold, max_steps: int):
    """Inflate, touch the road, ramp the vertical load to `load` over `ramp` s, settle."""
    inf = phases.inflate(model, params, pressure, dt, proto, max_steps)
    z0 = phases.first_contact_height(model, inf.y)
    road = phases.flat_road(z0)
    ld = phases.load_phase(model, params, pressure, dt, proto, inf.y, inf.t_end, road, jnp.zeros(6),
                           load * DOWN, phases.RIM_Z, ramp, ramp + hold, max_steps)
    return inf, z0, ld


def footprint(model, y, z_road, n_fine: int = 24):
    """Contact patch length (x) and width (y), m, and area (m^2) of state y on the road z = z_road.

    Each circumferential line of tread points is interpolated by a periodic cubic spline (the
    belt is smooth between nodes; linear interpolation would snap the patch ends towards the
    nodes on a coarse ring), then linearly across the tread columns; the in-contact region is
    where that surface lies below the road, so the patch edges are resolved between nodes.
    """
    from scipy.interpolate import CubicSpline

    X = model.assemble(y.x, y.q)
    n_tread = len(model.tread_cols_t)
    T = model.n_theta
    p = tread.tread_points(X, model.tread_cols, model.tread_depth, 1, model.normal_sign)
    p = np.stack([np.asarray(p.x), np.asarray(p.y), np.asarray(p.z)], -1).reshape(T, n_tread, 3)
    k = np.arange(T + 1)
    fine = np.linspace(0, T, T * n_fine, endpoint=False)
    closed = np.concatenate([p, p[:1]], axis=0)
    P = CubicSpline(k, closed, axis=0, bc_type="periodic")(fine)  # (T n_fine, n_tread, 3)
    v = np.linspace(0, 1, n_fine)[None, None, :, None]
    S = (1 - v) * P[:, :-1, None] + v * P[:, 1:, None]  # (T n_fine, n_tread - 1, n_fine, 3)
    inside = S[..., 2] < float(z_road)
    if not inside.any():
        return 0.0, 0.0, 0.0
    pts = S[inside]
    length = float(pts[:, 0].max() - pts[:, 0].min())
    width = float(pts[:, 1].max() - pts[:, 1].min())
    # area: each sample stands for 1 / n_fine of its column gap and one fine circumferential step
    du = np.roll(S, -1, axis=0) - S
    dv = (P[:, 1:] - P[:, :-1])[:, :, None, :]
    cell = np.linalg.norm(np.cross(du, dv), axis=-1) / n_fine
    area = float((cell * inside).sum())
    return length, width, area


def _phase_checks(model, name, res, require=True):
    solve.check_phase(name, res, model, require_settled=require)
    return {f"{name}_settled": bool(res.settled), f"{name}_t_end_s": float(res.t_end),
            f"{name}_kinetic_energy_J": float(solve.kinetic_energy(model, res.y)), f"{name}_steps": int(res.n_steps)}


def _setup(tire, pressure, proto, extra_time):
    """Stable step and one static loop size for every phase of the experiment."""
    dt = solve.stable_step(tire.model, tire.params, pressure, float(proto.settle_damping))
    longest = max(float(proto.inflate_max), float(extra_time))
    return dt, phases.steps_for(longest, dt)


def _contact_check(res, load):
    """Vertical contact force vs applied load at the settled state (relative error)."""
    fz = float(np.asarray(res.saved["contact_force"])[_last(res), 2])
    return fz, abs(fz - load) / load


def _last(res):
    t = np.asarray(res.saved["ke"])
    ok = np.isfinite(t)
    return int(np.nonzero(ok)[0][-1])


def run_footprint(tire, condition, proto):
    """E01: contact length 2a and width w under the condition's load (settled)."""
    p, load = condition["pressure_Pa"], condition["load_N"]
    dt, ns = _setup(tire, p, proto, float(proto.load_ramp + proto.settle_max))
    t0 = time.perf_counter()
    inf, z0, ld = jax.block_until_ready(_loaded(tire.model, tire.params, p, load, dt, proto, float(proto.load_ramp),
                                                float(proto.settle_max), ns))
    return reduce_footprint(tire, condition, inf, z0, ld, dt, time.perf_counter() - t0)


def reduce_footprint(tire, condition, inf, z0, ld, dt, wall):
    """Host reduction of a loaded, settled state to the E01 quantities (shared with sweeps)."""
    load = condition["load_N"]
    checks = _phase_checks(tire.model, "inflate", inf) | _phase_checks(tire.model, "load", ld)
    length, width, area = footprint(tire.model, ld.y, z0)
    deflection = -float(ld.y.q[2])
    fz, err = _contact_check(ld, load)
    fy = float(np.asarray(ld.saved["contact_force"])[_last(ld), 1])
    checks |= {"contact_force_N": fz, "contact_vs_load_rel_error": err, "contact_lateral_force_N": fy}
    R = tire.spec.geometry.outer_radius
    chord = 2 * np.sqrt(max(R**2 - (R - deflection) ** 2, 0.0))
    ref = tire.spec.reference
    q = {"contact_length_m": length, "contact_width_m": width, "contact_half_length_m": length / 2,
         "contact_area_m2": area, "deflection_m": deflection, "k_secant_N_per_m": load / deflection,
         "geometric_chord_m": chord,
         "measured_contact_length_m": ref["footprint_length_mm"] or None,
         "measured_contact_width_m": ref["footprint_width_mm"] or None}
    return ExperimentResult("footprint", condition, q, checks=checks, info=_info(dt, wall, inf, ld))


def _info(dt, wall, *phases_):
    steps = sum(int(r.n_steps) for r in phases_)
    t_sim = float(phases_[-1].t_end)
    return {"dt_s": dt, "steps": steps, "simulated_s": t_sim, "wall_s_including_compile": wall}


def run_vertical_stiffness(tire, condition, proto, max_load, stated_load, ramp, fit_range):
    """E02: quasi-static vertical load ramp 0 -> max_load; k_sv secant at `stated_load` and the
    slope of a linear fit of load against deflection over `fit_range` (N)."""
    p = condition["pressure_Pa"]
    dt, ns = _setup(tire, p, proto, float(ramp + proto.settle_max))
    t0 = time.perf_counter()
    inf, z0, ld = jax.block_until_ready(_loaded(tire.model, tire.params, p, max_load, dt, proto, ramp,
                                                float(proto.settle_max), ns))
    return reduce_vertical(tire, condition, proto, inf, ld, max_load, stated_load, ramp, fit_range, dt,
                           time.perf_counter() - t0)


def reduce_vertical(tire, condition, proto, inf, ld, max_load, stated_load, ramp, fit_range, dt, wall):
    """Host reduction of the E02 ramp (shared with sweeps)."""
    checks = _phase_checks(tire.model, "inflate", inf) | _phase_checks(tire.model, "load", ld)
    s = ld.saved
    t = np.asarray(jnp.linspace(inf.t_end, inf.t_end + ramp + proto.settle_max, solve.N_SAVE))
    valid = np.isfinite(np.asarray(s["ke"]))
    in_ramp = valid & (t <= float(inf.t_end) + ramp)
    defl = -np.asarray(s["q"])[:, 2]
    load = -np.asarray(s["rim_force"])[:, 2]
    fz = np.asarray(s["contact_force"])[:, 2]
    d_r, l_r, f_r = defl[in_ramp], load[in_ramp], fz[in_ramp]
    sec = signals.secant(d_r, l_r, stated_load, along="y")
    mask = (l_r >= fit_range[0]) & (l_r <= fit_range[1])
    fit = signals.linear_slope(d_r[mask], l_r[mask])
    end = _last(ld)
    d_static, l_static = defl[end], load[end]
    d_ramp_at_max = float(np.interp(l_static, l_r, d_r))
    upper = l_r > 0.25 * max_load  # the first quarter of a smoothstep ramp is where the rim accelerates
    checks |= {"quasi_static_deflection_rel_error": abs(d_ramp_at_max - d_static) / d_static,
               "contact_vs_load_max_rel_error_in_ramp": float(np.max(np.abs(f_r - l_r)[upper] / l_r[upper]))}
    q = {"k_sv_N_per_m": sec.secant, "k_sv_fit_N_per_m": fit.slope, "deflection_m": sec.x_at,
         "stated_load_N": stated_load, "max_load_N": max_load, "fit_r2": fit.r2,
         "settled_deflection_at_max_load_m": float(d_static)}
    sig = {"time_s": t[in_ramp], "load_N": l_r, "contact_force_N": f_r, "deflection_m": d_r}
    return ExperimentResult("vertical_stiffness", condition, q, signals=sig, checks=checks, info=_info(dt, wall, inf, ld))


def run_lateral_stiffness(tire, condition, proto, lateral_force, decay=0.3, release_ramp=1e-3, mass=111.25):
    """E09: loaded tire, lateral force at the rim centre, settled: k_l = F / y_ss. Then (decay > 0,
    s) the lateral force is ramped off in `release_ramp` s with the settle damping off and the
    rim's lateral free decay gives C_l with M = `mass` (m_wheel, kg; <= 0: the model's wheel mass):
    two peaks and a damped-sine fit (jtire.signals.free_decay) about the fitted final level."""
    from .sidewall import decay_about_fit, decay_checks, decay_quantities, release_phase

    p, load = condition["pressure_Pa"], condition["load_N"]
    dt, ns = _setup(tire, p, proto, float(max(proto.load_ramp + proto.settle_max, decay)))
    t0 = time.perf_counter()
    inf, z0, ld = _loaded(tire.model, tire.params, p, load, dt, proto, float(proto.load_ramp),
                          float(proto.settle_max), ns)
    lat = phases.load_phase(tire.model, tire.params, p, dt, proto, ld.y, ld.t_end, phases.flat_road(z0),
                            load * DOWN, load * DOWN + lateral_force * LEFT, phases.RIM_YZ, float(proto.load_ramp),
                            float(proto.load_ramp + proto.settle_max), ns)
    jax.block_until_ready(lat)
    wall = time.perf_counter() - t0
    checks = (_phase_checks(tire.model, "inflate", inf) | _phase_checks(tire.model, "load", ld)
              | _phase_checks(tire.model, "lateral", lat))
    y_ss = float(lat.y.q[1] - ld.y.q[1])
    fy_contact = float(np.asarray(lat.saved["contact_force"])[_last(lat), 1])
    checks |= {"contact_lateral_force_N": fy_contact,
               "contact_vs_lateral_rel_error": abs(abs(fy_contact) - lateral_force) / lateral_force,
               "vertical_deflection_m": -float(ld.y.q[2])}
    q = {"k_l_N_per_m": lateral_force / abs(y_ss), "lateral_deflection_m": abs(y_ss), "lateral_force_N": lateral_force}
    if decay <= 0:
        return ExperimentResult("lateral_stiffness", condition, q, checks=checks, info=_info(dt, wall, inf, ld, lat))
    # release: the same DOFs as the hold (y, z free), the vertical load stays, damping off
    t1 = time.perf_counter()
    ts, rel = release_phase(tire.model, tire.params, p, dt, proto, lat.y, lat.t_end, phases.flat_road(z0),
                            load0=load * DOWN + lateral_force * LEFT, load1=load * DOWN, rim_free=phases.RIM_YZ,
                            ramp=release_ramp, duration=decay)
    jax.block_until_ready(rel)
    wall += time.perf_counter() - t1
    solve.check_phase("release", rel, tire.model, require_settled=False)
    y = np.asarray(rel.saved["q"])[:, 1] - float(ld.y.q[1])
    M = mass if mass > 0 else float(tire.model.rim_mass + np.sum(np.asarray(tire.model.node_mass)))
    fd = decay_about_fit(ts, y, M, float(ts[0]) + release_ramp)
    q |= decay_quantities(fd, "decay_mass_kg", "C_l", "Ns_per_m")
    checks |= decay_checks(fd, rel) | {
        # friction may keep the rim off its pre-load position; this is how far (m)
        "release_final_level_minus_preload_m": float(fd.x_final),
        "release_contact_lateral_force_end_N": float(np.asarray(rel.saved["contact_force"])[-1, 1])}
    sig = {"time_s": ts - ts[0], "rim_y_m": y, "rim_z_m": np.asarray(rel.saved["q"])[:, 2],
           "contact_force_y_N": np.asarray(rel.saved["contact_force"])[:, 1]}
    info = _info(dt, wall, inf, ld, lat, rel) | {"decay_s": decay, "release_ramp_s": release_ramp,
                                                  "decay_samples": int(ts.size)}
    return ExperimentResult("lateral_stiffness", condition, q, signals=sig, checks=checks, info=info)
