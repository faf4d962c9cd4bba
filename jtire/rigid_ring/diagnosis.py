"""Why the populated rigid ring and the shell model disagree (docs/rigid-ring.md §8): one markdown
bullet per FAILed comparison row, naming the cause with the numbers that show it, or saying plainly
that the cause was not established.

`diagnose(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None)` gives the bullets,
`explain(...)` (same arguments) the Diagnosis records behind them (metric, state, text). Both work from
  * the comparison rows (`validation.compare`: the shell's and the ring's value of every metric),
  * the condition's table row and what `params.derive` makes of it, put through the ring's own
    linearized equations (`modes`: numpy, the same equations as `model.RigidRing`, no simulation),
  * optionally the characterization folder `char_dir` (the shell's case folders: the E02
    load-deflection curve, the E04 drop record's reductions, the E03 spindle F_x record, the E10
    measurement window) and the shell's validation signals (`shell_signals`, as `validate.validate`
    returns them: the slip-step F_y against distance).
Every number in a bullet is computed from those inputs. A cause counts as established (FULL) when
the mechanism named, put into numbers, accounts for the disagreement within the metric's own
tolerance; PARTIAL when it closes more than half of it (the bullet then says the rest is not
established); otherwise (NONE) the bullet starts "cause not established" and gives what was checked.

Causes the checks look for (each found on the default mesh; see the module's tests for the cases):
  * drop bounce frequency and peak F_z: the load-deflection curve stiffens (tangent stiffness at
    the load above the secant k_sv the linear ring uses);
  * damping ratios: the damping value the table chose (two-peak or fit) against the one the shell's
    metric is (the fit), the ring's frequency entering zeta = C / (2 m omega), and the single time
    constant tau = C_tot / k_sv of §3 that makes the ring's belt damping grow with frequency;
  * drum fore-aft mode: the isotropy assumption k_bx = k_bz (no fore-aft sidewall test);
  * lateral release: the reduced lateral model (m_tot on k_l) against the belt's own DOFs;
  * slip step: speed dependence of the shell, the E10 window not yet steady, the linear k_m against
    the curved M_z(alpha), and a first-order lag over sigma = k_f / k_l against a contact patch of
    finite length (stretched string: sigma_string = sigma - a).
"""

import csv
import dataclasses
import inspect
import json
import math
from pathlib import Path

import numpy as np

from .params import derive

from .modes import belt_vertical_mode, fore_aft_modes, lateral_modes, string_step_s63, vertical_modes  # noqa: F401

# ------------------------------------------------------------------ the shell's case folders


def _case(char_dir, experiment, load_N, pressure_Pa):
    """(result.json dict, signals {column: array} or None) of an experiment's case at a condition
    in a characterization folder, or (None, None)."""
    if char_dir is None:
        return None, None
    for d in sorted((Path(char_dir) / experiment / "cases").glob("*")):
        f = d / "result.json"
        if not f.exists():
            continue
        res = json.loads(f.read_text())
        c = res.get("condition", {})
        if abs(c.get("pressure_Pa", -1) - pressure_Pa) < 1e-3 and ("load_N" not in c or abs(c["load_N"] - load_N) < 1e-6):
            sig = None
            if (d / "signals.csv").exists():
                rows = list(csv.DictReader((d / "signals.csv").open()))
                if rows:
                    sig = {k: np.array([float(r[k]) if r[k] not in ("", "None") else np.nan for r in rows])
                           for k in rows[0]}
            return res, sig
    return None, None


