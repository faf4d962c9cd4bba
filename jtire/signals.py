"""Time-domain reductions of recorded signals: peaks, free decays, linear-range slopes, steady means.

Host-side numpy/scipy, run after a simulation on its recorded arrays. SI units: t in s, x in the
signal's own unit (m, rad, N), mass in kg (or an inertia in kg m^2 for a rotation), damping C in
N s/m (or N m s/rad), omega in rad/s. Signals are 1-D arrays of equal length N. Bad input raises
jtire.errors.ConfigError naming the field. Frequency-domain tools and the damped-mode fit live in
jtire.spectra.

Free decays follow the study's two-peak method (docs/experiments.md, "Reducing free vibrations"):
delta = ln(x1/x2) from two successive peaks of x - x_final, then the exact relation
xi = delta / sqrt(4 pi^2 + delta^2). The study printed a minus sign under the root; that variant is
available as xi_formula="study" only to reproduce its numbers, and the result always names the
formula used. Two peaks are fragile against noise and sampling, so a least-squares fit of a damped
sinusoid to the whole decay is reported beside it, with their relative differences.
"""

import dataclasses
import math

import numpy as np
import scipy.signal

from jtire.errors import ConfigError
from jtire.spectra import ResultMixin, check_signal, fit_modes, from_time

XI_FORMULAS = {
    "exact": "xi = delta / sqrt(4 pi^2 + delta^2)",
    "study": "xi = delta / sqrt(4 pi^2 - delta^2)  (study's misprint; not the linear-oscillator relation)",
}


# ---- peaks --------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Peaks(ResultMixin):
    """Interpolated extrema, in time order. Arrays (P,) and (Q,); minima empty unless asked for."""

    t_max: np.ndarray
    x_max: np.ndarray
    t_min: np.ndarray
    x_min: np.ndarray


def _parabolic(t, x, idx):
    """Vertex of the parabola through samples idx-1, idx, idx+1 (any spacing). Returns (t*, x*)."""
    idx = np.asarray(idx, dtype=int)
    if idx.size == 0:
        return np.zeros(0), np.zeros(0)
    h0, h2 = t[idx - 1] - t[idx], t[idx + 1] - t[idx]
    d0, d2 = x[idx - 1] - x[idx], x[idx + 1] - x[idx]
    # x = x[i] + b s + a s^2 through (h0, d0), (h2, d2); solve the 2x2 system by Cramer's rule.
    det = h0 * h2 * (h2 - h0)
    a = (d2 * h0 - d0 * h2) / det
    b = (d0 * h2**2 - d2 * h0**2) / det
    flat = a == 0
    s = np.where(flat, 0.0, -b / np.where(flat, 1.0, 2 * a))
    s = np.clip(s, h0, h2)  # a vertex outside the bracket means the sample itself is the best guess
    return t[idx] + s, x[idx] + b * s + a * s**2


def peaks(t, x, minima=False, t_start=None, prominence=None, distance_s=None):
    """Maxima (and, with minima=True, minima) of x(t), each refined by parabolic interpolation.

    t, x: (N,), t strictly increasing. t_start: ignore samples before it. prominence: minimum
    prominence (units of x) a peak needs (scipy.signal.find_peaks); None keeps all. distance_s:
    minimum time between peaks of one kind (s); noise makes several local maxima near each true
    peak, and this keeps only the highest. End samples are never peaks. Returns Peaks.
    """
    t, x = from_time(*check_signal(t, x), t_start, 3)
    dist = None
    if distance_s is not None:
        dist = max(1, int(distance_s / float(np.median(np.diff(t)))))
    imax, _ = scipy.signal.find_peaks(x, prominence=prominence, distance=dist)
    tmax, xmax = _parabolic(t, x, imax)
    if minima:
        imin, _ = scipy.signal.find_peaks(-x, prominence=prominence, distance=dist)
        tmin, xmin = _parabolic(t, x, imin)
    else:
        tmin = xmin = np.zeros(0)
    return Peaks(t_max=tmax, x_max=xmax, t_min=tmin, x_min=xmin)


