"""The optimizer competition's plumbing, on a cheap analytic black box (no FE soil model)."""

import csv
import importlib.util
from pathlib import Path

import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.calibration.soil.competition import (
    CompetitionSpec,
    fingerprint,
    load_config,
    run_competition,
    standin_objective,
)
from jtire.calibration.soil.report import calls_to_reach, format_table, summarize, write_outputs
from jtire.calibration.history import OptimizeResult
from jtire.errors import ConfigError

REPO = Path(__file__).resolve().parents[1]
CONFIG = REPO / "configs" / "calibration" / "soil_competition.toml"


@pytest.fixture(scope="module")
def cfg():
    return load_config(CONFIG)


def _spec(cfg, **comp):
    return CompetitionSpec.from_config({**cfg, "competition": {**cfg["competition"], **comp}})


def test_config_holds_the_study_setup(cfg):
    spec = CompetitionSpec.from_config(cfg)
    assert spec.methods == ("arsm", "ga", "mc") and spec.seeds >= 20 and spec.budget == 50
    assert spec.thresholds == (0.66, 0.18)
    assert spec.anchors["arsm"] == {"error_percent": 0.18, "calls": 24}
    soil = cfg["soil"]  # reference_xone_xda.toml [bekker], in SI
    assert soil["bekker_k_c"] == 16.03e3 and soil["bekker_k_phi"] == 1262.53e3
    assert soil["pressure_Pa"] == 1e5 and soil["plate_radius_m"] == 0.15


def test_standin_target_is_the_bekker_sinkage(cfg):
    # (k_c / b + k_phi) z^n = p with b = 0.15 m gives the study's 23.7896 mm; at E = S(rho) / z
    # the stand-in's error is zero
    f = standin_objective(cfg)
    z = 23.7896e-3
    e_star = 44.5e3 * (1500 / 1200) ** -0.25 / z
    assert f([1500.0, e_star]) < 1e-3  # percent; the study quotes z to 6 digits
    assert f([1500.0, 2 * e_star]) == pytest.approx(50.0, rel=1e-4)


def test_bad_config_fields_name_the_field(cfg):
    for comp, field in [({"seeds": 0}, "competition.seeds"), ({"methods": ["pso"]}, "methods"),
                        ({"budget": 2.5}, "competition.budget"),
                        ({"options": {"ga": {"pop": 3}}}, "competition.options.ga.pop")]:
        with pytest.raises(ConfigError, match=field):
            _spec(cfg, **comp)
    bad = {**cfg, "bounds": {**cfg["bounds"], "density_kg_m3": [2200.0, 1200.0]}}
    with pytest.raises(ConfigError, match="bounds.density_kg_m3"):
        CompetitionSpec.from_config(bad)


def _result(fs, method="x", seed=0):
    hist = [{"call": i, "x": [0.0, 0.0], "f": f} for i, f in enumerate(fs)]
    return OptimizeResult(np.zeros(2), min(fs), len(fs), hist, "budget", method, seed)


def test_calls_to_reach_and_summary_statistics(cfg):
    spec = _spec(cfg, seeds=3, budget=5, methods=["mc"])
    runs = [_result([5.0, 0.5, 0.1, 0.1, 0.1]), _result([5.0, 4.0, 0.6, 0.6, 0.6]),
            _result([1.0, 1.0, 1.0])]  # stopped early at 1.0: stays at 1.0
    assert calls_to_reach(runs[0], 0.18) == 3 and calls_to_reach(runs[1], 0.18) == np.inf
    (row,) = summarize({"mc": runs}, spec)
    assert row["final_error_median_pct"] == pytest.approx(0.6)
    assert row["calls_to_0.66pct_median"] == 3  # seeds: 2, 3, never -> the middle one
    assert row["reached_0.66pct_fraction"] == pytest.approx(2 / 3)
    assert row["calls_to_0.18pct_median"] == np.inf and row["reached_0.18pct_fraction"] == 1 / 3
    assert ">5" in format_table([row], spec)


