"""Diagnosis checks of the drop test's metrics (`diagnosis`): static deflection, bounce frequency and
damping, peak F_z, belt mode. Each check takes the condition's context and the comparison row and
returns (state, text)."""

import inspect
import math

import numpy as np

from .diagnosis_base import FULL, NONE, PARTIAL, _damping, _n, _p, _verdict, _within
from .modes import vertical_modes


def _drop_static(cx, c):
    d = cx.d
    eq = cx.load_N / d.k_sv
    if not _within(c.ring, eq, 0.25 * c.tolerance):
        return FULL, (f"the ring's value {_n(c.ring, 'm')} is not its rest position F_z/k_sv = {_n(eq, 'm')} "
                      f"({_p(eq / c.shell - 1)} against the shell): the ring's reduction is not the shell's rest after "
                      f"the drop")
    k_shell = cx.load_N / c.shell
    txt = (f"the table's k_sv = {_n(d.k_sv, 'N/m')} (the ring rests at F_z/k_sv = {_n(eq, 'm')}) is not the stiffness "
           f"at which the shell's drop rests: F_z/{_n(c.shell, 'm')} = {_n(k_shell, 'N/m')} ({_p(d.k_sv / k_shell - 1)})")
    res, _ = cx.case("vertical_stiffness")
    k02 = (res or {}).get("quantities", {}).get("k_sv_N_per_m")
    if k02:
        same = " (the table's is E02's)" if math.isclose(k02, d.k_sv, rel_tol=1e-6) else ""
        txt += f"; E02's secant at the load is {_n(k02, 'N/m')}{same}"
    return FULL, txt


def _in_contact_f(cx):
    """The shell's drop: f_n (Hz) of its small motion after the last lift-off, or None."""
    res, _ = cx.case("drop_test")
    w_in = (res or {}).get("quantities", {}).get("omega_n_in_contact_fit_rad_per_s") or cx.row.get(
        "omega_n_in_contact_fit_rad_per_s")
    return None if not w_in else w_in / (2 * math.pi)


def _drop_bounce_f_tangent(cx, c):
    """The ring already uses the tangent: compare its linear bounce with the shell's small motion."""
    d = cx.d
    f0 = vertical_modes(d)[0][0]
    txt = (f"the ring's springs already use E02's tangent k_vt = {_n(d.k_vt, 'N/m')} ({d.k_vt / d.k_sv:.3g} x the secant); "
           f"its linear bounce mode is {_n(f0, 'Hz')}")
    f_in = _in_contact_f(cx)
    if f_in is None:
        return NONE, txt + "; the shell's drop has no in-contact part to compare it with"
    txt += f"; after its last lift-off the shell rings at f_n = {_n(f_in, 'Hz')} ({_p(f0 / f_in - 1)})"
    if _within(f0, f_in, c.tolerance):
        law = "E02's curve past the load" if d.k_vr3 is not None else "the quadratic fitted at the load"
        txt += (". The small motions agree: the miss is in the part of the record with lift-offs, where the ring's "
                f"contact law is {law}")
    return NONE, txt


def _drop_bounce_f(cx, c):
    d = cx.d
    if d.uses_tangent:
        return _drop_bounce_f_tangent(cx, c)
    kt = cx.tangent_stiffness()
    if kt is None:
        return NONE, "no load-deflection curve at this pressure to test the stiffness the bounce sees"
    kt, src = kt
    need = (c.shell / c.ring) ** 2
    f0 = vertical_modes(d)[0][0]
    C = cx.row.get("C_tot_Ns_per_m")
    # the same damping ratio with the tangent stiffness: C scales with sqrt(k)
    d_t = cx.rederive(k_sv_N_per_m=kt, C_tot_Ns_per_m=None if C is None else C * math.sqrt(kt / d.k_sv))
    f_t = vertical_modes(d_t)[0][0]
    pred = c.ring * f_t / f0
    txt = (f"the load-deflection curve stiffens: its tangent at the load is {_n(kt, 'N/m')} ({src}), "
           f"{kt / d.k_sv:.3g} x the secant k_sv = {_n(d.k_sv, 'N/m')} the linear ring uses, where the shell's bounce "
           f"needs (f_shell/f_ring)^2 = {need:.3g} x; with the tangent the ring's linear bounce mode goes from "
           f"{_n(f0, 'Hz')} to {_n(f_t, 'Hz')}, its metric to ~{_n(pred, 'Hz')} ({_p(pred / c.shell - 1)})")
    state = _verdict(pred, c.shell, c.ring, c.tolerance)
    res, _ = cx.case("drop_test")
    w_in = (res or {}).get("quantities", {}).get("omega_n_in_contact_fit_rad_per_s")
    if w_in:
        f_in = w_in / (2 * math.pi)
        txt += (f"; after its last lift-off (small, linear motion) the shell rings at f_n = {_n(f_in, 'Hz')}, the "
                f"ring's linear mode with the tangent at {_n(f_t, 'Hz')} ({_p(f_t / f_in - 1)})")
        if _within(f_t, f_in, c.tolerance):
            state = FULL
    cfit = cx.row.get("C_tot_fit_Ns_per_m")
    if C is not None and cfit and C < 0.8 * cfit and c.ring < 0.95 * f0:
        txt += (f". The ring also rebounds off the road far longer: its C_tot = {_n(C, 'N s/m')} is "
                f"{C / cfit:.2g} x the fit value {_n(cfit, 'N s/m')}, and its fitted frequency {_n(c.ring, 'Hz')} "
                f"lies {_p(c.ring / f0 - 1)} off its own linear bounce")
    if state == PARTIAL:
        txt += "; the rest is not established (rate stiffening of the rubber is a candidate)"
    return state, txt


