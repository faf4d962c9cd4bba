"""`jtire calibrate | sensitivity | sample` on the STAND-IN simulator: bad configs are one line and
exit code 2 (no traceback); good ones write their outputs."""

import json

import pytest

from jtire.calibration.tire.spec import load_calibration
from jtire.cli import main

from .conftest import REPO

CAL = REPO / "configs" / "calibration"
STUDY_TEXT = (CAL / "study.toml").read_text()
POSTERIOR_TEXT = (CAL / "posterior.toml").read_text()


def _config(tmp_path, text, name="cal.toml"):
    tires = tmp_path / "tires"
    tires.mkdir(exist_ok=True)
    (tires / "xone_xda.toml").write_text((REPO / "configs" / "tires" / "xone_xda.toml").read_text())
    sub = tmp_path / "calibration"
    sub.mkdir(exist_ok=True)
    path = sub / name
    path.write_text(text)
    return path


def _one_line_error(capsys, argv, *words):
    assert main(argv) == 2
    text = capsys.readouterr().err
    # besides the error: the stand-in notice and progress lines (indented) may precede it
    err = "\n".join(ln for ln in text.strip().splitlines()
                    if not ln.startswith(("simulator: closed-form STAND-IN", "  ")))
    assert err.count("\n") == 0 and "Traceback" not in text, text
    for w in words:
        assert w in err, err
    return err


BAD_CALIBRATIONS = [
    (('name = "parts.mid_sidewall.E_meridional"', 'name = "parts.mid_sidewall.E_radial"'),
     ["unknown parameter", "allowed: parts.<part>.<field>"]),
    (('name = "undertread.E"\nfactor = [0.33, 3.0]', 'name = "undertread.E"\nfactor = [3.0, 0.33]'),
     ["free[14].factor", "inverted"]),
    (('name = "undertread.E"\nfactor = [0.33, 3.0]', 'name = "undertread.E"\nfactor = [1.0, 1.0]'),
     ["empty"]),
    (('experiment = "lateral_stiffness"', 'experiment = "lateral_stifness"'),
     ["targets.DY.experiment", "no such experiment"]),
    (("measured_N = 1529.39", "measured_N = -1529.39"), ["targets.FX1.measured_N", "> 0"]),
    (("measured_mm = 39.0625", "measured_N = 39.0625"), ["unit does not fit"]),
    (("budget = 45 ", "budget = 1 "), ["arsm.budget"]),
    (('surface = "reduced"', 'surface = "cubic"'), ["arsm.surface"]),
    (('method = "arsm"', 'method = "newton"'), ["method"]),
]


@pytest.mark.parametrize("edit, words", BAD_CALIBRATIONS)
def test_bad_calibration_configs(tmp_path, capsys, edit, words):
    assert edit[0] in STUDY_TEXT
    cfg = _config(tmp_path, STUDY_TEXT.replace(edit[0], edit[1], 1))
    _one_line_error(capsys, ["calibrate", str(cfg), "--standin", "--out", str(tmp_path / "o")],
                    "jtire calibrate: error:", *words)


def test_shell_simulator_is_the_default(capsys):
    """Without --standin the calibration runs the shell model (calibration/tire/shell.py): built here, not run
    (one evaluation of the study's targets on the default mesh takes minutes)."""
    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration
    from jtire.cli.calibrate import simulator_for

    spec = load_calibration(CAL / "study.toml", [])
    sim = simulator_for(spec, False, lambda *a, **k: None)
    assert isinstance(sim, ShellSimulator)
    assert [g["exp"].name for g in sim.groups] == ["vertical_stiffness", "lateral_stiffness", "rolling_resistance"]
    assert [len(g["targets"]) for g in sim.groups] == [1, 1, 2]  # both E12 targets share one batch
    assert sim.fingerprint()["mesh"]["n_theta"] == spec.tire.n_theta
    # a progress bar over the cases of each evaluation (an initial ARSM batch is ~20 min on the
    # default mesh): two evaluations of 3 and 2 cases, each bar filled and closed
    capsys.readouterr()
    for total in (3, 2):
        for done in range(1, total + 1):
            sim.on_case("x parameter sets", done, total)
    err = capsys.readouterr().err
    assert "simulate x parameter sets" in err and "3/3" in err and "2/2" in err


