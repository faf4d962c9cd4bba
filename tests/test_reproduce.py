"""`jtire reproduce`: the chain's manifest, resume and refusal, and its report. The fast tests run a chain of the two
cheap stages (the measured data and the quick soil competition, both real); the whole quick chain (`--quick`,
coarse ring, about 4 min) is the physics gate's test_reproduce_quick in tests/test_readme_workflows.py."""

import json

import pytest

from jtire import reproduce as R
from jtire.cli import main


@pytest.fixture
def two_stages(monkeypatch):
    """The chain cut to its data and competition stages, plus the figures stage with no scripts."""
    full = R.stages

    def cut(out, quick):
        return [s for s in full(out, True) if s.name in ("data", "compete")]

    monkeypatch.setattr(R, "stages", cut)
    monkeypatch.setattr(R, "figure_scripts", lambda: [])


def test_stages_are_the_study_in_order(tmp_path):
    """The six stages in the study's order, each a jtire command into its own subfolder; the posterior reads the
    chain's own calibration, the characterization its calibrated tire."""
    stages = R.stages(tmp_path, quick=False)
    assert [s.name for s in stages] == ["data", "compete", "calibrate", "characterize", "sample", "figures"]
    argv = {s.name: s.argv for s in stages}
    assert argv["characterize"][:3] == ("characterize", "--tire", str(tmp_path / "calibrate" / "calibrated_tire.toml"))
    assert argv["sample"][argv["sample"].index("--history") + 1] == str(tmp_path / "calibrate")
    assert "--quick" not in argv["compete"] and not any("n_theta" in a for a in argv["characterize"])
    quick = {s.name: s.argv for s in R.stages(tmp_path, quick=True)}
    assert quick["calibrate"][1].endswith("study_quick.toml") and "--quick" in quick["compete"]
    assert "tire.mesh.n_theta=32" in quick["characterize"]


def test_chain_resumes_and_refuses_other_settings(tmp_path, monkeypatch, capsys, two_stages):
    """A chain killed in its second stage resumes without rerunning the first; the report lists both stages with
    their times; the same folder with other settings, or a folder that is no reproduce folder, is refused in one
    line."""
    import jtire.cli.compete as compete

    out = tmp_path / "study"
    real = compete.run_cli

    def killed(args, say):
        raise KeyboardInterrupt

    monkeypatch.setattr(compete, "run_cli", killed)
    assert main(["reproduce", "--quick", "--out", str(out)]) == 130
    man = json.loads((out / "reproduce.json").read_text())
    assert man["stages"]["data"]["status"] == "done" and man["stages"]["compete"]["status"] == "running"
    data_mtime = (out / "data" / "fits.csv").stat().st_mtime_ns
    monkeypatch.setattr(compete, "run_cli", real)
    capsys.readouterr()
    assert main(["reproduce", "--quick", "--out", str(out)]) == 0
    assert "resuming" in capsys.readouterr().err
    assert (out / "data" / "fits.csv").stat().st_mtime_ns == data_mtime  # not rerun
    man = json.loads((out / "reproduce.json").read_text())
    assert [man["stages"][s]["status"] for s in ("data", "compete")] == ["done", "done"]
    report = (out / "report.md").read_text()
    assert "| data |" in report and "| compete |" in report and "## Table 4-3" in report
    assert "| arsm | 0.18 | 24 | 3 |" in report  # the study's single run beside jtire's 3 quick seeds
    html = (out / "report.html").read_text()
    assert html.startswith("<!DOCTYPE html>") and "data:image/png;base64," in html  # the competition's figure inline
    assert "<table>" in html
    for argv, words in ((["reproduce", "--out", str(out)], "made with other settings (quick: True there, False now)"),
                        (["reproduce", "--quick", "--out", str(tmp_path)], "is not a reproduce folder")):
        capsys.readouterr()
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and words in err, err


def test_failed_stage_names_itself(tmp_path, monkeypatch, capsys, two_stages):
    """A stage that fails stops the chain with one line naming the stage; the manifest says so."""
    import jtire.cli.compete as compete
    from jtire.errors import ConfigError

    def bad(args, say):
        raise ConfigError("competition.budget = 0: must be >= 1")

    monkeypatch.setattr(compete, "run_cli", bad)
    assert main(["reproduce", "--quick", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("jtire reproduce: error: stage compete: competition.budget = 0")
    man = json.loads((tmp_path / "s" / "reproduce.json").read_text())
    assert man["stages"]["compete"]["status"] == "failed"


def test_failed_cases_do_not_stop_the_chain(tmp_path, monkeypatch, capsys, two_stages):
    """A stage that wrote its outputs but lost some cases (the characterization's CasesFailed) lets the chain go
    on; the report names the failed cases, the exit status is 1, and a rerun runs that stage again (its command
    retries just those cases), the finished ones not."""
    import jtire.cli.compete as compete
    from jtire.errors import CasesFailed

    real, calls = compete.run_cli, []

    def lossy(args, say):
        calls.append(1)
        real(args, say)
        if len(calls) == 1:
            raise CasesFailed(["soil/seed 3: diverged"])
        return 0

    monkeypatch.setattr(compete, "run_cli", lossy)
    out = tmp_path / "study"
    assert main(["reproduce", "--quick", "--out", str(out)]) == 1
    man = json.loads((out / "reproduce.json").read_text())
    assert man["stages"]["compete"]["status"] == "done, 1 cases failed"
    assert man["stages"]["compete"]["failures"] == ["soil/seed 3: diverged"]
    assert "compete: done, 1 cases failed" in capsys.readouterr().err
    assert "| compete |" in (out / "report.md").read_text()
    data_mtime = (out / "data" / "fits.csv").stat().st_mtime_ns
    assert main(["reproduce", "--quick", "--out", str(out)]) == 0 and len(calls) == 2
    assert (out / "data" / "fits.csv").stat().st_mtime_ns == data_mtime


def test_report_takes_the_posteriors_final_round(tmp_path):
    """Where the check sent the posterior through refined rounds (sample/refined/, sample/refined_2/, ...), the
    report's intervals are the final round's, and the coverage of every round is listed, the first one too."""
    def round_(folder, inside, n, tau):
        folder.mkdir(parents=True)
        (folder / "diagnostics.json").write_text(json.dumps({"converged": True, "steps": 900, "tau": [tau],
                                                             "n_tau_required": 50, "rhat": [1.01],
                                                             "acceptance_mean": 0.3}))
        (folder / "check.json").write_text(json.dumps({"coverage": {"DZ": inside / n}, "inside": {"DZ": inside},
                                                       "n": n}))
        (folder / "predictive.md").write_text(f"| DZ | from {folder.name} |\n")

    round_(tmp_path / "sample", 1, 32, 11.0)
    round_(tmp_path / "sample" / "refined", 30, 31, 12.0)
    round_(tmp_path / "sample" / "refined_2", 28, 30, 13.0)
    text = R._posterior(tmp_path)
    assert "2 refined round(s)" in text and "| DZ | from refined_2 |" in text and "max tau 13" in text
    assert "- first round: DZ 0.03 (1/32)" in text and "- refined: DZ 0.97 (30/31)" in text
    assert "- refined_2: DZ 0.93 (28/30)" in text
