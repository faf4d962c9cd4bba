"""Frequency content of recorded signals: padded spectra, spectral peaks and modal fits.

Host-side reductions (numpy/scipy) that run after a simulation. Times in s, frequencies in Hz,
angular frequencies in rad/s. Signals are 1-D arrays of equal length N.

Two estimates of a mode's frequency are given side by side:
- the peak of a Hann-windowed, zero-padded spectrum (`amplitude_spectrum`), refined by a
  quadratic fit to the log magnitude of the three samples around the maximum. Zero padding does
  not add information, but it samples the spectrum finely enough that the interpolated peak is
  limited by the signal (noise, neighbouring modes), not by the raw bin spacing 1/T. For a single
  damped sinusoid the windowed spectrum is symmetric about the damped frequency f_d (the envelope
  is real), so the peak estimates f_d, not the undamped f_n.
- a least-squares fit of a sum of damped sinusoids to the time signal (`fit_modes`), started from
  the spectral peaks. It returns f_d, f_n and the damping ratio of each mode.
"""

import dataclasses
import math

import numpy as np
import scipy.fft
import scipy.optimize
import scipy.signal

from jtire.errors import ConfigError

# Above this many points a full padded FFT is refused: give a band (chirp-z zoom) instead.
_MAX_FFT = 1 << 24
# Sampling is "uniform" when every step is within this relative distance of the mean step.
_UNIFORM_RTOL = 1e-6
# Damping ratios the modal fit may take (ln-parameter box).
_XI_MIN, _XI_MAX = 1e-6, 1e3
# With n_modes=None, a further mode joins the modal fit only if it removes this fraction of the
# residual RMS (a mode fitted to white noise removes only about 2/N of it); at most this many.
_AUTO_MODE_GAIN, _AUTO_MODE_MAX = 0.2, 4


class ResultMixin:
    """`as_dict(prefix)` for the reduction results (flat, JSON-ready via jtire.io)."""

    def as_dict(self, prefix: str = "") -> dict:
        out = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if isinstance(v, np.generic):
                v = v.item()
            elif isinstance(v, np.ndarray):
                v = v.tolist()
            out[f"{prefix}_{f.name}" if prefix else f.name] = v
        return out


def check_signal(t, y, name_t="t", name_y="y", min_len=3):
    """Validate and convert a pair of 1-D series; t strictly increasing. Returns float arrays."""
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or y.shape != t.shape:
        raise ConfigError(f"{name_t}, {name_y}: must be 1-D of equal length, got {t.shape} and {y.shape}")
    if t.size < min_len:
        raise ConfigError(f"{name_t}: has {t.size} samples, need at least {min_len}")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(y))):
        raise ConfigError(f"{name_t}, {name_y}: must be finite (no NaN or inf)")
    if np.any(np.diff(t) <= 0):
        raise ConfigError(f"{name_t}: must be strictly increasing")
    return t, y


def from_time(t, y, t_start, min_len):
    """The samples at t >= t_start (all of them when t_start is None); ConfigError if fewer
    than min_len remain."""
    if t_start is None:
        return t, y
    keep = t >= t_start
    if keep.sum() < min_len:
        raise ConfigError(f"t_start = {t_start:g}: leaves {keep.sum()} samples, need >= {min_len}")
    return t[keep], y[keep]


def uniform_step(t, name="t") -> float:
    """The sampling step of a uniformly sampled time axis (s); ConfigError if not uniform."""
    dt = np.diff(t)
    mean = float(np.mean(dt))
    if np.max(np.abs(dt - mean)) > _UNIFORM_RTOL * mean:
        raise ConfigError(f"{name}: must be uniformly sampled (steps within {_UNIFORM_RTOL:g} relative)")
    return mean


def _check_band(f_band, fs):
    if f_band is None:
        return None
    lo, hi = (float(v) for v in f_band)
    if not (0.0 <= lo < hi <= fs / 2):
        raise ConfigError(f"f_band = ({lo:g}, {hi:g}): must satisfy 0 <= lo < hi <= fs/2 = {fs / 2:g} Hz")
    return lo, hi


