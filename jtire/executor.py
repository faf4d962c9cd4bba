"""Where a long job's cases run: in this process (the default) or on a Dask cluster (`jtire --cluster SPEC`).

A case is a `CaseTask` of plain data (an experiment's name and validated table, the solver settings, the
tire spec, one condition). `InProcess` runs a job's tasks through `jtire.batch` as before (an experiment's
conditions together, side by side over the host devices). `DaskExecutor` submits every task of the job at
once to a Dask cluster; a worker rebuilds the tire and the experiment from the task, runs it, and returns
the reduced result. The driver (this process) is the only writer of case folders, so a killed driver
resumes as before, and the cluster never enters a run's settings: a run may resume on another executor.

Cluster specs: `local:N` (N worker processes on this machine), `tcp://HOST:PORT` (a running Dask
scheduler), `slurm` or `pbs` (dask-jobqueue, with the queue settings from a cluster.toml; see
`jtire.cluster_config`). The extras come with `pip install 'jtire[cluster]'`.
"""

import contextlib
import dataclasses
import json
import os
import re

from .errors import ClusterError, ConfigError, JtireError


@dataclasses.dataclass(frozen=True)
class CaseTask:
    """One condition of one experiment, as plain data a worker process can rebuild everything from."""

    experiment: str
    table: dict  # the experiment's validated config table (SI)
    solver: dict
    tire: object  # config.TireSpec: numbers only
    condition: dict
    contact_table: bool = False  # also return the contact pressure over the patch (the footprint's Figure 5-2)
    params: tuple | None = None  # a calibration's material parameters: the leaves (numpy) of the tire's
    # MaterialParams in tree order; None: the tire file's own


def params_leaves(params) -> tuple:
    """A MaterialParams as plain data for a CaseTask (its leaves as numpy arrays)."""
    import jax
    import numpy as np

    return tuple(np.asarray(x) for x in jax.tree_util.tree_leaves(params))


@dataclasses.dataclass
class Outcome:
    """A finished task: an ExperimentResult or a batch.CaseFailure, and extra tables ({name: {column: array}})."""

    result: object
    tables: dict


def _group_key(task: CaseTask) -> str:
    # tasks with one key share a tire and an experiment instance (and, in a batch, compiled programs)
    from .fingerprint import plain

    return json.dumps(plain([task.experiment, task.table, task.solver, task.tire, task.contact_table]),
                      sort_keys=True, default=str)


def groups(tasks) -> list:
    """Task indices grouped by experiment, table, solver and tire, in first-seen order."""
    out = {}
    for i, t in enumerate(tasks):
        out.setdefault(_group_key(t), []).append(i)
    return list(out.values())


def build(task: CaseTask):
    """(experiment instance, Tire) of a task."""
    from .experiments import REGISTRY
    from .experiments.phases import Protocol
    from .tire import make_tire

    exp = REGISTRY[task.experiment].from_table(task.table, Protocol.from_dict(task.solver), task.tire)
    return exp, make_tire(task.tire)


def task_params(task: CaseTask, tire):
    """The task's MaterialParams (its leaves in the structure of the tire's own), or None."""
    import jax
    import jax.numpy as jnp

    if task.params is None:
        return None
    tree = jax.tree_util.tree_structure(tire.params)
    if tree.num_leaves != len(task.params):
        raise ClusterError(f"a case's parameters have {len(task.params)} leaves, this tire's {tree.num_leaves}")
    return jax.tree_util.tree_unflatten(tree, [jnp.asarray(x) for x in task.params])


def _outcome(task: CaseTask, tire, res) -> Outcome:
    from .batch import CaseFailure

    tables = {}
    if task.contact_table and not isinstance(res, CaseFailure):
        from .contact_pressure import footprint_table

        o = res.outputs[0]
        tables["contact_pressure"] = footprint_table(tire.model, tire.params, o["y"], float(o["z_road"]))
    if hasattr(res, "outputs"):  # raw states: large, and only needed for the tables above
        del res.outputs
    return Outcome(res, tables)


