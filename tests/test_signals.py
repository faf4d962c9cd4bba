"""Reductions of recorded signals (jtire.signals, jtire.spectra) on synthetic signals whose answers
are known in closed form: damped oscillators, decaying sinusoids, lines and ramps."""

import json
import math

import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.errors import ConfigError
from jtire.io import atomic_write_json
from jtire.signals import free_decay, is_steady, linear_slope, peaks, secant, steady_mean
from jtire.spectra import amplitude_spectrum, first_mode, fit_modes, spectrum_peaks

M = 70.75  # kg, the belt mass m_b of E07
FN = 12.0  # Hz, undamped natural frequency of the synthetic oscillators
WN = 2 * math.pi * FN

# Tolerances (relative unless stated), each with its reason.
TOL_2P = 0.03  # two peaks at ~10 samples/period with parabolic refinement (the brief's 2-3 %)
TOL_FIT = 0.005  # least-squares fit over the whole decay, with or without 1 % noise
TOL_OVERDAMPED = 0.01  # fitted xi of a decay without oscillation (noise free)
TOL_EXACT = 1e-12  # least squares on data that lie exactly on a line: rounding only
TOL_F_HZ = 0.05  # Hz: the E03 requirement, to tell 54.0 from 54.2 Hz apart


def oscillator(xi, fs, periods=None, t_end=None, amp=0.01, x_final=0.002, noise=0.0, seed=0,
               t_hold=0.0, x0=None):
    """Free response of m x'' + c x' + k x = 0 released from rest at x0 (default x_final + amp)
    at t_hold, held there before. Exact closed form for every damping ratio."""
    x0 = x_final + amp if x0 is None else x0
    a = x0 - x_final
    if t_end is None:
        t_end = t_hold + (periods / FN if periods else min(8.0 / (xi * WN), 20.0))
    t = np.arange(0.0, t_end, 1.0 / fs)
    s = np.clip(t - t_hold, 0.0, None)
    sig = xi * WN
    if xi < 1:
        wd = WN * math.sqrt(1 - xi * xi)
        u = a * np.exp(-sig * s) * (np.cos(wd * s) + sig / wd * np.sin(wd * s))
    elif xi == 1:
        u = a * np.exp(-WN * s) * (1 + WN * s)
    else:
        mu = WN * math.sqrt(xi * xi - 1)
        p1, p2 = -sig + mu, -sig - mu
        c2 = -p1 * a / (p2 - p1)
        u = (a - c2) * np.exp(p1 * s) + c2 * np.exp(p2 * s)
    rng = np.random.default_rng(seed)
    return t, x_final + u + noise * abs(a) * rng.standard_normal(t.size)


# ---- free decay ---------------------------------------------------------------------------
@pytest.mark.parametrize("xi", [0.02, 0.1, 0.3])
def test_free_decay_recovers_xi_wn_and_c(xi):
    # coarse: 10.37 samples per period, not a whole number, so the two peaks are sampled at
    # different phases (a whole number would hide the discretization error)
    t, x = oscillator(xi, fs=10.37 * FN)
    r = free_decay(t, x, M)
    c_true = xi * 2 * M * WN
    assert r.two_peak_ok and r.two_peak_reason == ""
    assert r.xi_formula.startswith("xi = delta / sqrt(4 pi^2 + delta^2)")
    assert r.xi_2p == pytest.approx(xi, rel=TOL_2P)
    assert r.omega_n_2p == pytest.approx(WN, rel=TOL_2P)
    assert r.c_2p == pytest.approx(c_true, rel=TOL_2P)
    assert r.xi_fit == pytest.approx(xi, rel=TOL_FIT)
    assert r.omega_n_fit == pytest.approx(WN, rel=TOL_FIT)
    assert r.c_fit == pytest.approx(c_true, rel=TOL_FIT)
    assert r.c_crit_fit == pytest.approx(2 * M * WN, rel=TOL_FIT)
    assert r.x_inf_fit == pytest.approx(0.002, abs=1e-4 * 0.01)  # 0.01 % of the amplitude
    assert r.fit_oscillatory and r.tail_settled
    # the disagreement fields are what they say
    assert r.rel_diff_xi == pytest.approx((r.xi_2p - r.xi_fit) / r.xi_fit, rel=1e-12)
    assert abs(r.rel_diff_xi) < TOL_2P + TOL_FIT