def amplitude_spectrum(t, y, pad_to_resolution=0.01, f_band=None, window="hann", detrend="linear"):
    """Magnitude of the windowed, zero-padded DFT of y(t).

    t, y: (N,) uniformly sampled. pad_to_resolution: wanted spacing of the output grid (Hz); the
    signal is zero padded (or, with a band, evaluated by chirp-z on the band) so the spacing is at
    most this. f_band: (lo, hi) Hz to evaluate, or None for 0..fs/2. window: any scipy window name
    ("hann", "boxcar", ...). detrend: "linear", "constant" (mean) or None.
    Returns (f (M,) Hz, magnitude (M,), raw_resolution_Hz = 1/(N dt), grid spacing Hz).
    """
    t, y = check_signal(t, y)
    dt = uniform_step(t)
    fs = 1.0 / dt
    n = t.size
    if not pad_to_resolution > 0:
        raise ConfigError(f"pad_to_resolution = {pad_to_resolution}: must be > 0 Hz")
    band = _check_band(f_band, fs)
    if detrend is not None:
        # Remove the static level (and drift) so the DC leakage does not mask the mode.
        y = scipy.signal.detrend(y, type=detrend)
    yw = y * scipy.signal.get_window(window, n, fftbins=False)
    raw = fs / n
    if band is not None:
        m = max(int(math.ceil((band[1] - band[0]) / pad_to_resolution)) + 1, 3)
        spec = scipy.signal.zoom_fft(yw, [band[0], band[1]], m, fs=fs, endpoint=True)
        f = np.linspace(band[0], band[1], m)
        step = (band[1] - band[0]) / (m - 1)
    else:
        # no padding when the raw bins already meet the spacing (the plain FFT, as the study had)
        need = int(math.ceil(fs / pad_to_resolution))
        n_fft = n if need <= n else scipy.fft.next_fast_len(need, real=True)
        if n_fft > _MAX_FFT:
            raise ConfigError(
                f"pad_to_resolution = {pad_to_resolution:g} Hz: needs {n_fft} FFT points "
                f"(max {_MAX_FFT}); give f_band to zoom on a band instead")
        spec = scipy.fft.rfft(yw, n_fft)
        f = scipy.fft.rfftfreq(n_fft, dt)
        step = fs / n_fft
    return f, np.abs(spec), raw, step


def interpolate_peak(f, mag, i):
    """Quadratic fit to log magnitude at samples i-1, i, i+1 of a uniform grid.

    Returns (f_peak, mag_peak). On a Gaussian-like main lobe the log is close to a parabola, so
    this refines the peak well below the grid spacing. At the grid ends returns the sample.
    """
    if i <= 0 or i >= len(f) - 1 or np.any(mag[i - 1:i + 2] <= 0):
        return float(f[i]), float(mag[i])
    a, b, c = np.log(mag[i - 1:i + 2])
    den = a - 2 * b + c
    p = 0.0 if den == 0 else 0.5 * (a - c) / den
    p = float(np.clip(p, -0.5, 0.5))
    return float(f[i] + p * (f[1] - f[0])), float(np.exp(b - 0.25 * (a - c) * p))


def spectrum_peaks(t, y, f_band, t_start=None, floor=0.0, n=None, pad_to_resolution=0.05):
    """Local maxima of `amplitude_spectrum` (Hann, linear detrend) of y(t >= t_start) in f_band, each
    refined by `interpolate_peak`: [(f Hz, height relative to the largest)], highest first, those at or
    above `floor` of the largest, at most n of them."""
    t, y = check_signal(t, y)
    if t_start is not None:
        keep = t >= t_start
        t, y = t[keep], y[keep]
    f, mag, _, _ = amplitude_spectrum(t, y, pad_to_resolution, f_band)
    i = np.flatnonzero((mag[1:-1] >= mag[:-2]) & (mag[1:-1] > mag[2:])) + 1
    if i.size == 0:
        return []
    i = i[np.argsort(-mag[i], kind="stable")]
    i = i[mag[i] >= floor * mag[i[0]]][:n]
    refined = [interpolate_peak(f, mag, int(k)) for k in i]
    return [(fk, mk / refined[0][1]) for fk, mk in refined]