def _drop_zeta(cx, c):
    d = cx.d
    z_in = cx.row.get("xi_in_contact_fit")
    if not (d.dampers_identified and z_in):
        return _damping(cx, c, "C_tot_Ns_per_m", "C_tot_2p_Ns_per_m", "C_tot_fit_Ns_per_m", "drop.bounce_f_Hz",
                        "drop_test")
    # C_bz, C_vr were split so the ring's linear bounce has E04's zeta after the last lift-off; the metric
    # fits each side's whole record from first contact, lift-offs included
    f_b, z_lin = vertical_modes(d)[0]
    pred, obs = z_in / c.shell, c.ring / c.shell
    txt = (f"C_bz and C_vr are split so the ring's linear bounce ({_n(f_b, 'Hz')}) has E04's in-contact zeta "
           f"{z_in:.3g} (after the last lift-off; the ring's: {z_lin:.3g}); the metric fits each whole record from "
           f"first contact, lift-offs included, where the shell gives {c.shell:.3g}: in-contact / whole record x "
           f"{pred:.3g} on the shell, observed ring / shell x {obs:.3g}")
    state = _verdict(pred, obs, 1.0, c.tolerance)
    if state != FULL:
        txt += (f"; the ring's own record gives x {c.ring / z_in:.3g} its in-contact zeta, the shell's x "
                f"{c.shell / z_in:.3g}: lift-offs change the two decays differently")
    return state, txt



def _drop_peak(cx, c):
    curve = cx.load_curve()
    if curve is None:
        return NONE, "no load-deflection curve at this pressure"
    F, x, src = curve
    res, _ = cx.case("drop_test")
    h = (res or {}).get("checks", {}).get("drop_height_m")
    if h is None:
        from . import scenarios
        h = inspect.signature(scenarios.drop_test).parameters["drop_height"].default
    L = cx.load_N
    xe = np.linspace(0.0, 6.0 * (h + x[-1]), 20001)
    last = (F[-1] - F[-2]) / (x[-1] - x[-2])
    Fe = np.where(xe <= x[-1], np.interp(xe, x, F), F[-1] + (xe - x[-1]) * last)
    W = np.concatenate([[0.0], np.cumsum(0.5 * (Fe[1:] + Fe[:-1]) * np.diff(xe))])
    i = int(np.argmax(W >= L * (h + xe)))
    p_curve, x_max = float(Fe[i]), float(xe[i])
    k = cx.d.k_sv
    p_lin = L + math.sqrt(L * L + 2 * h * k * L)
    extra = f", extrapolated past {_n(x[-1], 'm')} with its last slope" if x_max > x[-1] else ""
    txt = (f"the load-deflection curve stiffens: the impact energy F_z (h + deflection) of the {h * 1e3:g} mm drop, "
           f"stored on {src}{extra}, gives a peak of {_n(p_curve, 'N')} ({_p(p_curve / c.shell - 1)} against the "
           f"shell's {_n(c.shell, 'N')})")
    if cx.d.uses_tangent:
        law = ("follows E02's secant and tangent at the load and its largest load, then its end slope" if
               cx.d.k_vr3 is not None else "is a quadratic with E02's secant and tangent at the load, not the whole curve")
        txt += f"; the ring's contact law {law} (ring {_n(c.ring, 'N')})"
        state = _verdict(p_curve, c.shell, c.ring, c.tolerance)
        state = PARTIAL if state == FULL else state  # the ring's own law is not the curve: not shown to be the cause
    else:
        txt += f"; on the ring's linear k_sv it gives {_n(p_lin, 'N')} (ring {_n(c.ring, 'N')})"
        state = _verdict(p_curve, c.shell, c.ring, c.tolerance)
    if state == FULL and not _within(p_lin, c.ring, c.tolerance):
        state = PARTIAL
    if state == PARTIAL:
        txt += "; the rest is not established (the shell's dynamic stiffening is a candidate)"
    return state, txt


def _belt_mode(cx, c):
    parts, state = [], NONE
    for side, name in (("ring", "the ring's"), ("shell", "the shell's")):
        v, fb = getattr(c, side), cx.val("drop.bounce_f_Hz", side)
        if v and fb:
            n = round(v / fb)
            if n >= 2 and abs(v / (n * fb) - 1) <= c.tolerance:
                parts.append(f"{name} F_z peak {_n(v, 'Hz')} is {n} x its bounce {_n(fb, 'Hz')}: a harmonic of the "
                             f"bounce, whose F_z is clipped at every lift-off, not a belt mode")
                state = FULL
    fbelt = vertical_modes(cx.d)[-1][0]
    parts.append(f"the ring's linear belt mode (rim free) is {_n(fbelt, 'Hz')} ({_p(fbelt / c.shell - 1)} against the "
                 f"shell's {_n(c.shell, 'Hz')})")
    return state, "; ".join(parts)
