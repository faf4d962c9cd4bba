"""Diagnosis checks of the in-plane metrics (`diagnosis`): the drop test (static deflection, bounce
frequency and damping, peak F_z, belt mode) and the drum (vertical and fore-aft modes). Each check
takes the condition's context and the comparison row and returns (state, text)."""

import inspect
import math

import numpy as np

from .diagnosis_base import FULL, NONE, PARTIAL, _damping, _n, _p, _verdict, _within
from .modes import belt_vertical_mode, fore_aft_modes, vertical_modes


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
        txt += (". The small motions agree: the miss is in the part of the record with lift-offs, where the ring's "
                "contact law is the quadratic fitted at the load")
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
        txt += (f"; the ring's contact law is a quadratic with E02's secant and tangent at the load, not the whole "
                f"curve (ring {_n(c.ring, 'N')})")
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


def _drum_vertical_f(cx, c):
    """The ring's belt mode is sqrt(k_dv/m_b) with k_dv from the table's f (E03's FFT peak); the
    shell's metric is E03's modal-fit f_n: when they differ, that is the disagreement."""
    f_row, f_fit = cx.row.get("first_mode_Hz"), cx.row.get("first_mode_fit_fn_Hz")
    txt = f"the ring's belt mode {_n(c.ring, 'Hz')} against the table's f = {_n(f_row, 'Hz')} (E03's FFT peak)"
    if f_row and f_fit and _within(c.ring, f_row, 1e-3) and _within(c.shell, f_fit, 1e-3):
        return FULL, (f"the ring's belt mode reproduces the table's f = {_n(f_row, 'Hz')}, E03's FFT peak, while the "
                      f"shell's metric is E03's modal fit f_n = {_n(f_fit, 'Hz')} ({_p(f_row / f_fit - 1)}): the "
                      f"table takes the peak of a spectrum that holds more than one mode")
    return NONE, txt


def _drum_vertical_zeta(cx, c):
    d = cx.d
    f_b, z_b = belt_vertical_mode(d)
    t = d.tire
    if d.dampers_identified:
        # C_bz + C_vr were set from E03's own zeta: the ring's linear belt mode has it by construction
        z_e03 = cx.row.get("first_mode_xi")
        txt = (f"C_bz + C_vr come from E03's modal zeta {z_e03:.3g}: the ring's linear belt mode (rim locked) has "
               f"zeta {z_b:.3g} at {_n(f_b, 'Hz')}; its own record's fit gives {c.ring:.3g} (the fit of a record holding "
               f"the fore-aft and wind-up modes too)")
        return NONE, txt
    f_q = math.sqrt(d.k_sv / t.m_tot_kg) / (2 * math.pi)
    z_q = d.C_tot / (2 * math.sqrt(d.k_sv * t.m_tot_kg))
    zs_drop = cx.val("drop.bounce_zeta", "shell")
    txt = (f"one time constant tau = C_tot/k_sv = {d.tau * 1e3:.3g} ms for both vertical springs (§3) makes the ring's "
           f"damping stiffness-proportional, zeta = pi f tau: {z_q:.3g} at the bounce ({_n(f_q, 'Hz')}), {z_b:.3g} at the "
           f"belt mode ({_n(f_b, 'Hz')}), x {z_b / z_q:.3g}")
    state = NONE
    if zs_drop:
        r_s = c.shell / zs_drop
        txt += (f"; the shell's damping hardly depends on frequency: zeta {zs_drop:.3g} in the drop, {c.shell:.3g} here "
                f"(x {r_s:.3g})")
        if z_b / z_q > (1 + c.tolerance) * r_s:
            state = FULL
    c_need = 2 * c.shell * math.sqrt((d.k_bz + d.k_vr) * t.m_b_kg)
    txt += (f"; the shell's zeta needs C_bz + C_vr = {_n(c_need, 'N s/m')}, the ring has tau k_dv = "
            f"{_n(d.C_bz + d.C_vr, 'N s/m')}")
    cfit = cx.row.get("C_tot_fit_Ns_per_m")
    if cfit and not math.isclose(cfit, d.C_tot, rel_tol=0.2):
        txt += f" (from C_tot = {_n(d.C_tot, 'N s/m')}, x {d.C_tot / cfit:.2g} the fit value)"
    return state, txt


def _drum_speed(cx):
    res, _ = cx.case("drum_cleat")
    v = (res or {}).get("info", {}).get("surface_speed_m_s")
    if v is None:
        from . import scenarios
        v = inspect.signature(scenarios.drum_cleat).parameters["speed"].default
    return v


RINGING_ZETA = 0.5  # a mode damped more than this puts no peak in a spectrum: it cannot be a metric's


