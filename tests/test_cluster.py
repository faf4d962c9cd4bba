"""`jtire --cluster SPEC`: the cases of `sweep`, `characterize` and the calibration's evaluations on a Dask cluster.

Fast (no simulation): the spec and the cluster.toml are checked with one line each, the SLURM and PBS
job scripts are rendered and read (no batch queue here), a task refuses a driver of another build, and
a worker of another jtire build joining a scheduler is refused before anything runs.
In the physics gate (coarse ring, the fast suite's programs): a sweep on `local:2` writes the same
numbers, byte for byte, as the default runner; a worker SIGKILLed mid-case has its case rerun elsewhere
and written once; a driver SIGKILLed mid-sweep resumes (on the default runner: the cluster is no part of
a run's settings).
Slow only (CI's time): a characterization, an ARSM calibration and its posterior check, and the
Jacobian's geometry columns on `local:2` give the default runner's files and numbers.
"""

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from jtire import executor
from jtire.cli import main
from jtire.errors import ClusterError, ConfigError

from .conftest import COARSE_SET, REPO, SOLVER_SET

distributed = pytest.importorskip("distributed", reason="the cluster extras: pip install -e '.[cluster]'")

FOOTPRINT = REPO / "configs" / "experiments" / "footprint.toml"
# static E01 (the default method) at two conditions and the transient E01 at two: the static solves'
# host BLAS calls and the transient's compiled step both have to come out the same on a worker
SWEEP = [str(FOOTPRINT), *[a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)],
         "--set", "sweep.loads_kg=[4625.0]", "--set", "sweep.pressures_psi=[120.0, 150.0]"]
TRANSIENT = [*SWEEP[:-4], "--set", "sweep.loads_kg=[2312.5, 4625.0]", "--set", "sweep.pressures_psi=[120.0, 150.0]",
             "--set", "footprint.method=transient"]
DRIVER = [sys.executable, "-c", "import sys; from jtire.cli import main; sys.exit(main(sys.argv[1:]))"]


def jtire(*argv):
    return main([str(a) for a in argv])


def case_files(out):
    """{relative path: bytes} of every case's result and signals, without the wall times in result.json."""
    import json

    got = {}
    for f in sorted((Path(out) / "cases").glob("*/*")):
        if f.name == "result.json":
            r = json.loads(f.read_text())
            r["info"].pop("wall_s_per_case_in_batch", None)
            got[str(f.relative_to(out))] = json.dumps(r, sort_keys=True).encode()
        else:
            got[str(f.relative_to(out))] = f.read_bytes()
    got["summary.csv"] = (Path(out) / "summary.csv").read_bytes()
    return got


