"""Diagnosis checks of the out-of-plane metrics (`diagnosis`): the lateral release (frequency and
damping) and the slip step (steady F_y and M_z, relaxation length s63), against E10's measurement
window. Each check takes the condition's context and the comparison row and returns (state, text)."""

import math
from pathlib import Path

import numpy as np

from .. import results
from .diagnosis_base import FULL, NONE, PARTIAL, _damping, _n, _p, _verdict, _within
from .model import CONTACT
from .modes import lateral_modes, string_step_s63
from .params import derive


def _lateral_zeta(cx, c):
    d = cx.d
    if d.tread_damper_identified:  # (identified: every lateral spring and damper is there)
        f_r, z_r = lateral_modes(d, "ring")[0]
        if _within(f_r, cx.val("lateral.f_Hz", "ring"), 0.02):  # the validation ran the ring variant
            txt = (f"the ring's tread damper C_cy = {_n(d.C_cy, 'N s/m')} is set from this release ({d.C_cy_source}): "
                   f"the ring's linear release has zeta {z_r:.4g} ({_p(z_r / c.shell - 1)} against the shell's fit), its "
                   f"simulated release {c.ring:.4g}; what the simulated ring adds to its linearization (the string "
                   f"contact, the patch's stick) is not measured")
            return NONE, txt
    return _damping(cx, c, "C_l_Ns_per_m", "C_l_2p_Ns_per_m", "C_l_fit_Ns_per_m", "lateral.f_Hz",
                    "lateral_stiffness")


def _lateral_f(cx, c):
    d = cx.d
    f_red = lateral_modes(d, "reduced")[0][0]
    m_tot = d.tire.m_tot_kg
    k_dyn = m_tot * (2 * math.pi * c.shell) ** 2
    red = (f"the reduced lateral model puts m_tot = {m_tot:.4g} kg on k_l = {_n(d.k_l, 'N/m')} ({_n(f_red, 'Hz')}); for "
           f"the shell's frequency that mass needs m_tot (2 pi f)^2 = {_n(k_dyn, 'N/m')} = {k_dyn / d.k_l:.3g} x k_l")
    if None in (d.k_by, d.k_cy, d.k_bgamma, d.C_by, d.C_cy, d.C_bgamma):
        return NONE, red + "; the ring variant's inputs (k_by, k_bgamma, k_cy) are missing"
    f_ring = lateral_modes(d, "ring")[0][0]
    ring = (f"in the ring variant (belt y_b, gamma_b on k_by, k_bgamma and the tread k_cy; the springs from "
            f"{d.lateral_spring_source}) the belt's {d.tire.m_b_kg:.4g} kg moves less than the rim and the mode is at "
            f"{_n(f_ring, 'Hz')} ({_p(f_ring / c.shell - 1)})")
    if d.lateral_branch is not None and _within(f_ring, c.ring, 0.02):
        f_s = _storage_f(cx)
        return NONE, (ring + f"; the sidewall's Maxwell branches make its k_l x {d.k_l_at(f_s) / d.k_l:.4g} at "
                      f"{_n(f_s, 'Hz')}, E09's push on the storage moduli there; the rest is not established")
    if _within(f_ring, c.ring, 0.02) and not _within(f_red, c.ring, 0.02):
        # the validation ran the ring variant: its linear mode is the metric; what is left is its stiffness
        txt = ring + f"; the shell's frequency needs (f_shell/f_ring)^2 = {(c.shell / f_ring) ** 2:.3g} x its stiffness"
        r = d.lateral_storage_ratio
        if r is None or d.uses_storage:
            why = ("" if r is not None else " (rate stiffening of the rubber is a candidate: this characterization has "
                   "no push on the storage moduli)")
            return NONE, txt + f" at these masses; not established{why}; " + red
        st = derive(cx.row, d.tire, lateral_springs="storage")
        f_st = lateral_modes(st, "ring")[0][0]
        txt += (f"; the springs rest on the rubber's long-term moduli, the shell rings where the Prony series' "
                f"storage modulus is higher: E09's push on the storage moduli at {_n(_storage_f(cx), 'Hz')} gives k_l x "
                f"{r:.4g}, and with k_by, k_bgamma and k_l x that (k_cy follows) the ring rings at {_n(f_st, 'Hz')} "
                f"({_p(f_st / c.shell - 1)}); the ring keeps the static springs because the same springs shorten "
                f"its sigma_c from {_n(d.sigma_c, 'm')} to {_n(st.sigma_c, 'm')}, and the slip step's slower "
                f"build-up sees the long-term moduli (measured: docs/rigid-ring.md); one linear spring cannot give "
                f"both; the default springs' Maxwell branches would (this ring has none: {d.lateral_spring_source})")
        state = _verdict(f_st, c.shell, c.ring, c.tolerance)
        return state, txt + ("" if state == FULL else "; the rest is not established")
    txt = "the validation's " + red + "; " + ring
    state = _verdict(f_ring, c.shell, c.ring, c.tolerance)
    if state == PARTIAL:
        txt += (f"; the remaining stiffness ratio (f_shell/f_variant)^2 = {(c.shell / f_ring) ** 2:.3g} is not "
                f"established" + (" (rate stiffening of the rubber is a candidate: no push on the storage moduli)"
                                  if d.lateral_storage_ratio is None else ""))
    return state, txt