@pytest.mark.parametrize("xi", [0.02, 0.1, 0.3])
def test_free_decay_with_noise_fit_stays_within_tolerance(xi):
    t, x = oscillator(xi, fs=1000.0, noise=0.01, seed=7)  # 1 % of the amplitude, white
    r = free_decay(t, x, M)
    assert r.xi_fit == pytest.approx(xi, rel=TOL_FIT)
    assert r.c_fit == pytest.approx(xi * 2 * M * WN, rel=TOL_FIT)
    assert r.two_peak_ok  # the two-peak error is reported (rel_diff_xi), not bounded
    err_fit = abs(r.xi_fit / xi - 1)
    err_2p = abs(r.xi_2p / xi - 1)
    assert err_2p > err_fit  # two noisy samples carry less information than the whole decay
    if xi == 0.3:
        # the second peak is only 5 % of the release amplitude, so 1 % noise shows badly
        assert err_2p > 0.05


def test_study_formula_differs_at_xi_03():
    xi = 0.3
    t, x = oscillator(xi, fs=50 * FN)
    exact = free_decay(t, x, M, xi_formula="exact")
    study = free_decay(t, x, M, xi_formula="study")
    delta = 2 * math.pi * xi / math.sqrt(1 - xi * xi)  # exact log decrement of the oscillator
    assert exact.delta == pytest.approx(delta, rel=1e-3)  # 50 samples/period, refined peaks
    assert exact.xi_2p == pytest.approx(xi, rel=1e-3)
    assert study.xi_2p == pytest.approx(delta / math.sqrt(4 * math.pi**2 - delta**2), rel=1e-3)
    assert study.xi_2p / xi - 1 > 0.10  # the misprint overstates damping by ~10 % here
    assert "4 pi^2 - delta^2" in study.xi_formula and "4 pi^2 + delta^2" in exact.xi_formula
    assert study.xi_fit == pytest.approx(exact.xi_fit, rel=1e-12)  # the fit does not use it


def test_release_after_hold_from_below_final_level():
    # held 0.2 s below the final level, then released: first clear extremum is the overshoot max
    t, x = oscillator(0.1, fs=1000.0, t_hold=0.2, x0=-0.008, x_final=0.002, t_end=1.6)
    r = free_decay(t, x, M, t_start=0.2)
    assert r.peak_kind == "max"
    assert r.xi_fit == pytest.approx(0.1, rel=TOL_FIT)
    assert r.xi_2p == pytest.approx(0.1, rel=TOL_2P)
    assert r.t1 > 0.2 and r.t2 - r.t1 == pytest.approx(1 / (FN * math.sqrt(1 - 0.01)), rel=TOL_2P)


@pytest.mark.parametrize("xi", [1.0, 2.0])
def test_overdamped_decay_is_flagged_not_crashing(xi, tmp_path):
    t, x = oscillator(xi, fs=1000.0, t_end=1.0)
    r = free_decay(t, x, M)
    assert not r.two_peak_ok and "no clear peak" in r.two_peak_reason
    assert r.xi_2p is None and r.c_2p is None and r.rel_diff_xi is None
    assert r.xi_fit == pytest.approx(xi, rel=TOL_OVERDAMPED)
    assert r.omega_n_fit == pytest.approx(WN, rel=TOL_OVERDAMPED)
    assert not r.fit_oscillatory
    d = r.as_dict("c_by")
    assert all(k.startswith("c_by_") for k in d)
    assert all(v is None or not isinstance(v, float) or math.isfinite(v) for v in d.values())
    path = atomic_write_json(tmp_path / "result.json", d)
    assert json.loads(path.read_text())["c_by_xi_fit"] == pytest.approx(xi, rel=TOL_OVERDAMPED)


def test_free_decay_bad_input():
    t, x = oscillator(0.1, fs=500.0)
    with pytest.raises(ConfigError, match="mass"):
        free_decay(t, x, 0.0)
    with pytest.raises(ConfigError, match="xi_formula"):
        free_decay(t, x, M, xi_formula="minus")
    with pytest.raises(ConfigError, match="t_start"):
        free_decay(t, x, M, t_start=t[-1])


# ---- peaks --------------------------------------------------------------------------------
def test_peaks_parabolic_refinement():
    f, phi = 3.0, 0.7
    t = np.arange(0.0, 2.0, 1 / (10 * f))  # 10 samples per period
    x = np.cos(2 * np.pi * f * t + phi)
    pk = peaks(t, x, minima=True)
    k_max = np.arange(1, 1 + pk.t_max.size)
    t_true = (2 * np.pi * k_max - phi) / (2 * np.pi * f)
    # a parabola through 3 samples of a cosine 36 degrees apart: vertex within 0.2 % of a period
    assert np.max(np.abs(pk.t_max - t_true)) < 2e-3 / f
    assert np.max(np.abs(pk.x_max - 1)) < 2e-3
    # the raw sample maxima are off by up to half a sample (5 % of a period here)
    i_raw = np.flatnonzero((x[1:-1] > x[:-2]) & (x[1:-1] >= x[2:])) + 1
    raw_err = np.max(np.abs(t[i_raw] - t_true))
    assert raw_err > 10 * np.max(np.abs(pk.t_max - t_true))
    assert np.max(np.abs(pk.x_min + 1)) < 2e-3 and pk.t_min.size in (pk.t_max.size, pk.t_max.size + 1)