def _fore_aft_mode(cx, target, speed, **kw):
    """The mode of fore_aft_modes() nearest target (Hz), or the one with the largest x_b share, among
    those that ring (zeta < RINGING_ZETA: the tread string's own transport modes, zeta 0.6-0.7 near
    the drum's band, are left out with the rest of the overdamped ones)."""
    ms = [m for m in fore_aft_modes(cx.d, speed, **kw) if m[1] < RINGING_ZETA]
    if not ms:
        return None
    if target is not None:
        return min(ms, key=lambda m: abs(m[0] - target))
    return max(ms, key=lambda m: m[2])


def _shell_fx(cx):
    """(t, F_x, t_start, band) of the shell's drum-cleat spindle F_x record, or None."""
    res, sig = cx.case("drum_cleat")
    if sig is None or "axle_force_x_N" not in sig:
        return None
    info = res.get("info", {})
    t0 = info.get("t_cleat_leave_s", 0.0) - info.get("t_cleat_touch_s", 0.0)
    return sig["time_s"], sig["axle_force_x_N"], t0, tuple(info.get("f_band_Hz", (20.0, 200.0)))


def _shell_fx_peaks(cx):
    """[(f Hz, relative height)] of the 3 highest local maxima of the shell's spindle F_x spectrum
    after the cleat (in the drum's band), or None."""
    rec = _shell_fx(cx)
    if rec is None:
        return None
    t, fx, t0, band = rec
    m = t >= t0
    tt, y = t[m], fx[m]
    if tt.size < 16:
        return None
    y = y - np.polyval(np.polyfit(tt, y, 1), tt)
    dt = float(np.median(np.diff(tt)))
    X = np.abs(np.fft.rfft(y * np.hanning(y.size), 16 * y.size))
    f = np.fft.rfftfreq(16 * y.size, dt)
    sel = (f > band[0]) & (f < band[1])
    f, X = f[sel], X[sel]
    pk = [i for i in range(1, X.size - 1) if X[i] >= X[i - 1] and X[i] > X[i + 1]]
    pk = sorted(pk, key=lambda i: -X[i])[:3]
    return [(float(f[i]), float(X[i] / X[pk[0]])) for i in pk] if pk else None


def _drum_fore_aft_f(cx, c):
    d = cx.d
    v = _drum_speed(cx)
    m0 = _fore_aft_mode(cx, c.ring, v)
    if m0 is None or not _within(m0[0], c.ring, 0.01):
        return NONE, ("the ring's linearized fore-aft modes "
                      f"({', '.join(_n(m[0], 'Hz') for m in fore_aft_modes(d, v))}) do not reproduce its metric")
    if d.k_bx_measured:
        parts = [f"the ring's fore-aft / wind-up mode at {_n(c.ring, 'Hz')} uses k_bx = {_n(d.k_bx, 'N/m')} measured by E13 "
                 f"(the vertical split's k_bz is {_n(d.k_bz, 'N/m')})"]
    else:
        parts = [f"the ring's fore-aft / wind-up mode at {_n(c.ring, 'Hz')} rests on the isotropy assumption k_bx = k_bz = "
                 f"{_n(d.k_bz, 'N/m')} (§3: no E13 in this characterization)"]
    grid = np.geomspace(0.25, 8.0, 121)
    start = int(np.argmin(abs(grid - 1.0)))
    g, fr = [], []
    for direction in (range(start, grid.size), range(start, -1, -1)):  # follow the mode from the ring's k_bx
        f_prev = m0[0]
        for i in direction:
            f_prev = _fore_aft_mode(cx, f_prev, v, k_bx=grid[i] * d.k_bx)[0]
            g.append(grid[i])
            fr.append(f_prev)
    order = np.argsort(g)
    g, fr = np.asarray(g)[order], np.asarray(fr)[order]
    hit = np.flatnonzero(np.diff(np.sign(fr - c.shell)) != 0)
    state = NONE
    if hit.size:
        j = int(hit[0])
        mult = float(np.interp(c.shell, sorted([fr[j], fr[j + 1]]),
                               [g[j], g[j + 1]] if fr[j] < fr[j + 1] else [g[j + 1], g[j]]))
        parts.append(f"k_bx = {_n(mult * d.k_bx, 'N/m')} ({mult:.3g} x the ring's) puts it at the shell's {_n(c.shell, 'Hz')}")
        state = FULL
    else:
        parts.append(f"no k_bx within {grid[0]:g}..{grid[-1]:g} x the ring's reaches the shell's {_n(c.shell, 'Hz')} "
                     f"(range {_n(float(fr.min()), 'Hz')}..{_n(float(fr.max()), 'Hz')})")
    pk = _shell_fx_peaks(cx)
    if pk and len(pk) > 1:
        parts.append("the shell's spindle F_x rings in several modes (spectrum peaks "
                     + ", ".join(f"{f:.4g} Hz ({h:.2g})" for f, h in pk)
                     + "), the ring's in one; the metric follows the highest peak")
        if state == FULL and pk[1][1] >= 0.5:
            state = PARTIAL
            parts.append("which shell peak is the ring's fore-aft mode is not established")
    return state, "; ".join(parts)