def _storage_f(cx):
    """The frequency (Hz) the row's storage moduli were taken at (E09's release there), or None."""
    return cx.row.get("f_l_storage_Hz")


def _speeds(cx):
    return sorted({float(m.split(".")[0][5:]) for m in cx.rows if m.startswith("step_")})


def _step_unsettled(cx, v, tol=0.005):
    """The shell step's text when its F_y still moves at the record's end: the mean over the last tenth
    of the distance against the tenth before it, beyond tol (relative). None when settled or no record."""
    sig = (cx.shell_signals or {}).get(f"step_{v:g}")
    if sig is None:
        return None
    s, fy = (np.asarray(x, float) for x in sig)
    ok = np.isfinite(s) & np.isfinite(fy)
    s, fy = s[ok], fy[ok]
    if s.size < 20:
        return None
    w = 0.1 * (s[-1] - s[0])
    last, before = fy[s >= s[-1] - w], fy[(s >= s[-1] - 2 * w) & (s < s[-1] - w)]
    if not (last.size and before.size and np.mean(before)):
        return None
    change = float(np.mean(last) / np.mean(before)) - 1
    if abs(change) <= tol:
        return None
    return (f"the shell's F_y still moves {_p(change)} over its record's last {_n(w, 'm')} (mean against the "
            f"{_n(w, 'm')} before): its steady value, and the s63 measured against it, are taken before it settled")


def _step_alpha(cx):
    """Slip angle of the step (rad) from the ring's steady F_y = -k_f sin(alpha)."""
    for v in _speeds(cx):
        fy = cx.val(f"step_{v:g}.F_y_steady_N", "ring")
        if fy is not None and cx.d.k_f:
            return math.asin(min(1.0, abs(fy) / cx.d.k_f))
    return None


def _e10(cx, key, alpha):
    """|F_y| or |M_z| of the row's E10 curve at the slip angle alpha (rad), or None."""
    cv = cx.row.curves
    if cv is None:
        return None
    y = cv.wheel_lateral_force()[0] if key == "F_y" else cv.M_z_SAE_Nm
    if y is None:
        return None
    return float(abs(np.interp(math.degrees(alpha), cv.slip_angle_deg, y)))


def _e10_settling(cx, alpha):
    """(drift_rel over the E10 window at alpha, window (m), speed, estimated shortfall) or None. A
    first-order approach over sigma drifts by (shortfall) x window / sigma over the window."""
    res, sig = cx.case("cornering")
    if sig is None or "F_y_drift_rel" not in sig:
        return None
    i = int(np.argmin(abs(sig["slip_angle_deg"] - math.degrees(alpha))))
    drift = float(sig["F_y_drift_rel"][i])
    v = res.get("quantities", {}).get("speed_m_per_s")
    w = res.get("info", {}).get("measure_s")
    if not (np.isfinite(drift) and v and w and cx.d.sigma):
        return None
    return drift, v * w, v, drift * cx.d.sigma / (v * w)


def _steady_reference(cx, v, key):
    """(|F_y| or |M_z| (SAE) of the shell's steady solve at speed v (m/s) and the step's angle (the
    largest of the references' angles), or None; its error message when that solve failed, or None),
    from the validation's steady references (validate.steady_references)."""
    if cx.char_dir is None:
        return None, None
    tries = sorted((Path(cx.char_dir) / "validation" / results.steady_reference_folder(v)).glob("load_levels_*"),
                   key=lambda f: int(f.name.rsplit("_", 1)[1]))
    d = next((c for c in (results.find_case(results.cases_dir(f), cx.load_N, cx.pressure_Pa) for f in tries)
              if c is not None), None)
    if d is None:  # a failed case has no result.json: found by its name's condition part; the last try's error
        tail = results.case_name(0, {"load_N": cx.load_N, "pressure_Pa": cx.pressure_Pa}).split("_", 1)[1]
        errors = [results.read_error(c) for f in tries for c in sorted(results.cases_dir(f).glob(f"*_{tail}"))]
        return None, next((e for e in reversed(errors) if e), None)
    sig = results.read_signals(d)
    col = "F_y_SAE_N" if key == "F_y" else "M_z_SAE_Nm"
    if not sig or col not in sig:
        return None, None
    i = int(np.argmax(np.abs(np.asarray(sig["slip_angle_deg"], float))))
    return float(abs(sig[col][i])), None