# ---- free decay ---------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class FreeDecayResult(ResultMixin):
    """Two-peak and fitted damping of a free decay. Fields that a method could not give are None
    (never NaN); two_peak_reason / fit_oscillatory say why."""

    mass: float  # kg or kg m^2, as given
    x_final: float  # level the decay is measured about
    x_final_source: str  # "given" or "tail mean"
    tail_settled: bool  # x_final within 1 % of the initial excursion of the fitted x_inf
    xi_formula: str
    two_peak_ok: bool
    two_peak_reason: str  # "" when ok
    peak_kind: str | None  # "max" or "min": which extrema of x - x_final were used
    t1: float | None
    x1: float | None  # |x - x_final| at the first peak
    t2: float | None
    x2: float | None
    delta: float | None  # logarithmic decrement ln(x1/x2)
    xi_2p: float | None
    tau_d_2p: float | None  # s
    omega_d_2p: float | None  # rad/s
    omega_n_2p: float | None
    c_crit_2p: float | None  # 2 M omega_n
    c_2p: float | None  # xi C_c
    xi_fit: float
    omega_n_fit: float
    omega_d_fit: float  # 0 when the fit is non-oscillatory (xi >= 1)
    c_crit_fit: float
    c_fit: float
    x_inf_fit: float
    fit_rms: float  # residual RMS, units of x
    fit_rms_relative: float  # fit_rms / RMS of (x - x_inf_fit)
    fit_oscillatory: bool  # fitted omega_d * record length > pi (at least half a damped period)
    fit_success: bool
    rel_diff_xi: float | None  # (xi_2p - xi_fit) / xi_fit
    rel_diff_omega_n: float | None
    n: int


def _xi_from_delta(delta, formula):
    if formula == "exact":
        return delta / math.sqrt(4 * math.pi**2 + delta**2)
    if delta >= 2 * math.pi:
        return None  # the study's formula has no real value here
    return delta / math.sqrt(4 * math.pi**2 - delta**2)


def _dominant_frequency(t, u):
    """Strongest frequency (Hz) of u(t) (resampled uniformly, no window: a decay is its own
    window), or None when the spectrum peaks at the lowest bins (a non-oscillatory decay)."""
    n = t.size
    tu = np.linspace(t[0], t[-1], n)
    uu = np.interp(tu, t, u)
    dt = tu[1] - tu[0]
    mag = np.abs(np.fft.rfft(uu - uu.mean(), 8 * n))
    f = np.fft.rfftfreq(8 * n, dt)
    lo = 8 * 2  # skip the two lowest raw bins, where a slow drift or overdamped decay lives
    i = lo + int(np.argmax(mag[lo:]))
    return None if i == lo else float(f[i])


def _two_peak(t, u, amp0, rel_prominence, f_dom, formula):
    """Two successive same-kind extrema of u = x - x_final; returns dict of fields or reason."""
    dist = 0.5 / f_dom if f_dom else None
    pk = peaks(t, u, minima=True, prominence=rel_prominence * amp0, distance_s=dist)
    # keep only extrema on the right side of the final level (a max above it, a min below it)
    cand = [(tt, abs(v), "max") for tt, v in zip(pk.t_max, pk.x_max) if v > 0]
    cand += [(tt, abs(v), "min") for tt, v in zip(pk.t_min, pk.x_min) if v < 0]
    cand.sort()
    if not cand:
        return {"two_peak_reason": "no clear peak after t_start (overdamped or critically damped?)"}
    t1, x1, kind = cand[0]
    nxt = [c for c in cand[1:] if c[2] == kind]
    if not nxt:
        return {"two_peak_reason": f"only one clear {kind} after t_start (heavily damped: no second peak)"}
    t2, x2, _ = nxt[0]
    delta = math.log(x1 / x2)
    if delta <= 0:
        return {"two_peak_reason": f"second {kind} not smaller than the first (delta = {delta:.3g})"}
    xi = _xi_from_delta(delta, formula)
    if xi is None or xi >= 1:
        return {"two_peak_reason": f"delta = {delta:.3g} gives no damping ratio below 1 with this formula"}
    tau = t2 - t1
    wd = 2 * math.pi / tau
    return dict(two_peak_ok=True, two_peak_reason="", peak_kind=kind, t1=t1, x1=x1, t2=t2, x2=x2,
                delta=delta, xi_2p=xi, tau_d_2p=tau, omega_d_2p=wd, omega_n_2p=wd / math.sqrt(1 - xi**2))