# ---- damped-mode fit ----------------------------------------------------------------------
def _mode_columns(s, omega_n, xi):
    """Two basis columns e^{-xi wn s} (cos(wd s), sin(wd s)/wd) and their continuation for
    xi >= 1 (cosh, sinh/mu), so one model covers under-, critically and over-damped decays."""
    sigma = omega_n * xi
    q = omega_n**2 * (1.0 - xi**2)  # wd^2, negative when overdamped
    if q > 0:
        w = math.sqrt(q)
        env = np.exp(-sigma * s)
        return env * np.cos(w * s), env * np.sin(w * s) / w
    if q < 0:
        mu = math.sqrt(-q)  # mu < sigma, so both exponentials decay
        e1, e2 = np.exp((mu - sigma) * s), np.exp(-(mu + sigma) * s)
        return 0.5 * (e1 + e2), 0.5 * (e1 - e2) / mu
    env = np.exp(-sigma * s)
    return env, env * s


def _design(s, theta, offset):
    k = theta.size // 2
    cols = [np.ones_like(s)] if offset else []
    for j in range(k):
        cols.extend(_mode_columns(s, math.exp(theta[2 * j]), math.exp(theta[2 * j + 1])))
    return np.stack(cols, axis=1)


@dataclasses.dataclass(frozen=True)
class ModalFit(ResultMixin):
    """Least-squares fit y(t) ~ offset + sum_k e^{-xi_k wn_k s}(a_k cos(wd_k s) + b_k sin(wd_k s)/wd_k),
    s = t - t[0]. Arrays have one entry per mode (K,). omega_d is 0 for a non-oscillatory mode."""

    omega_n: np.ndarray  # rad/s
    xi: np.ndarray  # damping ratio (-)
    omega_d: np.ndarray  # rad/s
    amplitude: np.ndarray  # initial amplitude of each mode (units of y)
    offset: float  # constant level (units of y); 0 if not fitted
    rms: float  # residual RMS (units of y)
    rms_relative: float  # rms / RMS of (y - offset)
    n: int  # samples used
    success: bool
    t0: float  # s = t - t0
    coef: np.ndarray  # linear coefficients [offset,] a_1, b_1, ..., a_K, b_K

    def predict(self, t):
        """The fitted signal at times t (N,) s."""
        s = np.asarray(t, dtype=float) - self.t0
        theta = np.ravel(np.column_stack([np.log(self.omega_n), np.log(self.xi)]))
        return _design(s, theta, self.coef.size % 2 == 1) @ self.coef