def _drum_fore_aft_zeta(cx, c):
    d = cx.d
    v = _drum_speed(cx)
    m0 = _fore_aft_mode(cx, cx.val("drum.fore_aft_mode_Hz", "ring"), v)
    if m0 is None or not _within(m0[1], c.ring, 0.05):
        return NONE, "the ring's linearized fore-aft mode does not reproduce its damping"
    z_nobx = _fore_aft_mode(cx, m0[0], v, C_bx=0.0)[1]
    z_none = _fore_aft_mode(cx, m0[0], v, C_bx=0.0, C_btheta=0.0)[1]
    f_bx = math.sqrt(d.k_bx / d.tire.m_b_kg) / (2 * math.pi)
    z_bx = d.C_bx / (2 * math.sqrt(d.k_bx * d.tire.m_b_kg))
    txt = (f"of the ring's modal zeta {m0[1]:.3g}, the rolling tread (the brush through the contact patch, "
           f"V = {v:.3g} m/s) gives {z_none:.3g} alone, C_btheta {z_nobx - z_none:.2g}, and C_bx = "
           f"{_n(d.C_bx, 'N s/m')} ({d.k_bx_source}) the rest: zeta_bx = {z_bx:.3g} at f_bx = {_n(f_bx, 'Hz')}")
    if not d.k_bx_measured:
        txt += ("; isotropy plus one tau = C_tot/k_sv (§3) make it stiffness-proportional" if not d.dampers_identified
                else "; isotropy: C_bx is the identified C_bz")
    state = NONE
    zs = cx.val("drum.vertical_mode_zeta", "shell")
    if zs:
        cbx = 2 * zs * math.sqrt(d.k_bx * d.tire.m_b_kg)
        z_alt = _fore_aft_mode(cx, m0[0], v, C_bx=cbx)[1]
        state = _verdict(z_alt, c.shell, c.ring, c.tolerance)
        txt += (f"; with C_bx = {_n(cbx, 'N s/m')} (the shell's drum zeta {zs:.3g}, frequency-independent) the "
                f"mode's zeta is {z_alt:.3g} ({_p(z_alt / c.shell - 1)})")
    rec = _shell_fx(cx)
    if rec is not None:
        from .. import spectra
        t, fx, t0, band = rec
        zz = []
        for n in (1, 2):
            try:
                zz.append((n, spectra.first_mode(t, fx, f_band=band, t_start=t0, n_modes=n).xi_fit))
            except Exception:  # a fit that does not converge is simply not quoted  # noqa: BLE001
                pass
        if zz:
            txt += ("; the shell's own value depends on how many modes its fit assumes: "
                    + ", ".join(f"{z:.3g} with {n}" for n, z in zz) + f", {c.shell:.3g} in the metric (auto)")
    if state == PARTIAL:
        txt += "; the rest is not established"
    return state, txt


def _drum_peak_to_peak(cx, c, axis):
    """The cleat's force swing against what the cam gives quasi-statically: with the rim locked the
    ring's springs in series (k_vt) turn E03's effective height w into a rise k_vt w_max, and the
    normal force tilted by the effective slope into F_x ~ F_z slope. When the quasi-static swing
    is near the shell's, what differs is the ring's dynamic response to the cam at speed."""
    res, _ = cx.case("drum_cleat")
    q = (res or {}).get("quantities", {})
    env = (res or {}).get("info", {}).get("enveloping")
    w_max, k_vt = q.get("enveloping_max_height_m"), cx.d.k_vt or cx.d.k_sv
    if not env or not w_max or not k_vt:
        return NONE, "E03's case has no quasi-static crossing to compare with (its cam is what the ring rolls on)"
    rise = k_vt * w_max
    if axis == "z":
        peak, static = q.get("peak_axle_force_N"), q.get("static_axle_force_N")
        qs = rise  # from the static level up; the quasi-static response does not swing below it
        shell_rise = None if peak is None or static is None else peak - static
        txt = (f"quasi-statically the cam lifts the road by w_max = {_n(w_max * 1e3, 'mm')} (E03's crossing), a rise "
               f"k_vt w_max = {_n(qs, 'N')} on the rim-locked springs ({_p(qs / c.shell - 1)} against the shell's "
               f"peak to peak)")
        if shell_rise:
            txt += (f"; the shell's peak rises {_n(shell_rise, 'N')} above its rolling level (x {shell_rise / qs:.3g} the "
                    f"quasi-static rise)")
    else:
        slope = np.abs(np.asarray(env["slope"], float))
        fz = cx.load_N + rise
        qs = 2 * fz * float(np.max(slope))  # the tilt's swing, forward then back
        txt = (f"quasi-statically the normal force tilted by E03's effective slope (up to {np.max(slope):.3g}) swings F_x "
               f"by 2 F_z slope_max = {_n(qs, 'N')} ({_p(qs / c.shell - 1)} against the shell's peak to peak)")
    txt += (f"; the ring at speed swings x {c.ring / qs:.3g} that, the shell x {c.shell / qs:.3g}")
    split = _contact_split(cx, c, qs, axis)
    if split is not None:
        return split[0], txt + "; " + split[1]
    if _within(qs, c.shell, c.tolerance):
        mode = "vertical belt mode, excited by the cam at speed, overshoots" if axis == "z" else \
            "fore-aft and wind-up modes, excited by the cam at speed, overshoot"
        return PARTIAL, (txt + f": the cam carries the shell's quasi-static response; the ring's {mode} where the "
                         "shell's do not. Why is not established")
    return NONE, txt