def free_decay(t, x, mass, t_start=None, x_final=None, xi_formula="exact", rel_prominence=0.03,
               tail_fraction=0.1) -> FreeDecayResult:
    """Damping of a free decay x(t) by two peaks and by a damped-sinusoid fit.

    t, x: (N,) the recorded decay (t strictly increasing, s). mass: M for C_c = 2 M omega_n (kg or
    kg m^2), > 0. t_start: release time; earlier samples (the hold, the release transient) are
    dropped. x_final: level the decay settles to; None takes the mean of the last tail_fraction of
    the record, which must then have settled (see tail_settled). xi_formula: "exact" or "study".
    rel_prominence: a peak counts when its prominence is at least this fraction of the initial
    excursion max|x - x_final|; the first such extremum after t_start and the next one of the
    same kind (max or min) are the two peaks.
    The fit (jtire.spectra.fit_modes) is x_inf + e^{-xi wn s}(a cos wd s + b sin(wd s)/wd), with
    its cosh/sinh continuation for xi >= 1, over all samples from t_start, started from the
    two-peak result and the spectral peak. An overdamped or critically damped decay therefore
    gives a fitted xi >= 1 and two_peak_ok = False with a reason; it does not raise.
    """
    t, x = check_signal(t, x, "t", "x", min_len=8)
    if not (np.isfinite(mass) and mass > 0):
        raise ConfigError(f"mass = {mass}: must be > 0 (kg, or kg m^2 for a rotation)")
    if xi_formula not in XI_FORMULAS:
        raise ConfigError(f"xi_formula = {xi_formula!r}: must be one of {sorted(XI_FORMULAS)}")
    if not 0 < tail_fraction <= 0.5:
        raise ConfigError(f"tail_fraction = {tail_fraction}: must be in (0, 0.5]")
    if t_start is not None:
        keep = t >= t_start
        if keep.sum() < 8:
            raise ConfigError(f"t_start = {t_start:g}: leaves {keep.sum()} samples, need >= 8")
        t, x = t[keep], x[keep]
    n_tail = max(2, int(round(tail_fraction * t.size)))
    if x_final is None:
        x_final, source = float(np.mean(x[-n_tail:])), "tail mean"
    else:
        x_final, source = float(x_final), "given"
    u = x - x_final
    amp0 = float(np.max(np.abs(u)))
    if amp0 == 0:
        raise ConfigError("x: is constant after t_start, there is no decay to reduce")

    f_dom = _dominant_frequency(t, u)
    tp = _two_peak(t, u, amp0, rel_prominence, f_dom, xi_formula)
    fields = dict.fromkeys(["peak_kind", "t1", "x1", "t2", "x2", "delta", "xi_2p", "tau_d_2p",
                            "omega_d_2p", "omega_n_2p", "c_crit_2p", "c_2p"])
    fields.update(two_peak_ok=False)
    fields.update(tp)
    if fields["two_peak_ok"]:
        fields["c_crit_2p"] = 2 * mass * fields["omega_n_2p"]
        fields["c_2p"] = fields["xi_2p"] * fields["c_crit_2p"]

    # Starts for the fit: the two-peak result, the spectral peak, and for a decay without
    # oscillation a few damping ratios whose slow pole matches the observed 1/e time.
    starts = []
    if fields["two_peak_ok"]:
        starts.append((fields["omega_n_2p"], min(fields["xi_2p"], 0.95)))
    if f_dom:
        starts += [(2 * math.pi * f_dom, 0.02), (2 * math.pi * f_dom, 0.2)]
    below = np.nonzero(np.abs(u) < amp0 / math.e)[0]
    i0 = int(np.argmax(np.abs(u)))
    after = below[below > i0]
    t_e = (t[after[0]] - t[i0]) if after.size else (t[-1] - t[0])
    r = 1.0 / max(t_e, 1e-12 * (t[-1] - t[0]))
    for z in (0.7, 1.0, 2.0, 5.0):
        starts.append((r / (z - math.sqrt(max(z * z - 1, 0.0))) if z >= 1 else r / z, z))
    best = None
    for wn0, z0 in starts:
        fit = fit_modes(t, x, [wn0], [z0], offset=True)
        if best is None or fit.rms < best.rms:
            best = fit
    wn, xi, wd = float(best.omega_n[0]), float(best.xi[0]), float(best.omega_d[0])
    # the tail mean is a fair final level only if it agrees with the fitted asymptote
    settled = bool(abs(best.offset - x_final) <= 0.01 * amp0)
    rel_xi = rel_wn = None
    if fields["two_peak_ok"]:
        rel_xi = (fields["xi_2p"] - xi) / xi
        rel_wn = (fields["omega_n_2p"] - wn) / wn
    return FreeDecayResult(
        mass=float(mass), x_final=x_final, x_final_source=source, tail_settled=settled,
        xi_formula=XI_FORMULAS[xi_formula], **fields, xi_fit=xi, omega_n_fit=wn, omega_d_fit=wd,
        c_crit_fit=2 * mass * wn, c_fit=xi * 2 * mass * wn, x_inf_fit=best.offset, fit_rms=best.rms,
        fit_rms_relative=best.rms_relative, fit_oscillatory=bool(wd * (t[-1] - t[0]) > math.pi),
        fit_success=best.success,
        rel_diff_xi=rel_xi, rel_diff_omega_n=rel_wn, n=int(t.size))


