"""`jtire --cluster SPEC`, without simulation: the spec and the cluster.toml are checked with one line
each, the SLURM and PBS job scripts are rendered and read (no batch queue here), a task refuses a driver
of another build, and a worker of another jtire build joining a scheduler is refused before anything
runs. The simulations on a local cluster: tests/test_cluster_runs.py.
"""

import os
import shutil
import subprocess
import sys
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