# ---- spectra ------------------------------------------------------------------------------
def impact(f_d, fs=2000.0, t_end=0.5, noise=0.0, seed=3, second=True):
    """Axle force after an impact: static load + first mode at f_d (xi 0.03) + a mode at 85 Hz."""
    t = np.arange(0.0, t_end, 1.0 / fs)
    y = 45e3 + 3e3 * np.exp(-0.03 * 2 * np.pi * f_d * t) * np.sin(2 * np.pi * f_d * t + 0.3)
    if second:
        y += 1.5e3 * np.exp(-0.05 * 2 * np.pi * 85 * t) * np.sin(2 * np.pi * 85 * t)
    return t, y + noise * 3e3 * np.random.default_rng(seed).standard_normal(t.size)


def test_first_mode_resolves_54_0_from_54_2_hz():
    res, raw_bins = {}, {}
    for f in (54.0, 54.2):
        t, y = impact(f, noise=0.01)  # 0.5 s record: raw bins of 2 Hz, 1 % noise
        r = first_mode(t, y, f_band=(40.0, 70.0), pad_to_resolution=0.01)
        assert r.raw_resolution_Hz == pytest.approx(2.0, rel=1e-9)
        assert r.padded_resolution_Hz <= 0.01
        assert not r.peak_at_band_edge
        assert r.f_peak_Hz == pytest.approx(f, abs=TOL_F_HZ)
        assert r.f_fit_Hz == pytest.approx(f, abs=TOL_F_HZ)
        assert r.xi_fit == pytest.approx(0.03, rel=0.05)
        assert r.n_modes_fit >= 2  # the 85 Hz mode joined the fit
        res[f] = r
        # the study's plain FFT: both land in the same 2 Hz bin
        fr, mag, _, _ = amplitude_spectrum(t, y, pad_to_resolution=1e9, window="boxcar")
        band = (fr > 40) & (fr < 70)
        raw_bins[f] = fr[band][np.argmax(mag[band])]
    assert raw_bins[54.0] == raw_bins[54.2]
    assert res[54.2].f_peak_Hz - res[54.0].f_peak_Hz > 0.2 - 2 * TOL_F_HZ
    assert res[54.2].f_fit_Hz - res[54.0].f_fit_Hz > 0.2 - 2 * TOL_F_HZ


def test_one_mode_fit_is_biased_by_a_mode_outside_the_band():
    t, y = impact(54.0)
    one = first_mode(t, y, f_band=(40.0, 70.0), n_modes=1)
    auto = first_mode(t, y, f_band=(40.0, 70.0))
    assert abs(one.f_fit_Hz - 54.0) > 0.1  # why n_modes defaults to auto
    assert auto.f_fit_Hz == pytest.approx(54.0, abs=1e-6)  # noise free, both modes fitted exactly
    assert auto.fit_rms_relative < 1e-8


def test_first_mode_band_edge_and_bad_input():
    t, y = impact(54.0, second=False)
    assert first_mode(t, y, f_band=(60.0, 70.0), fit=False).peak_at_band_edge
    with pytest.raises(ConfigError, match="f_band"):
        first_mode(t, y, f_band=(70.0, 60.0))
    t_bad = t.copy()
    t_bad[5] += 1e-4
    with pytest.raises(ConfigError, match="uniformly"):
        first_mode(t_bad, y)


def test_fit_modes_two_known_modes():
    t = np.arange(0.0, 1.0, 1e-3)
    y = (np.exp(-0.02 * 2 * np.pi * 20 * t) * np.cos(2 * np.pi * 20 * t * math.sqrt(1 - 4e-4))
         + 0.5 * np.exp(-0.1 * 2 * np.pi * 50 * t) * np.sin(2 * np.pi * 50 * t * math.sqrt(0.99)))
    mf = fit_modes(t, y, 2 * np.pi * np.array([19.0, 52.0]), [0.05, 0.05], offset=False)
    order = np.argsort(mf.omega_n)
    np.testing.assert_allclose(mf.omega_n[order], 2 * np.pi * np.array([20.0, 50.0]), rtol=1e-8)
    np.testing.assert_allclose(mf.xi[order], [0.02, 0.1], rtol=1e-8)
    np.testing.assert_allclose(mf.predict(t), y, atol=1e-9)


