"""Diagnosis checks of the drum-cleat's metrics (`diagnosis`): the vertical and fore-aft modes and the
peak-to-peak forces, the latter split into the contact force and the belt's response to it. Each
check takes the condition's context and the comparison row and returns (state, text)."""

import inspect
import math

import numpy as np

from .. import spectra
from .diagnosis_base import FULL, NONE, PARTIAL, _n, _p, _verdict, _within
from .modes import belt_vertical_mode, fore_aft_modes


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
    if np.count_nonzero(t >= t0) < 16:
        return None
    return spectra.spectrum_peaks(t, fx, band, t_start=t0, n=3) or None


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