# ---- no simulation --------------------------------------------------------------------------------
@pytest.mark.parametrize("spec, line", [
    ("local:0", "--cluster local:0: local needs 1 to"),
    ("local", "--cluster local: expected local:N, tcp://HOST:PORT, slurm or pbs"),
    ("tcp://host", "--cluster tcp://host: expected"),
    ("sge", "--cluster sge: expected"),
])
def test_a_bad_spec_is_one_line(spec, line, capsys, tmp_path):
    assert jtire("--cluster", spec, "sweep", *SWEEP, "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err
    assert line in err and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()


def test_jobs_that_do_not_run_on_a_cluster_refuse_it(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("JTIRE_CLUSTER", "local:2")  # the environment's default, as a user would set it
    assert jtire("data", "--out", tmp_path / "d") == 2
    assert "--cluster local:2: only sweep, characterize, calibrate, sample run on a cluster" in capsys.readouterr().err


def test_an_unreachable_scheduler_is_one_line(capsys, tmp_path):
    assert jtire("--cluster", "tcp://127.0.0.1:9", "sweep", *SWEEP, "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err
    assert "cannot reach the scheduler" in err and err.count("\n") == 1, err


CLUSTER_TOML = """
[slurm]
jobs = 4
queue = "compute"
account = "tires"
cores = 16
processes = 16
memory = "64GB"
walltime = "04:00:00"
cache_dir = "/local/jtire-cache"
job_script_prologue = ["source ~/venvs/jtire/bin/activate"]

[pbs]
cores = 8
processes = 8
memory = "32GB"
walltime = "02:00:00"
"""


def test_slurm_and_pbs_job_scripts(tmp_path):
    """The job script a SLURM or PBS job would be submitted with (rendered, not submitted): the queue,
    account, cores, memory and walltime of cluster.toml; one device and one thread per worker process,
    the node-local compile cache, the user's prologue before the worker starts."""
    pytest.importorskip("dask_jobqueue")
    from jtire.cluster_config import job_script

    f = tmp_path / "cluster.toml"
    f.write_text(CLUSTER_TOML)
    s = job_script("slurm", f)
    for line in ("#SBATCH -p compute", "#SBATCH -A tires", "#SBATCH --cpus-per-task=16", "#SBATCH -t 04:00:00",
                 "export JTIRE_CPU_DEVICES=1", "export JTIRE_CACHE_DIR=/local/jtire-cache",
                 "source ~/venvs/jtire/bin/activate"):
        assert line in s, (line, s)
    assert "#SBATCH --mem=" in s
    worker = next(x for x in s.splitlines() if "distributed.cli.dask_worker" in x)
    assert "--nworkers 16" in worker and worker.rstrip().endswith("--nthreads 1"), worker
    assert s.index("JTIRE_CPU_DEVICES") < s.index("dask_worker")
    p = job_script("pbs", f)
    assert "#PBS -l select=1:ncpus=8" in p and "#PBS -l walltime=02:00:00" in p and "JTIRE_CPU_DEVICES=1" in p
    for kind in ("slurm", "pbs"):  # the shipped example (docs/cluster.md) is a valid file
        assert "--nworkers 16" in job_script(kind, REPO / "configs" / "cluster.toml")


@pytest.mark.parametrize("edit, line", [
    (("cores = 16", ""), "slurm.cores missing"),
    (("memory = \"64GB\"", "memory = \"lots\""), "slurm.memory = 'lots': must be like"),
    (("walltime = \"04:00:00\"", "walltime = \"4h\""), "slurm.walltime = '4h': must be HH:MM:SS"),
    (("processes = 16", "processes = 17"), "slurm.processes = 17: must be in [1, cores = 16]"),
    (("jobs = 4", "jobs = 0"), "slurm.jobs = 0: must be an integer in [1, 10000]"),
    (("queue = \"compute\"", "partition = \"compute\""), "slurm.partition: unknown field"),
    (("[slurm]", "[slurmm]"), "no [slurm] table"),
])
def test_a_bad_cluster_toml_is_one_line(edit, line, tmp_path, capsys):
    pytest.importorskip("dask_jobqueue")
    f = tmp_path / "cluster.toml"
    f.write_text(CLUSTER_TOML.replace(*edit))
    assert jtire("--cluster", "slurm", "--cluster-config", f, "sweep", *SWEEP, "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err
    assert line in err and str(f) in err and err.count("\n") == 1, err


def test_no_cluster_toml_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("JTIRE_CLUSTER_CONFIG", raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))
    assert jtire("--cluster", "pbs", "sweep", *SWEEP, "--out", tmp_path / "o") == 2
    assert "no cluster.toml" in capsys.readouterr().err


def test_a_task_refuses_a_driver_of_another_build():
    task = executor.CaseTask("footprint", {}, {}, None, {})
    with pytest.raises(ClusterError, match="runs jtire .* this driver 0.0.0\\+000000000000: start the workers"):
        executor.run_task(task, "0.0.0+000000000000", use_cache=False)


def test_parse_spec():
    assert executor.parse_spec("local:2") == ("local", 2)
    assert executor.parse_spec("tcp://10.0.0.5:8786") == ("tcp", "tcp://10.0.0.5:8786")
    assert executor.parse_spec("slurm") == ("slurm", None)
    with pytest.raises(ConfigError):
        executor.parse_spec("local:-1")


# ---- simulations on a local cluster (coarse ring) --------------------------------------------------------
@pytest.fixture(scope="module")
def default_sweeps(tmp_path_factory, e01_singles):
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


def test_a_worker_of_another_build_is_refused(tmp_path, capsys):
    """A worker importing a copy of jtire with one edited file (another build) joins a scheduler: the
    driver refuses the cluster with one line before anything runs."""
    import jtire as pkg
    from distributed import LocalCluster

    copy = tmp_path / "other" / "jtire"
    shutil.copytree(Path(pkg.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "units.py").write_text((copy / "units.py").read_text() + "# another build\n")
    with LocalCluster(n_workers=0, processes=False, protocol="tcp", dashboard_address=None) as cluster:
        env = dict(os.environ, PYTHONPATH=str(copy.parent))
        w = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker", cluster.scheduler_address,
                              "--nworkers", "1", "--nthreads", "1", "--no-nanny"], env=env, cwd=tmp_path,
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            from distributed import Client

            with Client(cluster.scheduler_address) as c:
                c.wait_for_workers(1, timeout=60)
            assert jtire("--cluster", cluster.scheduler_address, "sweep", *SWEEP, "--out", tmp_path / "o") == 2
        finally:
            w.kill()
            w.wait()
    err = capsys.readouterr().err
    assert "1 of 1 workers run another jtire build" in err and err.count("\n") == 1, err
    assert not (tmp_path / "o" / "cases").exists()


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
            assert case_files_json(tmp_path / "a" / f) == case_files_json(tmp_path / "b" / f), f
        else:
            assert (tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes(), f


def case_files_json(f):
    import json

    r = json.loads(Path(f).read_text())
    r["info"].pop("wall_s_per_case_in_batch", None)
    return r


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
    import json

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
        there = sim._values_on(ex, jobs, points, 2)
    np.testing.assert_array_equal(there, here)