def fit_modes(t, y, omega_n0, xi0, offset=True, n_starts_xi=(1.0,)):
    """Fit K damped modes to y(t) from initial guesses omega_n0 (K,) rad/s and xi0 (K,).

    Variable projection: the amplitudes (and offset) are linear and solved exactly for each trial
    (ln wn_k, ln xi_k), so the nonlinear search (scipy.optimize.least_squares) is only 2K-dim and
    the log parameters keep wn, xi > 0. n_starts_xi: factors on xi0 tried as extra starts; the
    lowest cost wins. Returns ModalFit.
    """
    t, y = check_signal(t, y)
    s = t - t[0]
    wn0 = np.atleast_1d(np.asarray(omega_n0, float))
    z0 = np.atleast_1d(np.asarray(xi0, float))
    if wn0.shape != z0.shape or np.any(wn0 <= 0) or np.any(z0 <= 0):
        raise ConfigError("omega_n0, xi0: must be positive arrays of equal shape")

    def resid(theta):
        a = _design(s, theta, offset)
        coef, *_ = np.linalg.lstsq(a, y, rcond=None)
        return a @ coef - y

    # Box on (ln wn, ln xi): a mode slower than 1/(100 T) or above the Nyquist frequency cannot
    # be identified from this record (above it an alias fits the samples as well as the truth),
    # and the bounds keep trial steps from overflowing.
    span = s[-1]
    wn_lo, wn_hi = 2 * np.pi / (100 * span), np.pi * (t.size - 1) / span
    lo = np.tile([math.log(wn_lo), math.log(_XI_MIN)], wn0.size)
    hi = np.tile([math.log(wn_hi), math.log(_XI_MAX)], wn0.size)
    best = None
    for fac in n_starts_xi:
        th0 = np.ravel(np.column_stack([np.log(wn0), np.log(z0 * fac)]))
        th0 = np.clip(th0, lo + 1e-9, hi - 1e-9)
        sol = scipy.optimize.least_squares(resid, th0, bounds=(lo, hi), method="trf", x_scale=1.0,
                                           xtol=1e-12, ftol=1e-12, gtol=1e-12)
        if best is None or sol.cost < best.cost:
            best = sol
    theta = best.x
    a = _design(s, theta, offset)
    coef, *_ = np.linalg.lstsq(a, y, rcond=None)
    wn, xi = np.exp(theta[0::2]), np.exp(theta[1::2])
    wd = wn * np.sqrt(np.clip(1.0 - xi**2, 0.0, None))
    ab = coef[1:] if offset else coef
    amp = np.hypot(ab[0::2], np.where(wd > 0, ab[1::2] / np.where(wd > 0, wd, 1.0), 0.0))
    off = float(coef[0]) if offset else 0.0
    r = a @ coef - y
    rms = float(np.sqrt(np.mean(r**2)))
    ref = float(np.sqrt(np.mean((y - off) ** 2)))
    return ModalFit(omega_n=wn, xi=xi, omega_d=wd, amplitude=amp, offset=off, rms=rms,
                    rms_relative=rms / ref if ref > 0 else 0.0, n=int(t.size), success=bool(best.success),
                    t0=float(t[0]), coef=coef)


# ---- first mode of an impact response -----------------------------------------------------
@dataclasses.dataclass(frozen=True)
class SpectrumResult(ResultMixin):
    """First-mode frequency of an impact response, from the spectrum and from a modal fit."""

    f_peak_Hz: float  # interpolated peak of the padded Hann spectrum (estimates f_d)
    f_fit_Hz: float  # damped frequency f_d of the fitted mode
    fn_fit_Hz: float  # undamped frequency f_n of the fitted mode
    xi_fit: float  # damping ratio of the fitted mode
    raw_resolution_Hz: float  # 1 / (N dt): the plain FFT bin spacing
    padded_resolution_Hz: float  # spacing of the zero-padded / zoomed grid
    f_band_lo_Hz: float
    f_band_hi_Hz: float
    peak_at_band_edge: bool  # True: the maximum sits on the band edge, so no peak inside
    fit_rms_relative: float  # fit residual RMS / signal RMS
    rel_diff_f: float  # (f_fit - f_peak) / f_peak
    n_modes_fit: int
    n: int  # samples used
    window: str

    def interior_peak_Hz(self):
        """f_peak_Hz when it is a peak inside the band, None when it sits within two raw bins of a band
        edge: there the maximum is the skirt of a mode outside the band (a window's side lobe of the
        bounce, say), not a mode in it."""
        margin = 2.0 * self.raw_resolution_Hz
        inside = self.f_band_lo_Hz + margin < self.f_peak_Hz < self.f_band_hi_Hz - margin
        return self.f_peak_Hz if inside and not self.peak_at_band_edge else None