def test_calibrate_and_sensitivity_on_the_standin(tmp_path, capsys):
    out = tmp_path / "cal"
    assert main(["calibrate", str(CAL / "study.toml"), "--standin", "--out", str(out),
                 "--budget", "30"]) == 0
    text = capsys.readouterr().out
    assert "| total |" in text and "30 evaluations" in text
    assert (out / "calibrated_tire.toml").is_file() and (out / "figure_4_6.png").is_file()
    # the calibrated tire checked by a fresh evaluation (--check-tire): its own values give the best
    # evaluation's responses back (the TOML keeps the values to 1e-9 relative or better)
    assert main(["calibrate", str(CAL / "study.toml"), "--standin", "--check-tire", str(out / "calibrated_tire.toml"),
                 "--out", str(tmp_path / "check")]) == 0
    capsys.readouterr()
    check = json.loads((tmp_path / "check" / "check_tire.json").read_text())
    best = json.loads((out / "summary.json").read_text())["responses_SI"]
    # (the drag bias b of FX1 and FX2 is read back from summary.json beside the tire: FX = FX_tire + b)
    targets = {t.name: t for t in load_calibration(CAL / "study.toml", []).targets}
    rows = [r for r in check["rows"] if r["target"] in targets]
    assert [r["target"] for r in rows] == list(targets)
    for row in rows:
        t = targets[row["target"]]
        assert row["simulated"] * t.unit_factor == pytest.approx(best[row["target"]], rel=1e-6)
    # the footprint checks are reported beside the targets (the stand-in's closed-form footprint)
    fl = next(r for r in check["rows"] if r["target"] == "FL (check)")
    assert fl["measured"] == pytest.approx(200.12) and 100 < fl["simulated"] < 400 and not fl["note"]
    # a rerun with other settings refuses in one line
    _one_line_error(capsys, ["calibrate", str(CAL / "study.toml"), "--standin", "--out", str(out),
                             "--set", "arsm.seed=4"], "holds results made with other settings (differs in options.seed)")
    # the calibrated tire is a tire every command takes: a calibration config on it parses
    cfg = _config(tmp_path, STUDY_TEXT.replace('tire_file = "../tires/xone_xda.toml"',
                                               f'tire_file = "{out / "calibrated_tire.toml"}"'))
    sens = tmp_path / "sens"
    assert main(["sensitivity", str(cfg), "--standin", "--out", str(sens), "--at", str(out)]) == 0
    text = capsys.readouterr().out
    assert "singular values" in text and "parameter directions identified" in text
    doc = json.loads((sens / "sensitivity.json").read_text())
    assert len(doc["identifiability"]["singular_values"]) == 4  # four targets: at most 4 directions
    assert (sens / "sensitivity.png").is_file()
    _one_line_error(capsys, ["sensitivity", str(cfg), "--standin", "--out", str(sens),
                             "--quantities", "DZ,footprint_area"], "footprint_area")


BAD_POSTERIORS = [
    (("walkers = 64", "walkers = 63"), ["sampler.walkers", "even"]),
    (("walkers = 64", "walkers = 20"), ["sampler.walkers", ">= 2 x"]),
    (("max_steps = 20000", "max_steps = -5"), ["sampler.max_steps"]),
    (("max_steps = 20000", "max_steps = 100"), ["sampler.check_every"]),
    (('kind = "log_uniform"', 'kind = "flat"'), ["prior.kind"]),
    (("[uncertainty.DY]", "[uncertainty.DX]"), ["uncertainty.DX", "no such target"]),
    (("relative = 0.03", "relative = -0.03"), ["uncertainty.DZ.relative"]),
    (('candidates = ["linear", "reduced", "full", "gp"]', 'candidates = ["spline"]'),
     ["emulator.candidates"]),
    (('kind = "best_miss"', 'kind = "kennedy"'), ["discrepancy.kind", "best_miss"]),
    (('moves = "de"', 'moves = "walk"'), ["sampler.moves", "stretch"]),
    (('coordinates = "logit"', 'coordinates = "probit"'), ["sampler.coordinates", "logit"]),
    (("refine = true", "refine = 1"), ["check.refine", "true or false"]),
    (("folds = 4", "folds = 40"), ["check.folds", "check.draws"]),
    (('variance = "wider"', 'variance = "add"'), ["check.variance", "wider", "floor", "scale"]),
]


