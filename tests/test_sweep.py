"""`jtire sweep`: a sweep killed mid-way resumes without recomputing what it finished; a folder made
with other settings refuses in one line; case folder names cannot collide.

The killed sweep runs in a subprocess (the real command, SIGKILLed): 4 cases of E01 (transient) on the
coarse ring with the default batching: case by case, side by side on the devices, each saved as it
finishes (the one-case program the in-process runs compiled, loaded from the persistent cache).
"""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from jtire import units as U
from jtire.cli import main
from jtire.cli.sweep import grid_conditions
from jtire.results import case_name
from jtire.config import load_run_config
from jtire.errors import ConfigError

from .conftest import COARSE_SET, REPO, SOLVER_SET

FOOTPRINT = REPO / "configs" / "experiments" / "footprint.toml"
ARGS = [str(FOOTPRINT), *[a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)],
        "--set", "sweep.loads_kg=[2312.5, 4625.0]", "--set", "sweep.pressures_psi=[120.0, 150.0]",
        # the transient method: the single-case program the in-process tests compiled (this file tests
        # the folder machinery, not the method)
        "--set", "footprint.method=transient"]
CMD = [sys.executable, "-c", "import sys; from jtire.cli import main; sys.exit(main(sys.argv[1:]))", "sweep"]
N_CASES = 4
TIMEOUT_S = 900  # a cold start (nothing in the compilation cache) compiles the program: minutes


def results(out):
    return sorted((out / "cases").glob("*/result.json"))


