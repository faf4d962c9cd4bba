"""E04 Total vertical damping C_tot: the drop test.

    1. inflate with the rim held (settle damping on, checked settled);
    2. the road is placed `drop_height` (20 mm) below the lowest tread point; the vertical load
       acts on the rim as a force (the condition's load, as in E02), the rim is released with only
       its vertical DOF free and the settle damping OFF: the wheel falls, hits the road, bounces
       and rings down on its own damping (the rubber's Maxwell branches and the tread);
    3. the rim's vertical motion from the first contact on is reduced with jtire.signals.free_decay
       (two peaks and a damped-sine fit), M = m_tot, and C_tot = 2 xi sqrt(m_tot k_sv). From 20 mm
       under the rated load the wheel leaves the road on the first rebounds (a non-linear decay),
       so the same reduction is also given for the record after the last lift-off
       (`*_in_contact_*`, None when too little of the record is left);
    4. k_sv: by default the drop is continued with the settle damping on until the wheel rests
       under the same load, and k_sv = contact force / deflection from first contact (the E02
       secant at the condition's load, measured at the end of the drop; k_sv_from = "settle").
       k_sv_from = "e02" runs the quasi-static E02 ramp (static.run_vertical_stiffness) instead,
       secant at the condition's load; it costs a ~0.8 s simulation more.

Load vs gravity: the study applies "the vertical load to the rim", the axle load of the condition,
as in E02 where k_sv is measured with a rim force alone; gravity on the wheel's own 111 kg adds
~1.1 kN (2.4 % of the rated load). `gravity = false` (default) matches E02; `gravity = true` adds
g to the rim and every node (the static contact force then includes the wheel's weight, and k_sv
is taken from that contact force).

Only z is free, the decay is measured about the settled rim position (the true static level under
the load), and because the wheel may leave the road on the first rebounds the decay is not that of
a linear oscillator: the two-peak and the fitted values are both reported with their difference.
All phases share the static experiments' compiled program (same drive structure, N_SAVE samples).
"""

import time

import jax
import jax.numpy as jnp
import numpy as np

from .. import signals, solve
from .. import units as U
from ..config import F
from ..errors import ConfigError
from . import phases
from .result import ExperimentResult
from .sidewall import decay_about_fit, decay_checks, decay_quantities, release_phase

DOWN = np.array([0.0, 0, -1, 0, 0, 0])
K_SV_SOURCES = ("settle", "e02")


def drop(tire, pressure, load, proto, drop_height, duration, gravity):
    """Inflate, then drop from `drop_height` under the rim force `load` (N), settle damping off.

    Returns (dt, inflate PhaseResult, road height z_road (m), ts (N_SAVE,), drop PhaseResult).
    """
    model, params = tire.model, tire.params
    dt = solve.stable_step(model, params, pressure, float(proto.settle_damping))
    phases.steps_for(max(float(proto.inflate_max), duration), dt)
    inf = phases.inflate(model, params, pressure, dt, proto, solve.MAX_STEPS)
    solve.check_phase("inflate", inf, model)
    z_road = float(phases.first_contact_height(model, inf.y)) - drop_height
    ts, fall = release_phase(model, params, pressure, dt, proto, inf.y, inf.t_end, phases.flat_road(z_road),
                             load0=load * DOWN, load1=load * DOWN, rim_free=phases.RIM_Z, ramp=0.0,
                             duration=duration, gravity=_g(gravity))
    return dt, inf, z_road, ts, fall


def _g(gravity):
    return np.array([0.0, 0.0, -U.G0]) if gravity else np.zeros(3)


def settle_after_drop(tire, pressure, load, proto, dt, fall, z_road, gravity):
    """Continue from the end of the drop with the settle damping on until at rest (same load)."""
    phases.steps_for(float(proto.settle_max), dt)
    t0 = fall.t_end
    drive = phases.make_drive(pressure, dt, proto, force0=load * DOWN, force1=load * DOWN, t0=t0, t1=t0,
                              rim_free=phases.RIM_Z, surface=phases.flat_road(z_road), gravity=_g(gravity))
    ts = jnp.linspace(t0, t0 + proto.settle_max, solve.N_SAVE)
    return solve.run_phase_jit(tire.model, tire.params, drive, fall.y, t0, t0 + proto.settle_max, ts, t0,
                               proto.ke_tol, solve.MAX_STEPS)