def test_competition_runs_resumes_and_writes_outputs(cfg, tmp_path):
    spec = _spec(cfg, seeds=2, budget=12)
    f = standin_objective(cfg)
    calls = {"n": 0}

    def counted(x):
        calls["n"] += 1
        return f(x)

    res = run_competition(counted, spec, tmp_path, progress=False,
                          fingerprint=fingerprint(cfg, "standin"))
    first = calls["n"]
    assert set(res) == {"arsm", "ga", "mc"} and all(len(r) == 2 for r in res.values())
    assert first == sum(r.n_calls for runs in res.values() for r in runs) <= 3 * 2 * 12
    again = run_competition(counted, spec, tmp_path, progress=False,
                            fingerprint=fingerprint(cfg, "standin"))
    assert calls["n"] == first  # everything replayed from the per-seed histories
    assert [r.f_best for r in again["ga"]] == [r.f_best for r in res["ga"]]
    with pytest.raises(ConfigError, match="objective"):  # another objective, same folder
        run_competition(counted, spec, tmp_path, progress=False,
                        fingerprint=fingerprint(cfg, "soil"))

    out = write_outputs(res, spec, tmp_path, "test")
    rows = list(csv.DictReader(open(out["runs_csv"])))
    assert len(rows) == first
    best = {}
    for r in rows:  # best_error_pct is the running minimum within each run
        key = (r["method"], r["seed"])
        best[key] = min(best.get(key, np.inf), float(r["error_pct"]))
        assert float(r["best_error_pct"]) == pytest.approx(best[key])
    summary = list(csv.DictReader(open(out["summary_csv"])))
    assert [s["method"] for s in summary] == ["arsm", "ga", "mc"]
    assert out["figure"].stat().st_size > 10_000


def test_cli_quick_standin(tmp_path, capsys):
    from jtire.cli import main

    assert main(["compete", str(CONFIG), "--quick", "--objective", "standin",
                 "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "ARSM" in printed and "0.18 % in 24 calls" in printed
    assert (tmp_path / "standin" / "progression.png").exists()
    assert main(["compete", str(tmp_path / "no.toml")]) == 2
    assert "no such competition config" in capsys.readouterr().err
    # --set overrides a config field, and a bad value is a one-line error naming it
    assert main(["compete", str(CONFIG), "--set", "bounds.density_kg_m3=[2200.0, 1200.0]",
                 "--out", str(tmp_path)]) == 2
    assert "bounds.density_kg_m3" in capsys.readouterr().err


def test_fig4_2_quick(tmp_path):
    spec = importlib.util.spec_from_file_location(
        "fig4_2", REPO / "paper_figures" / "fig4_2_competition.py")
    fig = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fig)
    png = tmp_path / "fig4_2.png"
    assert fig.main(["--quick", "--out", str(png)]) == 0
    assert png.stat().st_size > 10_000


@pytest.mark.slow
def test_arsm_meets_the_issue_goal_on_the_fe_soil_model(cfg, tmp_path):
    """The goal of the competition: over 20 seeds on the FE soil block (not the stand-in), the
    median ARSM run reaches 0.18 % sinkage error in at most 24 calls (the study's single run).
    Measured: 21.5 calls (quartiles 18, 24.8), every seed reaching it; ~35 s for 1000 calls."""
    from jtire.calibration.soil.competition import soil_objective

    spec = _spec(cfg, methods=["arsm"])
    assert spec.seeds == 20 and spec.budget == 50
    res = run_competition(soil_objective(cfg), spec, tmp_path, progress=False,
                          fingerprint=fingerprint(cfg, "soil"))
    (row,) = summarize(res, spec)
    assert row["calls_to_0.18pct_median"] <= 24
    assert row["reached_0.18pct_fraction"] >= 0.9