# The three tests on this killed-and-resumed sweep (two `jtire sweep` processes, ~50 s cold here) run in the
# physics gate; the fast suite keeps the in-process kill below and tests/test_kill_resume.py.
@pytest.fixture(scope="module")
def killed_and_resumed(tmp_path_factory, e01_singles):
    """Start the sweep, SIGKILL it as soon as its first case is written, run it again to the end.
    Returns (out folder, {file: (bytes, mtime_ns)} of the cases finished before the kill, the rerun's
    CompletedProcess)."""
    out = tmp_path_factory.mktemp("sweep") / "grid"
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.Popen(CMD + ARGS + ["--out", str(out)], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    t0 = time.monotonic()
    try:
        while not results(out):
            assert p.poll() is None, f"the sweep ended before its first case: {p.communicate()[1].decode()[-2000:]}"
            assert time.monotonic() - t0 < TIMEOUT_S, "no case finished in time"
            time.sleep(0.2)
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait()
    done = {f: (f.read_bytes(), f.stat().st_mtime_ns) for f in results(out)}
    assert 0 < len(done) < N_CASES, "killed too late to test a resume"
    again = subprocess.run(CMD + ARGS + ["--out", str(out)], env=env, capture_output=True, text=True, timeout=TIMEOUT_S)
    return out, done, again


@pytest.mark.slow
@pytest.mark.gate
def test_killed_sweep_resumes_without_recomputing(killed_and_resumed):
    out, done, again = killed_and_resumed
    assert again.returncode == 0, again.stderr[-2000:]
    assert f"resuming: {len(done)} of {N_CASES} cases already done" in again.stderr
    for f, (data, mtime) in done.items():
        assert f.read_bytes() == data and f.stat().st_mtime_ns == mtime, f"{f}: rewritten by the resume"
    assert len(results(out)) == N_CASES
    rows = (out / "summary.csv").read_text().splitlines()
    assert len(rows) == 1 + N_CASES
    for f in results(out):
        d = json.loads(f.read_text())
        assert d["checks"]["load_settled"] and d["quantities"]["contact_length_m"] > 0


@pytest.mark.slow
@pytest.mark.gate
def test_finished_sweep_rerun_computes_nothing(killed_and_resumed, capsys):
    out, _, _ = killed_and_resumed
    before = {f: f.stat().st_mtime_ns for f in results(out)}
    assert main(["sweep", *ARGS, "--out", str(out)]) == 0
    assert f"resuming: {N_CASES} of {N_CASES} cases already done" in capsys.readouterr().err
    assert {f: f.stat().st_mtime_ns for f in results(out)} == before


@pytest.mark.slow
@pytest.mark.gate
@pytest.mark.parametrize("other", [["--set", "solver.ke_tol_J=0.002"],  # other settings
                                   ["--set", "sweep.loads_kg=[2312.5, 4000.0]"],  # another grid
                                   ["--set", "tire.tread.friction=0.7"]])  # another tire
def test_rerun_with_other_settings_refuses_in_one_line(killed_and_resumed, capsys, other):
    out, _, _ = killed_and_resumed
    before = {f: f.stat().st_mtime_ns for f in results(out)}
    assert main(["sweep", *ARGS, *other, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    assert err.startswith("jtire sweep: error: ") and "holds results made with other settings" in err
    assert "use another output folder" in err
    assert {f: f.stat().st_mtime_ns for f in results(out)} == before


# ---- a kill between a case's signals.csv and its result.json ---------------------------------------------
class _Killed(BaseException):
    """Stands for SIGKILL: nothing in the command catches it."""


VERTICAL = REPO / "configs" / "experiments" / "vertical_stiffness.toml"
# 2 cases of E02 (static method: solved case by case, each saved as it finishes; it has signals.csv)
VERTICAL_ARGS = [str(VERTICAL), *[a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)],
                 "--set", "sweep.loads_kg=[2312.5, 4625.0]", "--set", "sweep.pressures_psi=[120.0]"]


def test_kill_between_signals_and_result_redoes_the_case(tmp_path, monkeypatch, capsys):
    """A case's result.json marks it done, so it is written last: killed after the second case's
    signals.csv and before its result.json, the rerun counts 1 of 2 done, leaves the first case as it
    was and runs the second again (its signals.csv rewritten, the same numbers)."""
    import jtire.experiments.result as result_mod

    out = tmp_path / "grid"
    real, calls = result_mod.atomic_write_json, []

    def killed_on_the_second(path, obj):
        calls.append(path)
        if len(calls) == 2:
            assert (path.parent / "signals.csv").is_file()  # the signals are on disk already
            raise _Killed
        return real(path, obj)

    monkeypatch.setattr(result_mod, "atomic_write_json", killed_on_the_second)
    with pytest.raises(_Killed):
        main(["sweep", *VERTICAL_ARGS, "--out", str(out)])
    monkeypatch.setattr(result_mod, "atomic_write_json", real)
    (first,) = results(out)
    killed = calls[1].parent
    assert killed != first.parent and not (killed / "result.json").exists()
    before = (first.read_bytes(), first.stat().st_mtime_ns)
    signals = (killed / "signals.csv").read_text()
    stale = (killed / "signals.csv").stat().st_ino
    capsys.readouterr()
    assert main(["sweep", *VERTICAL_ARGS, "--out", str(out)]) == 0
    assert "resuming: 1 of 2 cases already done" in capsys.readouterr().err
    assert (first.read_bytes(), first.stat().st_mtime_ns) == before
    assert (killed / "result.json").is_file() and (killed / "signals.csv").stat().st_ino != stale  # run again
    assert (killed / "signals.csv").read_text() == signals
    assert json.loads((killed / "result.json").read_text())["quantities"]["k_sv_N_per_m"] > 0


# ---- case names ----------------------------------------------------------------------------------------
def test_case_names_cannot_collide():
    # values that print alike (4 significant digits of psi, 6 of kg) still get their own folders: the
    # case index comes first
    g = grid_conditions({"loads_kg": [4625.0, 4625.0000001, 4625.0000002],
                         "pressures_psi": [120.0, 120.00001, 120.00002]})
    names = [case_name(i, c) for i, c in enumerate(g)]
    assert len(g) == 9 and len(set(names)) == 9
    assert all("/" not in n and n == n.strip() for n in names)
    assert names[0] == "000_p120psi_l4625kg"
    # per-pressure experiments (E05, E07, E08): no load in the name
    p = grid_conditions({}, per_pressure=True)
    assert [case_name(i, c) for i, c in enumerate(p)] == ["000_p70psi", "001_p120psi", "002_p150psi"]


def test_default_grid_is_the_studys():
    g = grid_conditions({})
    assert len(g) == 9
    assert sorted({round(c["pressure_Pa"] / U.PSI, 6) for c in g}) == [70.0, 120.0, 150.0]
    assert sorted({round(c["load_N"] / U.G0, 6) for c in g}) == [2312.5, 4625.0, 6937.5]


@pytest.mark.parametrize("grid, message", [({"loads_kg": [4625.0, 4625.0]}, "sweep.loads_kg: lists a value twice"),
                                           ({"pressures_psi": [120.0, 300.0]}, "sweep.pressures_psi"),
                                           ({"speeds": [1.0]}, "sweep.speeds: unknown field")])
def test_bad_grids_refused(grid, message):
    with pytest.raises(ConfigError, match=message):
        grid_conditions(grid)


def test_sweep_needs_one_experiment_and_a_sane_batch(tmp_path, capsys):
    assert main(["sweep", str(REPO / "configs" / "default.toml"), "--out", str(tmp_path / "x")]) == 2
    assert "exactly one experiment" in capsys.readouterr().err
    assert main(["sweep", str(FOOTPRINT), "--batch", "-1", "--out", str(tmp_path / "x")]) == 2
    assert "--batch -1" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()  # refused before anything was written


def test_sweep_grid_reaches_the_config():
    rc = load_run_config(FOOTPRINT, ["sweep.loads_kg=[2312.5]"])
    assert grid_conditions(rc.sweep)[0]["load_N"] == pytest.approx(2312.5 * U.G0)


# ---- every experiment over the whole grid (slow) -------------------------------------------------------
QUICK = [a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)]
EXPERIMENT_CONFIGS = sorted(p.name for p in (REPO / "configs" / "experiments").glob("*.toml"))


def test_every_experiment_has_a_config_to_sweep():
    from jtire.experiments import REGISTRY

    named = {load_run_config(REPO / "configs" / "experiments" / n).experiments[0].name for n in EXPERIMENT_CONFIGS}
    # slip_step (V03) is the rigid-ring validation's shell run; the study's twelve and jtire's E13 and E14
    assert named == set(REGISTRY) - {"slip_step"} and len(named) == 14


@pytest.mark.slow
@pytest.mark.parametrize("config", EXPERIMENT_CONFIGS)
def test_sweep_runs_every_experiment_at_every_grid_condition(config, tmp_path, capsys):
    """`jtire sweep` of each of the fourteen experiment configs over the study's whole 3 x 3 grid (loads
    2312.5 / 4625 / 6937.5 kg x 70 / 120 / 150 psi; E05, E07, E08, E13 once per pressure), on the coarse ring
    with the suite's protocol and each config's own stage lengths: every case finishes (no blow-up, no
    failed equilibrium or settling check: a failed required check is an error, so exit 0 means every
    case's required checks held), and every quantity written is a finite number. (The extremes, 6937.5 kg at 70 psi,
    are where a too-soft or too-fast protocol would first go unstable.)"""
    import csv
    import math

    out = tmp_path / "grid"
    code = main(["sweep", str(REPO / "configs" / "experiments" / config), *QUICK, "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 0, err[-3000:]
    exp = load_run_config(REPO / "configs" / "experiments" / config).experiments[0]
    n = 3 if exp.per_pressure else 9
    rows = list(csv.DictReader((out / "summary.csv").open()))
    assert len(rows) == n and not list(out.glob("cases/*/error.txt"))
    for f in results(out):
        d = json.loads(f.read_text())
        # the checks an experiment requires raise (exit 2, error.txt); the others are diagnostics
        # reported as found (e.g. E04 at 2312.5 kg bounces off the road: no two in-contact peaks)
        assert not any(v for k, v in d["checks"].items() if k.endswith("blew_up")), (f.parent.name, d["checks"])
        for k, v in d["quantities"].items():
            assert not isinstance(v, float) or math.isfinite(v), (f.parent.name, k, v)