# ---- slopes -------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class SlopeResult(ResultMixin):
    """Least-squares line y = slope x + intercept over a stated x range."""

    slope: float
    intercept: float
    r2: float  # coefficient of determination
    stderr: float  # standard error of the slope
    n: int
    x_lo: float
    x_hi: float


def linear_slope(x, y, x_range=None) -> SlopeResult:
    """Slope of y against x over x_range = (lo, hi) inclusive (None: all points); needs >= 3."""
    x, y = (np.asarray(v, dtype=float) for v in (x, y))
    if x.ndim != 1 or y.shape != x.shape or not np.all(np.isfinite(x) & np.isfinite(y)):
        raise ConfigError("x, y: must be finite 1-D arrays of equal length")
    lo, hi = (-np.inf, np.inf) if x_range is None else (float(x_range[0]), float(x_range[1]))
    if not lo < hi:
        raise ConfigError(f"x_range = ({lo:g}, {hi:g}): must have lo < hi")
    m = (x >= lo) & (x <= hi)
    n = int(m.sum())
    if n < 3:
        raise ConfigError(f"x_range = ({lo:g}, {hi:g}): holds {n} points, need at least 3")
    xs, ys = x[m], y[m]
    # centred sums keep the slope exact for large offsets in x
    xc, yc = xs - xs.mean(), ys - ys.mean()
    sxx = float(xc @ xc)
    if sxx == 0:
        raise ConfigError(f"x_range = ({lo:g}, {hi:g}): all x equal, slope undefined")
    slope = float(xc @ yc) / sxx
    intercept = float(ys.mean() - slope * xs.mean())
    res = ys - (slope * xs + intercept)
    ss_res, ss_tot = float(res @ res), float(yc @ yc)
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else 1.0
    return SlopeResult(slope=slope, intercept=intercept, r2=r2, stderr=math.sqrt(ss_res / (n - 2) / sxx),
                       n=n, x_lo=float(xs.min()), x_hi=float(xs.max()))


@dataclasses.dataclass(frozen=True)
class SecantResult(ResultMixin):
    """Secant y/x at the first point where the curve reaches `at` (along x or y)."""

    secant: float
    x_at: float
    y_at: float