def run_drop(tire, condition, proto, drop_height, duration, gravity, k_sv_from, mass):
    """E04 at the condition's load and pressure. drop_height, duration: m, s; mass: m_tot (kg;
    <= 0: the model's wheel mass); k_sv_from: "settle" or "e02" (module docstring)."""
    if k_sv_from not in K_SV_SOURCES:
        raise ConfigError(f"drop_test.k_sv_from = {k_sv_from!r}: must be one of {', '.join(K_SV_SOURCES)}")
    p, load = condition["pressure_Pa"], condition["load_N"]
    model = tire.model
    w0 = time.perf_counter()
    dt, inf, z_road, ts, fall = drop(tire, p, load, proto, drop_height, duration, gravity)
    jax.block_until_ready(fall)
    wall_drop = time.perf_counter() - w0
    solve.check_phase("drop", fall, model, require_settled=False)
    s = jax.tree_util.tree_map(np.asarray, fall.saved)
    z = s["q"][:, 2]
    touching = s["n_contact"] > 0
    if not touching.any():
        raise ConfigError(f"drop_test.duration_s = {duration:g}: the wheel never reached the road (raise it)")
    i_c = int(np.argmax(touching))
    t_contact = float(ts[i_c])
    own = float(model.rim_mass + np.sum(np.asarray(model.node_mass)))
    M = mass if mass > 0 else own

    settle = None
    w1 = time.perf_counter()
    if k_sv_from == "settle":
        settle = settle_after_drop(tire, p, load, proto, dt, fall, z_road, gravity)
        jax.block_until_ready(settle)
        solve.check_phase("settle", settle, model)
        z_static = float(settle.y.q[2])
        deflection = -z_static - drop_height  # rim travel beyond first contact (E02's deflection)
        # at rest the road carries the load (and with gravity the wheel's weight); the load is
        # used rather than the recorded contact force, which still carries the tread's ringing
        # (~1 % at the settle tolerance) while the rim position has settled to ~0.1 %
        fz = load + (own * U.G0 if gravity else 0.0)
        k_sv = fz / deflection
        e02 = None
    else:
        from .static import run_vertical_stiffness

        e02 = run_vertical_stiffness(tire, condition, proto, max(60e3, 1.2 * load), load, 0.3,
                                     (0.2 * load, max(60e3, 1.2 * load)))
        k_sv, deflection, fz = e02.quantities["k_sv_N_per_m"], e02.quantities["deflection_m"], load
        z_static = None
    wall_ksv = time.perf_counter() - w1

    def reduce(t_start):
        if z_static is None:
            return decay_about_fit(ts, z, M, t_start)
        return signals.free_decay(ts, z, M, t_start=t_start, x_final=z_static)

    fd = reduce(t_contact)
    q = {"C_tot_Ns_per_m": None, "C_tot_2p_Ns_per_m": None, "C_tot_fit_Ns_per_m": 2 * fd.xi_fit * np.sqrt(M * k_sv)}
    if fd.two_peak_ok:
        q["C_tot_2p_Ns_per_m"] = 2 * fd.xi_2p * np.sqrt(M * k_sv)
    q["C_tot_Ns_per_m"] = q["C_tot_2p_Ns_per_m"] if fd.two_peak_ok else q["C_tot_fit_Ns_per_m"]
    q |= {"k_sv_N_per_m": k_sv, "k_sv_source": "settled end of the drop" if settle is not None else "E02 ramp secant",
          "static_deflection_m": deflection, "static_load_N": fz, "m_tot_kg": M}
    dq = decay_quantities(fd, "decay_mass_kg", "C_tot_from_omega", "Ns_per_m")
    dq.pop("C_tot_from_omega_Ns_per_m")
    q |= dq
    # the rigid-ring relation k_sv = m_tot omega_n^2 holds only if the wheel moves as one mass
    q["k_from_frequency_N_per_m"] = M * fd.omega_n_fit**2

    airborne = touching[i_c:] == 0
    # The same reduction over the part of the record after the last lift-off, where the wheel
    # stays on the road and the oscillation is nearly linear (None when too little is left).
    i_in = i_c + (int(np.nonzero(airborne)[0][-1]) + 1 if airborne.any() else 0)
    fd_in = reduce(float(ts[i_in])) if ts.size - i_in >= 16 else None
    q |= {"t_in_contact_from_s": float(ts[i_in] - ts[0]) if fd_in is not None else None,
          "xi_in_contact_2p": fd_in.xi_2p if fd_in is not None else None,
          "xi_in_contact_fit": fd_in.xi_fit if fd_in is not None else None,
          "C_tot_in_contact_2p_Ns_per_m": (2 * fd_in.xi_2p * np.sqrt(M * k_sv)
                                           if fd_in is not None and fd_in.two_peak_ok else None),
          "C_tot_in_contact_fit_Ns_per_m": 2 * fd_in.xi_fit * np.sqrt(M * k_sv) if fd_in is not None else None,
          "omega_n_in_contact_fit_rad_per_s": fd_in.omega_n_fit if fd_in is not None else None}
    checks = {"inflate_settled": bool(inf.settled), "drop_height_m": drop_height,
              "first_contact_t_s": t_contact - float(ts[0]),
              "airborne_after_first_contact_fraction": float(airborne.mean()),
              "max_deflection_m": float(-z[i_c:].min() - drop_height),
              "gravity": bool(gravity), "model_wheel_mass_kg": own}
    if settle is not None:
        checks |= {"settle_settled": bool(settle.settled), "settle_t_s": float(settle.t_end - fall.t_end),
                   "static_contact_force_N": _last_contact_fz(settle),
                   "static_contact_vs_load_rel_error": abs(_last_contact_fz(settle) - fz) / fz}
    checks |= decay_checks(fd, fall, prefix="drop")
    if fd_in is not None:
        checks |= {"in_contact_two_peak_ok": fd_in.two_peak_ok, "in_contact_fit_rms_relative": fd_in.fit_rms_relative,
                   "in_contact_fit_oscillatory": fd_in.fit_oscillatory}
    sig = {"time_s": ts - ts[0], "rim_z_m": z, "contact_force_z_N": s["contact_force"][:, 2],
           "n_contact": s["n_contact"], "rubber_dissipated_J": s["dissipated"] - s["dissipated"][0]}
    steps = int(inf.n_steps + fall.n_steps) + (int(settle.n_steps) if settle is not None else e02.info["steps"])
    info = {"study_id": "E04", "dt_s": dt, "steps": steps, "simulated_s": float(fall.t_end),
            "wall_s_including_compile": wall_drop + wall_ksv, "wall_drop_s": wall_drop, "wall_k_sv_s": wall_ksv,
            "duration_s": duration, "decay_samples": int(ts.size),
            "load_applied_as": "rim force (condition load)" + (" + gravity" if gravity else "")}
    if e02 is not None:
        info["e02"] = e02.quantities
    return ExperimentResult("drop_test", condition, q, signals=sig, checks=checks, info=info)


def _last_contact_fz(res):
    fz = np.asarray(res.saved["contact_force"])[:, 2]
    ok = np.isfinite(fz)
    return float(fz[ok][-1])


SCHEMA = {
    "drop_height_mm": F(float, U.MM, 0, 200, 20.0, "mm between the lowest tread point and the road"),
    "duration_s": F(float, 1, 0.05, 3, 0.4, "s of drop and free decay"),
    "gravity": F(bool, 1, default=False),
    "k_sv_from": F(str, default="settle"),
    "m_tot_kg": F(float, 1, 0, 1e4, 111.25, "kg, m_tot for C_tot (0: the model's wheel mass)"),
}


def _run(tire, condition, proto, drop_height_mm, duration_s, gravity, k_sv_from, m_tot_kg):
    return run_drop(tire, condition, proto, drop_height_mm, duration_s, gravity, k_sv_from, m_tot_kg)


from .registry import Experiment, register  # noqa: E402  (the registry imports this module)

register(Experiment("drop_test", _run, SCHEMA, needs_load=True,
                    description="E04 total vertical damping C_tot (drop test)"))