def test_spectrum_peaks_two_lightly_damped_modes():
    """Two modes 10 Hz apart, well resolved by a 1 s record (1 Hz bins, Hann main lobe 4 Hz): each peak
    within 0.1 Hz of its damped frequency (the parabolic refinement on a 0.05 Hz grid), highest first;
    a sinusoid of a twentieth the amplitude below the floor is left out, and t_start cuts the record."""
    t = np.arange(0.0, 1.2, 1e-3)
    y = (np.exp(-0.002 * 2 * np.pi * 60 * t) * np.cos(2 * np.pi * 60 * t) + 0.3 * np.sin(2 * np.pi * 70 * t)
         + 0.05 * np.sin(2 * np.pi * 110 * t) + 3.0 * (t < 0.2))  # the step before t_start is cut
    pk = spectrum_peaks(t, y, (20.0, 150.0), t_start=0.2, floor=0.2)
    assert [round(f) for f, _ in pk] == [60, 70]  # the mode (halving over the record) first
    assert abs(pk[0][0] - 60.0) < 0.1 and abs(pk[1][0] - 70.0) < 0.1
    assert pk[0][1] == 1.0 and 0.2 < pk[1][1] < 1.0
    assert len(spectrum_peaks(t, y, (20.0, 150.0), t_start=0.2)) >= 3  # no floor: the 110 Hz line too
    assert len(spectrum_peaks(t, y, (20.0, 150.0), t_start=0.2, n=1)) == 1


# ---- slopes, secants, steady state --------------------------------------------------------
def test_linear_slope_exact_and_sub_range():
    x = np.linspace(0.0, 0.06, 61)
    r = linear_slope(x, 1.28e6 * x + 250.0)
    assert r.slope == pytest.approx(1.28e6, rel=TOL_EXACT)
    assert r.intercept == pytest.approx(250.0, rel=1e-9)  # absolute rounding ~1e-10 N at 1e5 N
    assert r.r2 == pytest.approx(1.0, abs=TOL_EXACT) and r.n == 61
    # piecewise: slope 2 up to x = 1, slope 5 after; a stated range inside the first piece
    x = np.linspace(0.0, 2.0, 201)
    y = np.where(x <= 1.0, 2.0 * x, 2.0 + 5.0 * (x - 1.0))
    sub = linear_slope(x, y, x_range=(0.2, 0.8))
    assert sub.slope == pytest.approx(2.0, rel=TOL_EXACT) and sub.n == 61
    both = linear_slope(x, y)
    assert both.r2 < 0.99 and 2.0 < both.slope < 5.0  # the whole curve is not one line
    with pytest.raises(ConfigError, match="x_range"):
        linear_slope(x, y, x_range=(0.001, 0.002))


def test_secant_at_a_load():
    # softening load-deflection curve F = k d - c d^2; the secant at F* is F*/d*
    k, c, f_star = 1.3e6, 2.0e6, 50e3
    d = np.linspace(0.0, 0.05, 5001)
    r = secant(d, k * d - c * d**2, f_star, along="y")
    d_star = (k - math.sqrt(k * k - 4 * c * f_star)) / (2 * c)
    # linear interpolation error c h^2 / 8 ~ 2.5e-4 N on 5e4 N
    assert r.secant == pytest.approx(f_star / d_star, rel=1e-7)
    assert r.x_at == pytest.approx(d_star, rel=1e-7)
    at_x = secant(d, k * d - c * d**2, 0.03, along="x")
    assert at_x.secant == pytest.approx(k - c * 0.03, rel=1e-9)
    with pytest.raises(ConfigError, match="at"):
        secant(d, k * d, 1e9)


def test_steady_mean_detects_drift():
    t = np.linspace(0.0, 10.0, 1001)
    ramp = steady_mean(t, 100.0 + 2.0 * t, window=(5.0, 10.0))
    assert ramp.drift_per_s == pytest.approx(2.0, rel=TOL_EXACT)
    assert ramp.mean == pytest.approx(115.0, rel=TOL_EXACT)
    assert ramp.drift_relative == pytest.approx(2.0 * 5.0 / 115.0, rel=1e-9)
    assert not is_steady(ramp, tol=0.01)
    noisy = 1529.0 + 15.0 * np.random.default_rng(11).standard_normal(t.size)  # 1 % noise
    flat = steady_mean(t, noisy, window=(2.0, 10.0))
    assert abs(flat.mean - 1529.0) < 4 * 15.0 / math.sqrt(flat.n)  # 4 sigma of the mean
    assert abs(flat.drift_per_s) < 4 * flat.drift_stderr
    assert is_steady(flat, tol=0.01)
    assert flat.std == pytest.approx(15.0, rel=0.15)  # 800 samples: sampling spread ~2.5 %