class InProcess:
    """Today's runner: the tasks through `jtire.batch.run` in this process. batch_size 1 (case by case)
    with several host devices: every task is its own run, side by side over the devices in task order
    (`batch.side_by_side`), so the next experiment's cases start while the last of one still runs (an
    experiment after another left a device idle at each one's end). Otherwise each group's conditions
    in batches of `batch_size`, an experiment after another."""

    description = "this process"

    def run(self, tasks, on_outcome, batch_size: int = 1) -> None:
        import jax

        from . import batch

        built = {}  # group key -> (experiment, tire): one per group, shared by its tasks
        for idx in groups(tasks):
            built[_group_key(tasks[idx[0]])] = build(tasks[idx[0]])
        if batch_size == 1 and len(jax.devices()) > 1:
            def job(i):
                exp, tire = built[_group_key(tasks[i])]
                plist = None if tasks[i].params is None else [task_params(tasks[i], tire)]
                return lambda d: (tire, batch.run(exp, tire, [tasks[i].condition], plist, batch=1, device=d,
                                                  keep_outputs=tasks[i].contact_table)[0])

            batch.side_by_side([job(i) for i in range(len(tasks))],
                               lambda k, got: on_outcome(k, _outcome(tasks[k], *got)))
            return
        for idx in groups(tasks):
            exp, tire = built[_group_key(tasks[idx[0]])]
            keep = tasks[idx[0]].contact_table
            plist = None
            if any(tasks[i].params is not None for i in idx):
                plist = [tire.params if tasks[i].params is None else task_params(tasks[i], tire) for i in idx]

            def done(k, res, idx=idx, tire=tire):
                on_outcome(idx[k], _outcome(tasks[idx[k]], tire, res))

            batch.run(exp, tire, [tasks[i].condition for i in idx], plist, batch=batch_size, on_result=done,
                      keep_outputs=keep)


# ---- the worker's side -------------------------------------------------------------------------------
_WORKER_CACHE = []


def worker_version() -> str:
    from .fingerprint import code_version

    return code_version()


def run_task(task: CaseTask, driver_version: str, use_cache: bool) -> Outcome:
    """Run one task in a worker process: refuse another jtire build, turn the compile cache on (the
    worker's own folder: JTIRE_CACHE_DIR of its environment, else its user cache), run, reduce."""
    from . import batch

    mine = worker_version()
    if mine != driver_version:
        import socket

        raise ClusterError(f"a worker on {socket.gethostname()} runs jtire {mine}, this driver {driver_version}: "
                           f"start the workers from the same jtire build")
    if use_cache and not _WORKER_CACHE:
        from . import cache

        _WORKER_CACHE.append(cache.enable())
    exp, tire = build(task)
    params = task_params(task, tire)
    [res] = batch.run(exp, tire, [task.condition], None if params is None else [params], batch=1,
                      keep_outputs=task.contact_table)
    return _outcome(task, tire, res)


# ---- the driver's side of a Dask cluster -----------------------------------------------------------------
class DaskExecutor:
    """Every task of a job to a Dask cluster, one task per condition, at most one per worker thread at a
    time so the order stays the driver's: first one task of each group (each compiles its programs and
    writes them to the cache), then the tasks of groups whose first is back (they load those programs),
    and a waiting group's task only where a worker would otherwise sit idle (a cold cache then costs
    one compile per program, not one per worker)."""

    POLL_S = 2.0  # how often the driver looks for workers that joined (a batch queue starts them late)

    def __init__(self, client, description: str):
        self.client = client
        self.description = description

    def slots(self) -> int:
        return max(1, sum(self.client.nthreads().values()))

    def run(self, tasks, on_outcome, batch_size: int = 1) -> None:
        from distributed import wait

        from .cache import active_dir

        version, use_cache = worker_version(), active_dir() is not None
        ready, waiting = [], []  # task indices: groups whose first is back / groups still compiling
        rest = {}  # first task of a group -> the group's other tasks
        for idx in groups(tasks):
            ready.append(idx[0])  # the first of every group goes first
            rest[idx[0]] = list(idx[1:])
            waiting += idx[1:]
        running = {}  # future -> task index
        try:
            while ready or waiting or running:
                free = self.slots() - len(running)
                while free > 0 and (ready or waiting):
                    i = (ready or waiting).pop(0)
                    f = self.client.submit(run_task, tasks[i], version, use_cache, pure=False, retries=0,
                                           key=f"jtire-{tasks[i].experiment}-{i}-{os.urandom(4).hex()}")
                    running[f] = i
                    free -= 1
                try:
                    done = wait(list(running), timeout=self.POLL_S, return_when="FIRST_COMPLETED").done
                except TimeoutError:  # nothing finished: look for new workers again
                    continue
                for f in done:
                    i = running.pop(f)
                    on_outcome(i, self._result(f, tasks[i]))
                    for j in rest.pop(i, ()):  # the group's programs are in the cache now
                        if j in waiting:
                            waiting.remove(j)
                            ready.append(j)
        finally:
            for f in running:
                f.cancel()

    @staticmethod
    def _result(f, task):
        from distributed.client import FutureCancelledError

        try:
            from distributed.scheduler import KilledWorker
        except ImportError:  # older distributed
            from distributed import KilledWorker
        try:
            return f.result()
        except KilledWorker as e:
            raise ClusterError(f"a {task.experiment} case killed every worker that took it ({e}); see the "
                               f"workers' logs") from None
        except FutureCancelledError:
            raise ClusterError("the cluster cancelled a case (the scheduler or its workers went away)") from None


