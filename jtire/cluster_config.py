"""The batch-queue settings of `jtire --cluster slurm|pbs`: a cluster.toml, kept apart from every run's
settings (a run may resume on another executor), turned into a dask-jobqueue cluster.

The file is found at --cluster-config, else $JTIRE_CLUSTER_CONFIG, else ./cluster.toml, else
~/.config/jtire/cluster.toml. `configs/cluster.toml` is a commented example. Its [slurm] or [pbs] table
takes the jobqueue settings below; each job runs `processes` worker processes, each one case at a time
on one host device, and `cache_dir` puts the compile cache on node-local disk
(JAX's cache writes are not atomic on a network file system).
"""

import os
import re
from pathlib import Path

from .errors import ConfigError

# key -> (kind, check, allowed range for the message)
_INT = {"jobs": (1, 10000), "cores": (1, 1024), "processes": (1, 1024)}
_STR = {"queue", "account", "walltime", "memory", "local_directory", "log_directory", "interface", "cache_dir",
        "python", "resource_spec"}
_LISTS = {"job_extra_directives", "job_script_prologue", "worker_extra_args"}
_MEMORY = re.compile(r"\d+(\.\d+)?\s*[KMGT]i?B")
_WALLTIME = re.compile(r"(\d+-)?\d{1,3}:\d{2}:\d{2}")


def find(path=None) -> Path:
    for p in (path, os.environ.get("JTIRE_CLUSTER_CONFIG"), "cluster.toml",
              Path.home() / ".config" / "jtire" / "cluster.toml"):
        if p and Path(p).is_file():
            return Path(p)
    if path:
        raise ConfigError(f"--cluster-config {path}: no such file")
    raise ConfigError("--cluster slurm|pbs: no cluster.toml (give --cluster-config FILE, set JTIRE_CLUSTER_CONFIG, "
                      "or copy configs/cluster.toml to ./cluster.toml)")


def read(kind: str, path=None) -> tuple:
    """(validated settings of the [kind] table, file). One line naming the file and field otherwise."""
    from .config import read_toml

    f = find(path)
    raw = read_toml(f)
    if kind not in raw or not isinstance(raw[kind], dict):
        raise ConfigError(f"{f}: no [{kind}] table (the settings of --cluster {kind})")
    t = dict(raw[kind])
    for key, v in t.items():
        where = f"{f}: {kind}.{key}"
        if key in _INT:
            lo, hi = _INT[key]
            if not isinstance(v, int) or isinstance(v, bool) or not lo <= v <= hi:
                raise ConfigError(f"{where} = {v!r}: must be an integer in [{lo}, {hi}]")
        elif key in _STR:
            if not isinstance(v, str) or not v.strip():
                raise ConfigError(f"{where} = {v!r}: must be a non-empty string")
        elif key in _LISTS:
            if not isinstance(v, list) or not all(isinstance(x, str) for x in v):
                raise ConfigError(f"{where}: must be a list of strings")
        else:
            raise ConfigError(f"{where}: unknown field (allowed: {', '.join(sorted([*_INT, *_STR, *_LISTS]))})")
    for key in ("cores", "memory"):
        if key not in t:
            raise ConfigError(f"{f}: {kind}.{key} missing (cores and memory per job)")
    if "memory" in t and not _MEMORY.fullmatch(t["memory"].strip()):
        raise ConfigError(f"{f}: {kind}.memory = {t['memory']!r}: must be like \"64GB\" or \"500MiB\"")
    if "walltime" in t and not _WALLTIME.fullmatch(t["walltime"].strip()):
        raise ConfigError(f"{f}: {kind}.walltime = {t['walltime']!r}: must be HH:MM:SS (or D-HH:MM:SS)")
    t.setdefault("processes", 1)
    t.setdefault("jobs", 1)
    if t["processes"] > t["cores"]:
        raise ConfigError(f"{f}: {kind}.processes = {t['processes']}: must be in [1, cores = {t['cores']}]")
    return t, f


def jobqueue_kwargs(kind: str, t: dict) -> dict:
    """dask-jobqueue's keyword arguments for the settings: each worker process runs one case at a time on
    one host device (one thread, JTIRE_CPU_DEVICES=1, the same on every worker so they share compiled
    programs), with the node-local cache folder. So processes = cores uses every core."""
    kw = {k: v for k, v in t.items() if k not in ("jobs", "cache_dir")}
    prologue = ["export JTIRE_CPU_DEVICES=1"]
    if "cache_dir" in t:
        prologue.append(f"export JTIRE_CACHE_DIR={t['cache_dir']}")
    kw["job_script_prologue"] = prologue + list(t.get("job_script_prologue", []))
    kw["worker_extra_args"] = ["--nthreads", "1", *t.get("worker_extra_args", [])]
    return kw


def job_cluster(kind: str, path=None) -> tuple:
    """(dask-jobqueue cluster, jobs to start) for --cluster slurm|pbs."""
    try:
        from dask_jobqueue import PBSCluster, SLURMCluster
    except ImportError:
        from .errors import ClusterError

        raise ClusterError(f"--cluster {kind}: needs dask-jobqueue: pip install 'jtire[cluster]'") from None
    t, _ = read(kind, path)
    cls = SLURMCluster if kind == "slurm" else PBSCluster
    return cls(**jobqueue_kwargs(kind, t)), t["jobs"]


def job_script(kind: str, path=None) -> str:
    """The batch script one job of the cluster would be submitted with (nothing is submitted)."""
    cluster, _ = job_cluster(kind, path)
    try:
        return cluster.job_script()
    finally:
        cluster.close()