def first_mode(t, y, f_band=None, pad_to_resolution=0.01, t_start=None, n_modes=None,
               window="hann", detrend="linear", fit=True):
    """First-mode frequency of y(t) (e.g. the axle force after a cleat impact).

    t, y: (N,) uniform sampling (s, any unit). f_band: (lo, hi) Hz in which to look for the peak;
    None searches (2/T, fs/2), skipping the lowest bins where the leftover trend sits.
    pad_to_resolution: grid spacing of the padded spectrum (Hz). t_start: drop samples before it
    (the impact itself is not free vibration). n_modes: modes in the time-domain fit; the first
    starts at the band peak, each further one at the strongest peak of the residual's spectrum,
    because other modes, even outside the band, bias a one-mode fit (docs/design-notes.md). None
    (auto) adds modes while each removes >= 20 % of the residual RMS, at most 4. fit=False skips the
    fit (the fit fields are then NaN). The fit costs a few hundred least-squares passes over all N
    samples: decimate very long records first.
    Returns SpectrumResult.
    """
    t, y = from_time(*check_signal(t, y), t_start, 8)
    dt = uniform_step(t)
    fs, n = 1.0 / dt, t.size
    band = _check_band(f_band, fs) or (min(2.0 * fs / n, fs / 2), fs / 2)
    if not (n_modes is None or (isinstance(n_modes, int) and 1 <= n_modes <= 10)):
        raise ConfigError(f"n_modes = {n_modes}: must be None (auto) or an integer in [1, 10]")
    f, mag, raw, step = amplitude_spectrum(t, y, pad_to_resolution, band, window, detrend)
    i = int(np.argmax(mag))
    f_peak, _ = interpolate_peak(f, mag, i)
    edge = i == 0 or i == f.size - 1

    f_fit = fn_fit = xi_fit = rms_rel = float("nan")
    k = 0
    if fit:
        mf = _greedy_modal_fit(t, y, f_peak, n_modes, window)
        # modes may trade places during the fit: report the one nearest the spectral peak
        j = int(np.argmin(np.abs(mf.omega_d / (2 * np.pi) - f_peak)))
        f_fit, fn_fit, xi_fit = mf.omega_d[j] / (2 * np.pi), mf.omega_n[j] / (2 * np.pi), mf.xi[j]
        rms_rel, k = mf.rms_relative, mf.omega_n.size
    return SpectrumResult(
        f_peak_Hz=f_peak, f_fit_Hz=float(f_fit), fn_fit_Hz=float(fn_fit), xi_fit=float(xi_fit),
        raw_resolution_Hz=raw, padded_resolution_Hz=step, f_band_lo_Hz=band[0], f_band_hi_Hz=band[1],
        peak_at_band_edge=bool(edge), fit_rms_relative=float(rms_rel),
        rel_diff_f=float((f_fit - f_peak) / f_peak) if fit else float("nan"),
        n_modes_fit=k, n=int(n), window=window)


def _greedy_modal_fit(t, y, f_main, n_modes, window):
    """Fit the mode at f_main (Hz), then add modes one at a time at the strongest peak of the
    residual's spectrum: exactly n_modes in all, or with n_modes None while each new mode removes
    at least _AUTO_MODE_GAIN of the residual RMS (noise never does), up to _AUTO_MODE_MAX."""
    xi_starts = (0.2, 1.0, 4.0)  # impact responses range from lightly to moderately damped
    mf = fit_modes(t, y, [2 * np.pi * f_main], [0.05], offset=True, n_starts_xi=xi_starts)
    target = _AUTO_MODE_MAX if n_modes is None else n_modes
    raw = 1.0 / (t.size * (t[1] - t[0]))
    while mf.omega_n.size < target and not (n_modes is None and mf.rms_relative < 1e-9):
        # 8x padding is plenty for a starting guess (the fit does the refining), capped for long records
        res = max(raw / 8, 1.0 / ((t[1] - t[0]) * _MAX_FFT))
        f, mag, _, _ = amplitude_spectrum(t, y - mf.predict(t), res, None, window, "linear")
        ok = f > 2 * raw  # the lowest bins hold what is left of the static level
        f_new = interpolate_peak(f, mag, int(np.flatnonzero(ok)[np.argmax(mag[ok])]))[0]
        wn0 = np.append(mf.omega_n, 2 * np.pi * f_new)
        xi0 = np.append(mf.xi, 0.05)
        new = min((fit_modes(t, y, wn0, xi0 * np.append(np.ones(mf.xi.size), fac), offset=True)
                   for fac in xi_starts), key=lambda m: m.rms)
        if n_modes is None and not new.rms < (1 - _AUTO_MODE_GAIN) * mf.rms:
            break
        mf = new
    return mf