# ---- which executor a job uses ------------------------------------------------------------------------------
_CURRENT = []


def current():
    """The executor long jobs hand their cases to: the one `using` set, else in-process."""
    return _CURRENT[-1] if _CURRENT else InProcess()


@contextlib.contextmanager
def using(executor):
    _CURRENT.append(executor)
    try:
        yield executor
    finally:
        _CURRENT.pop()


BLAS_THREADS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
SPEC_HELP = "local:N, tcp://HOST:PORT, slurm or pbs"


def parse_spec(spec: str) -> tuple:
    """('local', N) | ('tcp', address) | ('slurm' | 'pbs', None); one line naming --cluster otherwise."""
    s = spec.strip()
    m = re.fullmatch(r"local:(\d+)", s)
    if m:
        n = int(m.group(1))
        limit = 4 * (os.cpu_count() or 1)
        if not 1 <= n <= limit:
            raise ConfigError(f"--cluster {spec}: local needs 1 to {limit} workers (4 per core on this machine)")
        return "local", n
    if re.fullmatch(r"(tcp|tls)://[^\s:/]+:\d{1,5}", s):
        return "tcp", s
    if s in ("slurm", "pbs"):
        return s, None
    raise ConfigError(f"--cluster {spec}: expected {SPEC_HELP} (or set JTIRE_CLUSTER)")


@contextlib.contextmanager
def connect(spec: str, config_file=None):
    """A DaskExecutor on the cluster `spec` names, closed (with any cluster it started) on exit."""
    kind, arg = parse_spec(spec)
    try:
        import logging

        from distributed import Client, LocalCluster
    except ImportError:
        raise ClusterError(f"--cluster {spec}: needs the cluster extras: pip install 'jtire[cluster]'") from None
    cluster = client = None
    try:
        if kind == "local":
            # fresh worker processes (spawned, never forked: JAX is not fork-safe), one thread each;
            # the environment (JTIRE_CPU_DEVICES, JTIRE_CACHE_DIR) is this process's
            # and Dask's own thread settings for BLAS dropped: the static solves' host BLAS calls round
            # differently with another thread count (docs/design-notes.md), and the numbers must be the
            # default runner's
            import dask

            unset = {f"distributed.nanny.pre-spawn-environ.{k}": None for k in BLAS_THREADS}
            with dask.config.set(unset):
                cluster = LocalCluster(n_workers=arg, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.ERROR)
            client = Client(cluster)
            where = f"{arg} local worker processes"
        elif kind == "tcp":
            try:
                client = Client(arg, timeout=10)  # seconds to reach the scheduler
            except OSError as e:
                raise ClusterError(f"--cluster {spec}: cannot reach the scheduler ({e})") from None
            where = f"the scheduler at {arg}"
        else:
            from .cluster_config import job_cluster

            cluster, jobs = job_cluster(kind, config_file)
            cluster.scale(jobs=jobs)
            client = Client(cluster)
            where = f"{jobs} {kind} jobs"
        handshake(client)
        yield DaskExecutor(client, where)
    finally:
        if client is not None:
            with contextlib.suppress(Exception):
                client.close()
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close()


def handshake(client) -> None:
    """Refuse the cluster, with one line, when a connected worker runs another jtire build (the worker
    side checks every task too, for workers that join later)."""
    mine = worker_version()
    try:
        theirs = client.run(worker_version)
    except JtireError:
        raise
    except Exception as e:  # a worker without jtire at all
        raise ClusterError(f"the cluster's workers cannot run jtire ({type(e).__name__}: {e})") from None
    other = {a: v for a, v in theirs.items() if v != mine}
    if other:
        a, v = next(iter(other.items()))
        raise ClusterError(f"{len(other)} of {len(theirs)} workers run another jtire build (worker {a}: {v}; this "
                           f"driver: {mine}): start the workers from the same build")
