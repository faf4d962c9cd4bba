"""`jtire --cluster local:2` against the default runner, on the coarse ring with the fast suite's programs.

In the physics gate: a sweep on `local:2` writes the same numbers, byte for byte, as the default runner;
a worker SIGKILLed mid-case has its case rerun elsewhere and written once; a driver SIGKILLed mid-sweep
resumes (on the default runner: the cluster is no part of a run's settings).
Slow only (CI's time): a characterization, an ARSM calibration and its posterior check, and the
Jacobian's geometry columns on `local:2` give the default runner's files and numbers.
"""

import json
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from jtire import executor

from .conftest import COARSE_SET, REPO, SOLVER_SET
from .test_cluster import DRIVER, SWEEP, TRANSIENT, jtire

distributed = pytest.importorskip("distributed", reason="the cluster extras: pip install -e '.[cluster]'")


def without_wall(f) -> dict:
    """A case's result.json without its wall time (the one field a rerun changes)."""
    r = json.loads(Path(f).read_text())
    r["info"].pop("wall_s_per_case_in_batch", None)
    return r


def case_files(out):
    """{relative path: content} of every case's result (without its wall time) and signals, and summary.csv."""
    got = {str(f.relative_to(out)): without_wall(f) if f.name == "result.json" else f.read_bytes()
           for f in sorted((Path(out) / "cases").glob("*/*"))}
    got["summary.csv"] = (Path(out) / "summary.csv").read_bytes()
    return got


# ---- simulations on a local cluster (coarse ring) --------------------------------------------------------
@pytest.fixture(scope="module")
def default_sweeps(tmp_path_factory):
    """The two sweeps on the default runner (this process): static and transient E01."""
    base = tmp_path_factory.mktemp("default")
    assert jtire("sweep", *SWEEP, "--out", base / "static") == 0
    assert jtire("sweep", *TRANSIENT, "--out", base / "transient") == 0
    return base


@pytest.mark.slow
@pytest.mark.gate
def test_local_cluster_sweeps_match_the_default_runner_byte_for_byte(default_sweeps, tmp_path):
    assert jtire("--cluster", "local:2", "sweep", *SWEEP, "--out", tmp_path / "static") == 0
    assert case_files(tmp_path / "static") == case_files(default_sweeps / "static")
    assert jtire("--cluster", "local:2", "sweep", *TRANSIENT, "--out", tmp_path / "transient") == 0
    assert case_files(tmp_path / "transient") == case_files(default_sweeps / "transient")


@pytest.mark.slow
@pytest.mark.gate
def test_a_worker_killed_mid_case_reruns_it_elsewhere_written_once(default_sweeps, tmp_path, monkeypatch):
    """SIGKILL the worker running the first case the moment it starts: Dask hands the case to the other
    worker (the nanny restarts the killed one); every case is saved once, with the default runner's numbers."""
    from jtire import results

    saved = []
    real_save = results.save
    monkeypatch.setattr(results, "save", lambda case, *a, **k: (saved.append(Path(case).name), real_save(case, *a, **k)))
    killed = []

    with executor.connect("local:2") as ex, executor.using(ex):
        client = ex.client

        def killer():
            t0 = time.monotonic()
            while not killed and time.monotonic() - t0 < 600:
                busy = {w: ks for w, ks in client.processing().items() if any(str(k).startswith("jtire-") for k in ks)}
                if busy:
                    w = next(iter(busy))
                    time.sleep(1.0)  # inside the case, past its start
                    pid = client.run(os.getpid, workers=[w])[w]
                    os.kill(pid, signal.SIGKILL)
                    killed.append((w, pid))
                time.sleep(0.05)

        th = threading.Thread(target=killer, daemon=True)
        th.start()
        assert jtire("sweep", *TRANSIENT, "--out", tmp_path / "t") == 0
        th.join(timeout=5)
    assert killed, "no worker was killed: the test did not test anything"
    assert sorted(saved) == sorted(set(saved)) and len(saved) == 4, saved
    assert case_files(tmp_path / "t") == case_files(default_sweeps / "transient")


@pytest.mark.slow
@pytest.mark.gate
def test_a_killed_driver_resumes_with_nothing_lost(default_sweeps, tmp_path):
    """The driver on local:2 SIGKILLed once its first case is saved; its workers go with it; the rerun,
    on the default runner, keeps what was saved and finishes the rest, with the same numbers."""
    out = tmp_path / "t"
    env = dict(os.environ, MPLBACKEND="Agg")
    p = subprocess.Popen([*DRIVER, "--cluster", "local:2", "sweep", *TRANSIENT, "--out", str(out)], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    t0 = time.monotonic()
    try:
        while not list(out.glob("cases/*/result.json")):
            assert p.poll() is None, p.communicate()[1].decode()[-2000:]
            assert time.monotonic() - t0 < 600, "no case finished in time"
            time.sleep(0.1)
    finally:
        p.send_signal(signal.SIGKILL)
        p.wait()
    first = {f: f.read_bytes() for f in out.glob("cases/*/result.json")}
    assert 0 < len(first) < 4, "killed too late to test a resume"
    assert jtire("sweep", *TRANSIENT, "--out", out) == 0
    assert all(f.read_bytes() == b for f, b in first.items())  # not recomputed
    assert case_files(out) == case_files(default_sweeps / "transient")


@pytest.mark.slow
def test_local_cluster_characterization_matches_the_default_runner(tmp_path):
    """`jtire characterize` with every case submitted at once to local:2: the case files, the tables
    and the `.tir` are the default runner's, byte for byte (wall times aside). Static, transient and
    per-pressure experiments at two conditions, without the validation."""
    small = [*[a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)], "--set", "grid.loads_kg=[4625.0]",
             "--set", "grid.pressures_psi=[120.0, 150.0]", "--set",
             'experiments=["footprint", "vertical_stiffness", "inplane_rotation"]', "--no-validate"]
    assert jtire("characterize", *small, "--out", tmp_path / "a") == 0
    assert jtire("--cluster", "local:2", "characterize", *small, "--out", tmp_path / "b") == 0
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    assert files == sorted(p.relative_to(tmp_path / "b") for p in (tmp_path / "b").rglob("*") if p.is_file())
    assert "tire.tir" in {str(f) for f in files}
    for f in files:
        if f.name == "result.json":
            assert without_wall(tmp_path / "a" / f) == without_wall(tmp_path / "b" / f), f
        else:
            assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f


