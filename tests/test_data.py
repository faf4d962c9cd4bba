"""Measured rolling-resistance data: the study's averages, the fits and their intervals, the CLI."""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import jtire  # noqa: F401  (float64)
from jtire.data import LBF_N, PSI_PA, analyze, config_averages, load_sandbox, load_track
from jtire.data_fits import compare_target, fit_linear, fit_power, load_targets
from jtire.errors import ConfigError

ROOT = Path(__file__).resolve().parents[1]
EXACT = 1e-10  # float64 least squares on exact data: only round-off remains
COLUMN_DIGITS = 1e-8  # the sandbox rrc column is printed to 9 significant digits


def _by_label(avgs, axle=None):
    return {a.label: a for a in avgs if axle is None or a.axle == axle}


def test_unit_constants_are_the_definitions():
    # lbf = 0.45359237 kg * g_n; psi = lbf / in^2 with 1 in = 0.0254 m (both exact definitions).
    assert LBF_N == pytest.approx(0.45359237 * 9.80665, rel=1e-15)
    assert PSI_PA == pytest.approx(0.45359237 * 9.80665 / 0.0254**2, rel=1e-15)
    t = load_track()
    assert t.fz_n[0] == pytest.approx(1247.368 * LBF_N, rel=1e-15)  # first row, converted once
    assert t.pressure_pa[0] == pytest.approx(120.0 * PSI_PA, rel=1e-15)


def test_track_bobtail_average_matches_study_digits():
    # The study prints Fx 24.03552 lbf, Fz 1160.946 lbf, RRC 0.018806 for the track bobtail.
    a = _by_label(config_averages(load_track()))["bobtail"]
    assert a.n_runs == 6
    assert round(a.fx_n / LBF_N, 5) == 24.03552
    assert round(a.fz_n / LBF_N, 3) == 1160.946
    assert round(a.rrc_study, 6) == 0.018806


def test_study_rrc_is_mean_of_tabulated_column_not_a_force_ratio():
    # Documents how the study averaged: the two ratios built from the forces miss its 0.018806.
    a = _by_label(config_averages(load_track()))["bobtail"]
    assert round(a.rrc_ratio_of_means, 6) == 0.020703
    assert round(a.rrc_mean_of_ratios, 6) == 0.020834


def test_track_mean_loads_match_the_nominal_load_labels():
    # The nominal-load column is the study's printed mean Fz (2 decimals) for the 120 psi configs,
    # except trailer1 whose label is exactly 10.00 lbf low (a one-digit slip in the study).
    avgs = _by_label(config_averages(load_track()))
    for label in ("bobtail", "trailer2", "trailer3"):
        a = avgs[label]
        assert round(a.fz_n / LBF_N, 2) == pytest.approx(a.nominal_load_n / LBF_N, abs=1e-9)
    t1 = avgs["trailer1"]
    assert (t1.fz_n - t1.nominal_load_n) / LBF_N == pytest.approx(10.0, abs=0.005)


def test_sandbox_rrc_column_is_fx_over_fz():
    s = load_sandbox()
    assert np.max(np.abs(s.rrc_table / s.rrc_ratio - 1.0)) < COLUMN_DIGITS
    for a in config_averages(s):
        assert a.rrc_study == pytest.approx(a.rrc_mean_of_ratios, rel=COLUMN_DIGITS)
    assert len(config_averages(s)) == 10  # 5 configurations x 2 axles, 3 runs each
    assert {a.n_runs for a in config_averages(s)} == {3}


def test_track_rrc_column_close_to_fx_over_fz_only_at_high_load():
    # Per-run RRC was formed before the left/right averaging; the difference is small on the
    # loaded configurations (F_z > 30 kN: within 0.5 %) and large for the light bobtail (> 5 %).
    for a in config_averages(load_track()):
        rel = abs(a.rrc_study / a.rrc_mean_of_ratios - 1.0)
        if a.fz_n > 30e3:
            assert rel < 0.005, a.label
        if a.label == "bobtail":
            assert rel > 0.05


def test_linear_fit_recovers_known_line_exactly():
    fz = np.linspace(5e3, 45e3, 9)
    a, b = 0.012, 2.5e-7
    fit = fit_linear(fz, a + b * fz)
    assert fit.a == pytest.approx(a, rel=EXACT)
    assert fit.b == pytest.approx(b, rel=EXACT)
    assert fit.line.sigma < 1e-12  # no residual on an exact line
    assert fit.line.exact  # ... and flagged: its intervals have zero width


def test_exact_fit_is_refused_by_the_analysis_not_reported(tmp_path):
    # Points on a line to round-off give zero-width intervals and infinite z-scores; the analysis
    # refuses them (one line naming the fit) instead of printing a certainty no data has.
    from jtire.data import points_trend_fits
    from jtire.data_fits import Target

    fz = np.linspace(30e3, 45e3, 6)
    with pytest.raises(ConfigError, match=r"fit exact \(test\): the 6 points lie exactly on the linear"):
        points_trend_fits("exact", "test", fz, 0.01 + 1e-7 * fz)
    fit = fit_linear(fz, 0.01 + 1e-7 * fz)
    with pytest.raises(ConfigError, match="lie exactly on the trend"):
        compare_target(fit, Target("t", 40e3, 800.0), "exact")
    # one part in 1e6 of scatter (the 6 printed digits of the tables) is data, not an exact fit
    noisy = (0.01 + 1e-7 * fz) * (1 + 1e-6 * np.array([1, -1, 1, 1, -1, -1]))
    assert not points_trend_fits("noisy", "test", fz, noisy).linear.line.exact