def _belt_on_contact(d, t, f_contact, axis="z"):
    """The spindle force (deviation from its rolling level) of the ring's rim-locked belt, m_b on
    k_bz || C_bz (axis "z") or k_bx || C_bx ("x"), driven by the contact force deviation
    f_contact(t) (linear between samples). Exact for the ring: its belt's x and z equations with the
    rim held are these, whatever the spin does."""
    import scipy.signal

    m = d.tire.m_b_kg
    k, c = (d.k_bz, d.C_bz) if axis == "z" else (d.k_bx, d.C_bx)
    sys_ = scipy.signal.StateSpace([[0.0, 1.0], [-k / m, -c / m]], [[0.0], [1.0 / m]], [[k, c]], [[0.0]])
    tt = np.asarray(t, float)
    _, y, _ = scipy.signal.lsim(sys_, np.asarray(f_contact, float), tt - tt[0])
    return y


def _contact_split(cx, c, qs, axis="z"):
    """Split the spindle force's miss into the contact force the cleat makes and the belt's response
    to it: the ring's spindle force is its rim-locked belt driven by its contact force, exactly; the
    same belt driven by the shell's own contact force (E03's record) is checked against the shell's
    spindle force. When it holds, what differs is the contact force. (state, text) or None without
    both records."""
    res, sig = cx.case("drum_cleat")
    key, spindle, ring_key = {"z": ("contact_force_z_N", "axle_force_N", "drum_contact"),
                              "x": ("contact_force_x_N", "axle_force_x_N", "drum_contact_x")}[axis]
    ring = cx.ring_signals.get(ring_key)
    if sig is None or key not in sig or spindle not in sig or ring is None:
        return None
    t, fc = np.asarray(sig["time_s"], float), np.asarray(sig[key], float)
    pre, after = t < 0, t >= 0  # time from the touch: before it, the rolling level
    if pre.sum() < 4 or after.sum() < 16:
        return None
    f_sp = _belt_on_contact(cx.d, t, fc - fc[pre].mean(), axis)
    ptp = float(np.ptp(f_sp[after]))
    fr = np.asarray(ring[1], float)
    springs = "k_bz, C_bz" if axis == "z" else "k_bx, C_bx"
    parts = [f"the ring's rim-locked belt (m_b on {springs}) driven by the shell's own contact F_{axis} (E03's record) "
             f"swings the spindle F_{axis} by {_n(ptp, 'N')} ({_p(ptp / c.shell - 1)} against the shell's "
             f"{_n(c.shell, 'N')}), and the ring's spindle force is that belt driven by its own contact force"]
    if axis == "z":
        ring_rise, shell_rise = float(np.max(fr) - fr[0]), float(np.max(fc[after]) - fc[pre].mean())
        parts.append(f"the shell's contact force at speed rises {_n(shell_rise, 'N')} above its rolling level (x "
                     f"{shell_rise / qs:.3g} its quasi-static crossing's k_vt w_max), the ring's {_n(ring_rise, 'N')} "
                     f"(x {ring_rise / qs:.3g})")
    else:
        ring_sw, shell_sw = float(np.ptp(fr)), float(np.ptp(fc[after]))
        parts.append(f"the shell's contact F_x swings {_n(shell_sw, 'N')} (x {shell_sw / qs:.3g} the quasi-static 2 F_z "
                     f"slope_max), the ring's {_n(ring_sw, 'N')} (x {ring_sw / qs:.3g})")
    if _within(ptp, c.shell, c.tolerance):
        parts.append("so the miss is the contact force the cleat makes at speed, not the belt's response to it; why the "
                     "shell's contact differs from its quasi-static crossing at speed is not established")
        return FULL, "; ".join(parts)
    parts.append("the belt mode does not carry the shell's spindle force from its contact force")
    return NONE, "; ".join(parts)