def secant(x, y, at, along="y") -> SecantResult:
    """Secant y/x where the curve first reaches along=at, linearly interpolated between samples.

    E.g. a load-deflection curve (x deflection m, y force N), along="y", at=50e3: the stiffness
    50 kN / deflection at 50 kN.
    """
    x, y = (np.asarray(v, dtype=float) for v in (x, y))
    if x.ndim != 1 or y.shape != x.shape or x.size < 2:
        raise ConfigError("x, y: must be 1-D arrays of equal length >= 2")
    if along not in ("x", "y"):
        raise ConfigError(f"along = {along!r}: must be 'x' or 'y'")
    v = y if along == "y" else x
    d = v - at
    hit = np.nonzero(d[:-1] * d[1:] <= 0)[0]
    if hit.size == 0:
        raise ConfigError(f"at = {at:g}: outside the recorded {along} range [{v.min():g}, {v.max():g}]")
    i = int(hit[0])
    w = 0.0 if d[i] == d[i + 1] else d[i] / (d[i] - d[i + 1])
    xa, ya = x[i] + w * (x[i + 1] - x[i]), y[i] + w * (y[i + 1] - y[i])
    if xa == 0:
        raise ConfigError(f"at = {at:g}: reached at x = 0, where the secant y/x is undefined")
    return SecantResult(secant=float(ya / xa), x_at=float(xa), y_at=float(ya))


def tangent(x, y, at_y, half_width) -> float:
    """dy/dx where the curve y(x) passes y = at_y: the slope at x(at_y) of a quadratic fitted to
    the points with |y - at_y| <= half_width (needs >= 3; a quadratic, not a chord, so a curve
    that stiffens is not read as its secant over the window)."""
    x, y = (np.asarray(v, dtype=float) for v in (x, y))
    m = np.isfinite(x) & np.isfinite(y) & (np.abs(y - at_y) <= half_width)
    if int(m.sum()) < 3 or np.ptp(x[m]) == 0:
        raise ConfigError(f"at = {at_y:g} +- {half_width:g}: holds {int(m.sum())} distinct points, need at least 3")
    xs, ys = x[m], y[m]
    x0 = float(np.interp(at_y, np.sort(ys), xs[np.argsort(ys)]))
    scale = float(np.ptp(xs))
    c = np.polyfit((xs - x0) / scale, ys, min(2, int(m.sum()) - 1))
    return float(c[-2] / scale)


# ---- steady state -------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class SteadyResult(ResultMixin):
    """Mean of a signal over a time window and how much it still drifts there."""

    mean: float
    std: float
    drift_per_s: float  # slope of a linear fit over the window (units of y per s)
    drift_stderr: float  # its standard error
    drift_relative: float  # drift_per_s * window length / |mean| (inf if mean == 0 and drifting)
    t0: float
    t1: float
    n: int


def steady_mean(t, y, window=None) -> SteadyResult:
    """Mean, spread and linear drift of y over window = (t0, t1) s inclusive (None: everything)."""
    t, y = check_signal(t, y)
    t0, t1 = (float(t[0]), float(t[-1])) if window is None else (float(window[0]), float(window[1]))
    if not t0 < t1:
        raise ConfigError(f"window = ({t0:g}, {t1:g}): must have t0 < t1")
    fit = linear_slope(t, y, (t0, t1))
    m = (t >= t0) & (t <= t1)
    ys = y[m]
    mean = float(ys.mean())
    span = t1 - t0
    if mean != 0:
        rel = fit.slope * span / abs(mean)
    else:
        rel = 0.0 if fit.slope == 0 else math.inf
    return SteadyResult(mean=mean, std=float(ys.std(ddof=1)), drift_per_s=fit.slope,
                        drift_stderr=fit.stderr, drift_relative=float(rel), t0=t0, t1=t1, n=fit.n)


def is_steady(result: SteadyResult, tol: float) -> bool:
    """True when the drift over the window is at most tol of |mean| (|drift_relative| <= tol)."""
    if not tol >= 0:
        raise ConfigError(f"tol = {tol}: must be >= 0")
    return bool(abs(result.drift_relative) <= tol)


N_BLOCKS = 10  # batch means for the standard error of the hub-force mean


def block_stderr(y, n_blocks: int = N_BLOCKS) -> float:
    """Standard error of the mean of a correlated series by batch means (n_blocks equal blocks)."""
    y = np.asarray(y, float)
    n = len(y) // n_blocks
    if n < 2:
        raise ConfigError(f"series of {len(y)} samples: need at least {2 * n_blocks} for {n_blocks} blocks")
    means = y[: n * n_blocks].reshape(n_blocks, n).mean(axis=1)
    return float(means.std(ddof=1) / np.sqrt(n_blocks))