def test_power_fit_recovers_known_law_exactly():
    fz = np.linspace(5e3, 45e3, 9)
    c, d = 0.4, -0.3
    fit = fit_power(fz, c * fz**d)
    assert fit.c == pytest.approx(c, rel=1e-9)  # ln c is extrapolated to F_z = 1 N: looser
    assert fit.d == pytest.approx(d, rel=EXACT)


def test_standard_errors_match_scipy_linregress():
    # An independent implementation of the same OLS formulas.
    rng = np.random.default_rng(7)
    x = rng.uniform(5e3, 45e3, 20)
    y = 0.02 + 1e-7 * x + rng.normal(0.0, 0.003, 20)
    fit = fit_linear(x, y)
    ref = stats.linregress(x, y)
    assert fit.b == pytest.approx(ref.slope, rel=1e-9)
    assert fit.a == pytest.approx(ref.intercept, rel=1e-9)
    assert fit.line.stderr[1] == pytest.approx(ref.stderr, rel=1e-9)
    assert fit.line.stderr[0] == pytest.approx(ref.intercept_stderr, rel=1e-9)


def test_confidence_intervals_cover_truth_at_nominal_rate():
    # 2000 replicates of a noisy line, 95 % intervals: the coverage of the slope and of the mean
    # trend at 38.7 kN must be within 4 binomial sigmas (4 * 0.0049) of 0.95. Five points (3
    # degrees of freedom) so that a normal instead of a Student-t quantile would show (~0.86).
    rng = np.random.default_rng(20240601)
    a, b, x0 = 0.016, 1.2e-7, 38.7e3
    x = np.array([5e3, 12e3, 25e3, 39e3, 42e3])
    hits_b = hits_mean = 0
    reps = 2000
    for _ in range(reps):
        fit = fit_linear(x, a + b * x + rng.normal(0.0, 0.005, x.size))
        lo, hi = fit.b_ci
        hits_b += lo <= b <= hi
        p = fit.predict(x0)
        hits_mean += p.lower[0] <= a + b * x0 <= p.upper[0]
    tol = 4 * math.sqrt(0.95 * 0.05 / reps)
    assert abs(hits_b / reps - 0.95) < tol
    assert abs(hits_mean / reps - 0.95) < tol


def test_power_ci_covers_truth_on_one_seeded_dataset():
    rng = np.random.default_rng(3)
    fz = np.repeat([5e3, 12e3, 39e3, 42e3], 6)
    c, d = 0.05, -0.1
    fit = fit_power(fz, c * fz**d * np.exp(rng.normal(0.0, 0.15, fz.size)))
    assert fit.d_ci[0] <= d <= fit.d_ci[1]
    assert fit.c_ci[0] <= c <= fit.c_ci[1]


def test_targets_read_from_reference_and_compared():
    targets = load_targets()
    assert [round(t.rrc, 4) for t in targets] == [0.0395, 0.0411]  # the study's quoted RRCs
    s = analyze()
    lin = s.fits["track_120psi"].linear
    cmp = compare_target(lin, targets[0])
    p = lin.predict(targets[0].load_n)
    assert cmp.z_mean == pytest.approx((targets[0].rrc - p.mean[0]) / p.se[0], rel=EXACT)
    assert cmp.percent == pytest.approx((targets[0].rrc / p.mean[0] - 1) * 100, rel=EXACT)
    # Only the 4 x 120 psi track configurations enter the track fit.
    assert lin.line.n == 24 and s.fits["track_120psi_means"].linear.line.n == 4


def test_bad_inputs_raise_config_error(tmp_path):
    with pytest.raises(ConfigError, match="confidence"):
        fit_linear([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], confidence=1.5)
    with pytest.raises(ConfigError, match="not found"):
        load_track(tmp_path)
    (tmp_path / "track_rolling_resistance.csv").write_text(
        "# comment\nconfig,label,pressure_psi,nominal_load_lbs,run,fx_lbs,fz_lbs,rrc\n"
        "1,a,120,1000,1A,10,abc,0.01\n")
    with pytest.raises(ConfigError, match="fz_lbs"):
        load_track(tmp_path)


def test_cli_data_writes_tables(tmp_path, capsys):
    from jtire.cli import main

    assert main(["data", "--out", str(tmp_path)]) == 0
    for name in ("track_averages.csv", "sandbox_averages.csv", "fits.csv",
                 "target_comparison.csv", "fits.json"):
        assert (tmp_path / name).is_file(), name
    doc = json.loads((tmp_path / "fits.json").read_text())
    assert doc["fits"]["track_120psi"]["linear"]["a"] == pytest.approx(
        analyze().fits["track_120psi"].linear.a, rel=EXACT)
    assert "0.018806" in capsys.readouterr().out
    # an output folder that cannot be made: one line naming it, no traceback
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    assert main(["data", "--out", str(blocker / "sub")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "jtire data: error: cannot read or write" in err[0] and "a_file" in err[0]


@pytest.mark.parametrize("script", ["fig3_5_track_rrc.py", "fig3_7_sandbox_rrc.py"])
def test_figure_script_quick(script, tmp_path):
    out = tmp_path / "fig.png"
    path = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    env = dict(os.environ, PYTHONPATH=path, MPLBACKEND="Agg")
    r = subprocess.run([sys.executable, str(ROOT / "paper_figures" / script), "--quick",
                        "--out", str(out)], env=env, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