@dataclasses.dataclass
class _Context:
    char: object
    row: object
    d: object
    rows: dict  # metric -> Comparison
    char_dir: object
    shell_signals: dict
    load_N: float
    pressure_Pa: float
    _cache: dict = dataclasses.field(default_factory=dict)

    def case(self, experiment):
        if experiment not in self._cache:
            self._cache[experiment] = _case(self.char_dir, experiment, self.load_N, self.pressure_Pa)
        return self._cache[experiment]

    def val(self, metric, side):
        c = self.rows.get(metric)
        return None if c is None else getattr(c, side)

    def rederive(self, **q):
        """derive() of this condition's row with some quantities replaced (SI keys of the table)."""
        return derive(dataclasses.replace(self.row, q=self.row.q | q), self.char.tire)

    def load_curve(self):
        """(F (n,), deflection (n,), source) of the load-deflection curve at this pressure: the E02
        record when the case folder has it, else the table's secant k_sv over the grid's loads
        (through the origin); None with fewer than two loads."""
        res, sig = self.case("vertical_stiffness")
        if sig is not None and "load_N" in sig and "deflection_m" in sig:
            F, x = sig["load_N"], sig["deflection_m"]
            ok = np.isfinite(F) & np.isfinite(x)
            if ok.sum() >= 3:
                return F[ok], x[ok], "the E02 load-deflection record"
        pts = sorted((r.load_N, r.load_N / r.get("k_sv_N_per_m")) for r in self.char.rows
                     if math.isclose(r.pressure_Pa, self.pressure_Pa, rel_tol=1e-6) and r.get("k_sv_N_per_m"))
        if len(pts) < 2:
            return None
        F, x = (np.array([0.0] + [p[i] for p in pts]) for i in (0, 1))
        return F, x, "the table's k_sv over the grid's loads"

    def tangent_stiffness(self):
        """(k_t at the condition's load, source) from load_curve(), or None."""
        c = self.load_curve()
        if c is None:
            return None
        F, x, src = c
        kt = np.gradient(F, x)
        return float(np.interp(self.load_N, F, kt)), src


# ------------------------------------------------------------------ formatting


def _p(x):
    return f"{100 * x:+.1f} %"


def _n(x, unit="", digits=4):
    if x is None:
        return "—"
    a = abs(x)
    for f, pre in ((1e6, "M"), (1e3, "k")):
        if a >= f and unit and unit[0] in "N":
            return f"{x / f:.{digits}g} {pre}{unit}"
    return f"{x:.{digits}g}" + (f" {unit}" if unit else "")


def _within(x, y, tol):
    return x is not None and y is not None and y != 0 and abs(x / y - 1) <= tol


# ------------------------------------------------------------------ one check per metric family
# Each returns (state, text): FULL when the named mechanism, in numbers, accounts for the
# disagreement within the metric's tolerance; PARTIAL when it accounts for most of it (the text then
# says what is left unexplained); NONE when it does not (the bullet then says "cause not established").

FULL, PARTIAL, NONE = "full", "partial", "none"


def _verdict(pred, shell, ring, tol):
    """FULL if pred is within tol of shell, PARTIAL if it closes more than half the ring's gap
    (in log terms, so a factor and its inverse count alike)."""
    if _within(pred, shell, tol):
        return FULL
    if pred and shell and ring and pred / shell > 0 and ring / shell > 0 and \
            abs(math.log(pred / shell)) < 0.5 * abs(math.log(ring / shell)):
        return PARTIAL
    return NONE


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


def _drop_bounce_f(cx, c):
    d = cx.d
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
    return _damping(cx, c, "C_tot_Ns_per_m", "C_tot_2p_Ns_per_m", "C_tot_fit_Ns_per_m", "drop.bounce_f_Hz",
                    "drop_test")


def _lateral_zeta(cx, c):
    return _damping(cx, c, "C_l_Ns_per_m", "C_l_2p_Ns_per_m", "C_l_fit_Ns_per_m", "lateral.f_Hz",
                    "lateral_stiffness")


def _damping(cx, c, key, key_2p, key_fit, f_metric, experiment):
    """A free-decay damping ratio: the shell's metric is its damped-sine fit, the ring carries the
    table's chosen value (the two-peak one when the decay had two clean peaks), and zeta = C/(2 m
    omega) is taken at each side's own frequency."""
    C, c2p, cfit = cx.row.get(key), cx.row.get(key_2p), cx.row.get(key_fit)
    if C is None or not cfit:
        return NONE, f"the table lacks {key_fit} to compare the damping the ring carries with the shell's fit"
    which = "two-peak" if c2p is not None and math.isclose(C, c2p, rel_tol=1e-9) else "chosen"
    f_s, f_r = cx.val(f_metric, "shell"), cx.val(f_metric, "ring")
    obs = c.ring / c.shell
    ratio_c = C / cfit
    txt = (f"the ring carries the {which} {key.split('_N')[0]} = {_n(C, 'N s/m')}, x {ratio_c:.3g} the damped-sine fit "
           f"{_n(cfit, 'N s/m')} the shell's zeta comes from")
    pred_ratio = ratio_c
    if f_s and f_r:
        pred_ratio *= f_s / f_r
        txt += (f"; and zeta = C/(2 m omega) is taken at the ring's {_n(f_r, 'Hz')}, not the shell's {_n(f_s, 'Hz')} "
                f"(x {f_s / f_r:.3g})")
    txt += f": together x {pred_ratio:.3g}, observed x {obs:.3g}"
    state = _verdict(pred_ratio, obs, 1.0, c.tolerance)
    res, _ = cx.case(experiment)
    air = (res or {}).get("checks", {}).get("airborne_after_first_contact_fraction")
    if air and which == "two-peak" and abs(ratio_c - 1) > c.tolerance:
        txt += (f". The two methods differ on the shell's own record: {100 * air:.0f} % of it after first contact is "
                f"airborne, a decay that is not that of a linear oscillator")
    if state == PARTIAL:
        txt += "; the rest is not established"
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
           f"shell's {_n(c.shell, 'N')}); on the ring's linear k_sv it gives {_n(p_lin, 'N')} (ring {_n(c.ring, 'N')})")
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