SMALL_CALIBRATION = '''tire_file = "coarse_tire.toml"
method = "arsm"
[targets.DZ]
experiment = "vertical_stiffness"
quantity = "deflection_m"
condition = { load_kg = 4625.0, pressure_psi = 120.0 }
table = { stated_load_kN = 50.0, max_load_kN = 60.0 }
measured_mm = 39.0625
[targets.DY]
experiment = "lateral_stiffness"
quantity = "lateral_deflection_m"
condition = { load_kg = 4625.0, pressure_psi = 120.0 }
table = { force_kN = 5.0, decay_s = 0.0 }
measured_mm = 11.0997
[[free]]
name = "parts.mid_sidewall.E_meridional"
factor = [0.33, 3.0]
[[free]]
name = "geometry.crown_radius"
bounds = [1000.0, 4000.0]
'''
# a posterior over it: 6 runs train a linear emulator; 4 check draws through the shell model
SMALL_POSTERIOR = '''calibration = "small.toml"
history = "a"
[uncertainty.DZ]
relative = 0.03
why = "test"
[uncertainty.DY]
relative = 0.05
why = "test"
[emulator]
candidates = ["linear", "reduced"]
seed = 0
[sampler]
walkers = 8
max_steps = 1000
check_every = 100
n_tau = 50
seed = 0
[check]
draws = 4
seed = 0
refine = false
'''


def small_calibration(folder):
    """small.toml, posterior.toml and the coarse ring's tire file (32 segments, 4 crown elements) in folder."""
    tire = (REPO / "configs" / "tires" / "xone_xda.toml").read_text()
    coarse = tire.replace("\nn_theta = 64 ", "\nn_theta = 32 ").replace("\nn_crown = 6 ", "\nn_crown = 4 ")
    assert coarse.count("= 32 ") == 1 and "\nn_crown = 4 " in coarse
    (folder / "coarse_tire.toml").write_text(coarse)
    (folder / "small.toml").write_text(SMALL_CALIBRATION)
    (folder / "posterior.toml").write_text(SMALL_POSTERIOR)
    return folder / "small.toml"


@pytest.mark.slow
def test_local_cluster_arsm_calibration_matches_the_default_runner(tmp_path, monkeypatch):
    """An ARSM calibration through the shell model (coarse ring, E02 and E09 static, a modulus and the
    crown radius free: each point its own section), 6 evaluations: on local:2 every evaluation's
    responses, the calibrated tire file and Table 4-4 are the default runner's, byte for byte. Then
    the posterior check (`sample --check`, 4 draws through the shell model) on that calibration: the
    same simulated draws and coverage on local:2 as in this process."""
    monkeypatch.chdir(tmp_path)
    cfg = small_calibration(tmp_path)
    assert jtire("calibrate", cfg, "--out", "a", "--budget", "6") == 0
    assert jtire("--cluster", "local:2", "calibrate", cfg, "--out", "b", "--budget", "6") == 0

    def jsonl(f, drop=("batch_wall_s",)):
        rows = [json.loads(ln) for ln in (tmp_path / f).read_text().splitlines()]
        return [{k: v for k, v in r.items() if k not in drop} for r in rows]

    a = jsonl("a/history.jsonl")
    assert len(a) == 6 and jsonl("b/history.jsonl") == a
    for f in ("calibrated_tire.toml", "table_4_4.csv"):
        assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f
    assert jtire("sample", "posterior.toml", "--out", "s_a", "--check") == 0
    assert jtire("--cluster", "local:2", "sample", "posterior.toml", "--out", "s_b", "--check") == 0
    runs = jsonl("s_a/check_runs.jsonl", drop=())
    assert len(runs) == 4 and jsonl("s_b/check_runs.jsonl", drop=()) == runs
    assert (tmp_path / "s_a" / "check.json").read_bytes() == (tmp_path / "s_b" / "check.json").read_bytes()


@pytest.mark.slow
def test_the_geometry_columns_plain_runs_on_a_cluster_are_the_in_process_ones(tmp_path):
    """The Jacobian's geometry columns are forward differences of plain runs: on local:2 (all the
    columns' runs at once) each run's responses are those of the in-process runs, exactly."""
    import numpy as np

    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration

    spec = load_calibration(small_calibration(tmp_path))
    sim = ShellSimulator(spec, spec.tire)
    jobs = sim.target_jobs()
    theta = spec.space.default.copy()
    points = [theta, theta + np.array([0.0, 1e-3])]
    here = np.array([sim._values(jobs, th, 2) for th in points])
    assert np.all(np.isfinite(here)) and not np.array_equal(here[0], here[1])  # the radius moved them
    with executor.connect("local:2") as ex:
        there = sim._values_on(ex, jobs, points, spec.response_names)
    np.testing.assert_array_equal(there, here)