def _step_force(cx, c, key):
    d = cx.d
    alpha = _step_alpha(cx)
    v_here = float(c.metric.split(".")[0][5:])
    unit, sym = ("N", "k_f") if key == "F_y" else ("N m", "k_m")
    lin = (d.k_f if key == "F_y" else d.k_m) * math.sin(alpha) if alpha else None
    curve = _e10(cx, key, alpha) if alpha else None
    parts, state = [], NONE
    res, _ = cx.case("cornering")
    v10 = (res or {}).get("quantities", {}).get("speed_m_per_s")
    at = f" (E10, at {v10:.3g} m/s)" if v10 else ""
    shell = abs(c.shell)
    if curve and key == "M_z" and d.mz_curve is not None and _within(abs(c.ring), curve, 0.02):
        parts.append(f"the ring's M_z {_n(abs(c.ring), unit)} is E10's steady curve{at} at its slip ({_n(curve, unit)} at "
                     f"{math.degrees(alpha):.3g} deg), the shell's step {_n(shell, unit)} ({_p(shell / curve - 1)} vs the curve)")
        lin = curve  # the ring follows the curve: what is left is the step against the steady curve
    elif curve:
        # the record's tail may still carry the lateral mode's ringing: say how far from the ring's own law
        off = "" if _within(abs(c.ring), lin, 0.002) else (f" ({_p(abs(c.ring) / lin - 1)} from it over the record's tail, "
                                                            f"where its lateral mode still rings)")
        parts.append(f"the ring's {key} {_n(abs(c.ring), unit)} is the linear {sym} sin(alpha) = {_n(lin, unit)} at "
                     f"{math.degrees(alpha):.3g} deg{off}; the cornering curve{at} has {_n(curve, unit)} there "
                     f"({_p(lin / curve - 1)} linear vs curve), the shell's step {_n(shell, unit)} "
                     f"({_p(shell / curve - 1)} vs curve)")
        if not _within(lin, curve, c.tolerance) and _within(shell, curve, c.tolerance):
            state = FULL
            parts.append(f"{sym}, a slope fitted over the first degrees of a curved {key}(alpha), misses the curve's own "
                         f"value at the step angle")
    for vo in [v for v in _speeds(cx) if v != v_here]:
        so = cx.val(f"step_{vo:g}.{c.metric.split('.', 1)[1]}", "shell")
        if so:
            dv = shell / abs(so) - 1
            parts.append(f"the shell's value changes {_p(dv)} from {vo:g} to {v_here:g} m/s (a speed dependence the "
                         f"ring does not have)")
            if state == NONE and curve and _within(lin, curve, c.tolerance) and abs(dv) > 0.5 * abs(c.rel_diff):
                state = FULL
    ref, failed = _steady_reference(cx, v_here, key)
    if failed:
        parts.append(f"the shell's steady-rolling solve at {v_here:g} m/s, the reference for this split, failed: "
                     f"{failed.splitlines()[0]}")
    if ref is not None:
        ring = abs(c.ring)
        parts.append(f"the shell's steady-rolling solve at {v_here:g} m/s and the step's angle gives {_n(ref, unit)}: "
                     f"the step's transient settles {_p(shell / ref - 1)} from it (the transient's own gap to the "
                     f"steady solve, docs/steady-rolling.md), and the ring is {_p(ring / ref - 1)} from it")
        if curve:
            parts.append(f"from E10's speed to {v_here:g} m/s the steady {key} changes {_p(ref / curve - 1)}")
        if state == NONE:
            # what the shell's two steps (E10's speed -> this speed, steady -> transient) account for
            pred = (lin if lin else ring) * (ref / curve if curve else 1.0) * shell / ref
            state = _verdict(pred, shell, ring, c.tolerance)
            if state == PARTIAL:
                parts.append("the rest is not established")
    moving = _step_unsettled(cx, v_here) if key == "F_y" else None
    if moving:
        parts.append(moving)
    st = _e10_settling(cx, alpha) if alpha else None
    if st is not None:
        drift, win, v, short = st
        parts.append(f"E10's force still grew over its {_n(win, 'm')} window at {v:.3g} m/s (drift {_p(drift)}: "
                     f"~{_p(short)} short of steady for a lag over sigma = {_n(d.sigma, 'm')})")
        if (state == NONE and curve and abs(short) > 0.5 * abs(c.rel_diff)
                and _within(shell, curve * (1 + short), c.tolerance)):
            state = FULL
    return state, "; ".join(parts) if parts else "no E10 curve and no second speed to compare"