def _fore_aft_mode(cx, target, speed, **kw):
    """The mode of fore_aft_modes() nearest target (Hz), or the one with the largest x_b share."""
    ms = fore_aft_modes(cx.d, speed, **kw)
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
    parts = [f"the ring's fore-aft / wind-up mode at {_n(c.ring, 'Hz')} rests on the isotropy assumption k_bx = k_bz = "
             f"{_n(d.k_bz, 'N/m')} (§3: no test measures k_bx)"]
    grid = np.geomspace(0.25, 8.0, 121)
    start = int(np.argmin(abs(grid - 1.0)))
    g, fr = [], []
    for direction in (range(start, grid.size), range(start, -1, -1)):  # follow the mode from k_bx = k_bz
        f_prev = m0[0]
        for i in direction:
            f_prev = _fore_aft_mode(cx, f_prev, v, k_bx=grid[i] * d.k_bz)[0]
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
        parts.append(f"k_bx = {_n(mult * d.k_bz, 'N/m')} ({mult:.3g} x k_bz) puts it at the shell's {_n(c.shell, 'Hz')}")
        state = FULL
    else:
        parts.append(f"no k_bx within {grid[0]:g}..{grid[-1]:g} x k_bz reaches the shell's {_n(c.shell, 'Hz')} "
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
    txt = (f"of the ring's modal zeta {m0[1]:.3g}, the rolling tread's slip lag (contact relaxation length a, "
           f"V = {v:.3g} m/s) gives {z_none:.3g} alone, C_btheta {z_nobx - z_none:.2g}, and C_bx = tau k_bx = "
           f"{_n(d.C_bx, 'N s/m')} the rest: isotropy plus one tau = C_tot/k_sv (§3) make it stiffness-proportional, "
           f"zeta_bx = pi f_bx tau = {z_bx:.3g} at f_bx = {_n(f_bx, 'Hz')}")
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


def _lateral_f(cx, c):
    d = cx.d
    f_red = lateral_modes(d, "reduced")[0][0]
    m_tot = d.tire.m_tot_kg
    k_dyn = m_tot * (2 * math.pi * c.shell) ** 2
    txt = (f"the validation's reduced lateral model puts m_tot = {m_tot:.4g} kg on k_l = {_n(d.k_l, 'N/m')} "
           f"({_n(f_red, 'Hz')}); for the shell's frequency that mass needs m_tot (2 pi f)^2 = {_n(k_dyn, 'N/m')} = "
           f"{k_dyn / d.k_l:.3g} x k_l")
    if None in (d.k_by, d.k_cy, d.k_bgamma, d.C_by, d.C_cy, d.C_bgamma):
        return NONE, txt + "; the ring variant's inputs (k_by, k_bgamma, k_cy) are missing"
    f_ring = lateral_modes(d, "ring")[0][0]
    txt += (f"; in the ring variant (belt y_b, gamma_b on k_by, k_bgamma and the tread k_cy; the same static k_l) the "
            f"belt's {d.tire.m_b_kg:.4g} kg moves less than the rim and the mode is at {_n(f_ring, 'Hz')} "
            f"({_p(f_ring / c.shell - 1)})")
    state = _verdict(f_ring, c.shell, c.ring, c.tolerance)
    if state == PARTIAL:
        txt += (f"; the remaining stiffness ratio (f_shell/f_variant)^2 = {(c.shell / f_ring) ** 2:.3g} is not "
                f"established (rate stiffening of the sidewall rubber is a candidate)")
    return state, txt


def _speeds(cx):
    return sorted({float(m.split(".")[0][5:]) for m in cx.rows if m.startswith("step_")})


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
    if curve:
        parts.append(f"the ring's {key} {_n(abs(c.ring), unit)} is the linear {sym} sin(alpha) at "
                     f"{math.degrees(alpha):.3g} deg; the cornering curve{at} has {_n(curve, unit)} there "
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
    parts, state = [f"the ring is a first-order lag over sigma = k_f/k_l = {_n(d.sigma, 'm')} at any speed "
                    f"(s63 = {_n(c.ring, 'm')})"], NONE
    s_str = string_step_s63(d.sigma, d.a) if d.sigma and d.a else None
    if s_str:
        parts.append(f"a contact patch of half length a = {_n(d.a, 'm')} builds part of the force inside its own "
                     f"length: a stretched string with the same k_f/k_l (sigma_string = sigma - a = "
                     f"{_n(d.sigma - d.a, 'm')}) reaches 63 % at {_n(s_str, 'm')} ({s_str / d.sigma:.2g} sigma; "
                     f"{_p(s_str / c.shell - 1)} against the shell)")
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
    txt = "; ".join(parts)
    if state == PARTIAL:
        txt += "; the rest is not established"
    return state, txt


CHECKS = {
    "drop.static_deflection_m": _drop_static,
    "drop.bounce_f_Hz": _drop_bounce_f,
    "drop.bounce_zeta": _drop_zeta,
    "drop.peak_F_z_N": _drop_peak,
    "drop.belt_mode_Hz": _belt_mode,
    "drum.vertical_mode_Hz": _drum_vertical_f,
    "drum.vertical_mode_zeta": _drum_vertical_zeta,
    "drum.fore_aft_mode_Hz": _drum_fore_aft_f,
    "drum.fore_aft_mode_zeta": _drum_fore_aft_zeta,
    "lateral.f_Hz": _lateral_f,
    "lateral.zeta": _lateral_zeta,
}


def _check_for(metric):
    if metric in CHECKS:
        return CHECKS[metric]
    if metric.startswith("step_"):
        tail = metric.split(".", 1)[1]
        if tail == "F_y_steady_N":
            return lambda cx, c: _step_force(cx, c, "F_y")
        if tail == "M_z_steady_Nm":
            return lambda cx, c: _step_force(cx, c, "M_z")
        if tail == "s63_m":
            return _step_s63
    return None


@dataclasses.dataclass(frozen=True)
class Diagnosis:
    metric: str
    rel_diff: float | None  # ring / shell - 1
    state: str  # FULL, PARTIAL or NONE (cause not established)
    text: str

    def bullet(self) -> str:
        rel = "" if self.rel_diff is None else f" {_p(self.rel_diff)}"
        text = self.text if self.state != NONE else "cause not established: " + self.text
        return f"- {self.metric}{rel}: {text}"


def explain(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None) -> list:
    """A Diagnosis for every FAIL row of `rows` (validation.compare's Comparison list), in their
    order, at the condition (load_N, pressure_Pa) of the characterization `char` (table.
    read_characterization). char_dir: the characterization folder, whose case folders add the
    shell's own records (None: the table alone). shell_signals: the shell's validation signals
    ({"step_5": (distance, F_y SAE), ...}, as validate.validate returns them), optional."""
    fails = [c for c in rows if c.verdict == "FAIL"]
    if not fails:
        return []
    row = char.row(load_N, pressure_Pa)
    if row is None:
        return [Diagnosis(c.metric, c.rel_diff, NONE, "no table row at this condition") for c in fails]
    cx = _Context(char, row, derive(row, char.tire), {c.metric: c for c in rows}, char_dir, shell_signals or {},
                  load_N, pressure_Pa)
    out = []
    for c in fails:
        check = _check_for(c.metric)
        if check is None:
            state, text = NONE, "no diagnosis is implemented for this metric"
        else:
            try:
                state, text = check(cx, c)
            except (TypeError, ValueError, ZeroDivisionError, KeyError, AttributeError, IndexError, OSError,
                    np.linalg.LinAlgError) as e:  # a missing or malformed input: say so, never stop the report
                state, text = NONE, f"the check could not run ({type(e).__name__}: {e})"
        out.append(Diagnosis(c.metric, c.rel_diff, state, text))
    return out


def diagnose(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None) -> list:
    """One markdown bullet per FAIL row (see explain): "- metric +x %: cause, with its numbers", or
    "- metric +x %: cause not established: what was checked, with its numbers"."""
    return [d.bullet() for d in explain(char, load_N, pressure_Pa, rows, char_dir, shell_signals)]