@pytest.mark.parametrize("edit, words", BAD_POSTERIORS)
def test_bad_sampling_configs(tmp_path, capsys, edit, words):
    assert edit[0] in POSTERIOR_TEXT
    _config(tmp_path, STUDY_TEXT, "study.toml")
    cfg = _config(tmp_path, POSTERIOR_TEXT.replace(edit[0], edit[1], 1), "post.toml")
    _one_line_error(capsys, ["sample", str(cfg), "--out", str(tmp_path / "o")],
                    "jtire sample: error:", *words)


def test_sample_without_history_is_one_line(tmp_path, capsys):
    _one_line_error(capsys, ["sample", str(CAL / "posterior.toml"), "--history",
                             str(tmp_path / "nothing"), "--out", str(tmp_path / "o")],
                    "run `jtire calibrate`")


def test_sample_short_run_says_not_converged(tmp_path, capsys):
    """A budget far below 50 tau: the run says it did not converge (exit code 1), and still
    writes its reports; the simulator check runs on the stand-in."""
    cal = tmp_path / "cal"
    assert main(["calibrate", str(CAL / "study.toml"), "--standin", "--out", str(cal)]) == 0
    capsys.readouterr()
    out = tmp_path / "post"
    rc = main(["sample", str(CAL / "posterior.toml"), "--history", str(cal), "--out", str(out),
               "--set", "sampler.max_steps=60", "--set", "sampler.check_every=30",
               "--set", 'emulator.candidates=["linear", "reduced"]', "--check", "--standin"])
    text = capsys.readouterr().out
    assert rc == 1 and "NOT CONVERGED" in text
    assert "k_sv" in text and "RRC at 38.7 kN" in text and "coverage" in text
    for name in ("chain.h5", "diagnostics.json", "predictive.csv", "widths.csv", "corner.png",
                 "emulator.json", "check.json"):
        assert (out / name).is_file(), name
    chk = json.loads((out / "check.json").read_text())
    assert chk["n"] == 32
    for name, cov in chk["coverage"].items():  # the count inside and the exact interval of the truth
        k = chk["inside"][name]
        assert k / 32 == cov and f"{name} {cov:.2f} ({k}/32; " in text
        lo, hi = chk["coverage_interval"][name]
        assert lo <= cov <= hi
    if "refined round" in text:  # the stand-in's coverage was off: a refined round ran
        assert json.loads((out / "refined" / "check.json").read_text())["n"] == 32
        assert "variance_scale" in json.loads((out / "refined" / "emulator.json").read_text())


def test_sample_check_refines_and_resumes_without_rerunning(tmp_path, capsys):
    """The stand-in check (coverage off on a 60-step chain): a refined round in out/refined with
    rescaled variance and fresh draws; the same command again reruns no simulator: both checks
    reuse their stored runs, and the reports come out the same."""
    cal = tmp_path / "cal"
    assert main(["calibrate", str(CAL / "study.toml"), "--standin", "--out", str(cal)]) == 0
    out = tmp_path / "post"
    argv = ["sample", str(CAL / "posterior.toml"), "--history", str(cal), "--out", str(out),
            "--set", "sampler.max_steps=60", "--set", "sampler.check_every=30", "--set",
            'emulator.candidates=["linear"]', "--set", "check.draws=8", "--check", "--standin"]
    capsys.readouterr()
    main(argv)
    first = capsys.readouterr().out
    assert "refined round" in first, first[-2000:]
    a = json.loads((out / "check.json").read_text())
    b = json.loads((out / "refined" / "check.json").read_text())
    assert a["thetas"] != b["thetas"]  # fresh draws check the refined emulator
    assert json.loads((out / "refined" / "emulator.json").read_text())["n_points"] == \
        json.loads((out / "emulator.json").read_text())["n_points"] + 8
    n_rounds = first.count("refined round ")
    if n_rounds == 2:  # still off after the first: the second trains on both checks' runs
        assert json.loads((out / "refined_2" / "emulator.json").read_text())["n_points"] == \
            json.loads((out / "emulator.json").read_text())["n_points"] + 16
    last = out / ("refined" if n_rounds == 1 else "refined_2")
    before = (last / "predictive.csv").read_text()
    main(argv)
    again = capsys.readouterr().out
    assert again.count("stored runs reused") == 1 + n_rounds and "simulated" not in again
    assert (last / "predictive.csv").read_text() == before