def _step_s63(cx, c):
    d = cx.d
    v_here = float(c.metric.split(".")[0][5:])
    state, s_str = NONE, (string_step_s63(d.sigma, d.a) if d.sigma and d.a else None)
    if CONTACT == "string":
        parts = [f"the ring's tread is a stretched string through the patch on its belt's lateral springs, sigma = "
                 f"k_f/k_l = {_n(d.sigma, 'm')} in all (s63 = {_n(c.ring, 'm')}, {c.ring / d.sigma:.2g} sigma)"]
        if s_str:
            parts.append(f"Pacejka's quasi-static stretched string with the same k_f/k_l and a = {_n(d.a, 'm')} reaches "
                         f"63 % at {_n(s_str, 'm')} ({s_str / d.sigma:.2g} sigma; {_p(s_str / c.shell - 1)} against the "
                         f"shell); the ring's belt masses and tread damper move it {_p(c.ring / s_str - 1)}")
    else:
        parts = [f"the ring is a first-order lag over sigma = k_f/k_l = {_n(d.sigma, 'm')} at any speed "
                 f"(s63 = {_n(c.ring, 'm')})"]
        if s_str:
            parts.append(f"a contact patch of half length a = {_n(d.a, 'm')} builds part of the force inside its own "
                         f"length: a stretched string with the same k_f/k_l (sigma_string = sigma - a = "
                         f"{_n(d.sigma - d.a, 'm')}) reaches 63 % at {_n(s_str, 'm')} ({s_str / d.sigma:.2g} sigma; "
                         f"{_p(s_str / c.shell - 1)} against the shell)")
    if d.lateral_branch is not None and d.sigma:
        f_b = v_here / (2 * math.pi * d.sigma)
        parts.append(f"the sidewall's Maxwell branches (tau {1e3 * d.lateral_branch[1]:.3g} ms) make the ring's k_l x "
                     f"{d.k_l_at(f_b) / d.k_l:.4g} at the build-up's V/(2 pi sigma) = {_n(f_b, 'Hz')} (x "
                     f"{d.k_l_at(_storage_f(cx)) / d.k_l:.4g} at the lateral mode)")  # (a branch needs f_l_storage)
    if s_str:
        state = _verdict(s_str, c.shell, c.ring, c.tolerance)
    for vo in [v for v in _speeds(cx) if v != v_here]:
        so = cx.val(f"step_{vo:g}.s63_m", "shell")
        if so:
            parts.append(f"the shell's s63 changes {_p(c.shell / so - 1)} from {vo:g} to {v_here:g} m/s, which neither a "
                         f"lag nor the quasi-static string can")
    f_lat = cx.val("lateral.f_Hz", "shell")
    if f_lat and d.sigma:
        parts.append(f"at {v_here:g} m/s sigma is rolled in {1e3 * d.sigma / v_here:.3g} ms, {d.sigma / v_here * f_lat:.2g} "
                     f"of the shell's lateral period 1/{_n(f_lat, 'Hz')} (the shorter, the less a quasi-static model holds)")
    sig = (cx.shell_signals or {}).get(f"step_{v_here:g}")
    if sig is not None:
        s, fy = (np.asarray(x, float) for x in sig)
        tail = s >= s[-1] - 0.05 * (s[-1] - s[0])
        fss = float(np.mean(fy[tail]))
        if fss:
            over = float(np.max(fy[s > 0] / fss)) - 1
            if over > 0.02:
                parts.append(f"the shell's F_y overshoots by {_p(over)} (a lightly damped carcass mode: it reaches "
                             f"63 % sooner than a lag does)")
    moving = _step_unsettled(cx, v_here)
    if moving:
        parts.append(moving)
    txt = "; ".join(parts)
    if state == PARTIAL:
        txt += "; the rest is not established"
    return state, txt
