"""One batch runner for every experiment: cases x parameter sets, vmapped, sharded over devices.

`simulate_batch(exp, model, params, cases)` is the pure, traceable batch: the experiment's
`simulate` vmapped over the leading axis of `cases` (and of `params` when it carries one). Run
eagerly with the batch placed across the devices (`shard`), every phase goes through one compiled
phase program per phase structure and batch shape, partitioned over the devices by XLA, and shared by
all experiments (`experiments.program.run_one`); JAX's persistent cache (`jtire.cache`) keeps the
compiled programs across processes.

`run(exp, tire, conditions, ...)` is the host driver: it expands conditions into cases, computes the
stable step of each case, runs the cases in batches (padded to a multiple of the device count),
reduces every condition on the host as soon as its batch returns and hands each result to a
callback (so sweeps save as they go). On a CPU the devices are host devices: `jtire` asks JAX for
one per core at import (`JTIRE_CPU_DEVICES` overrides). On a GPU it runs unchanged over
`jax.devices()`. Several hosts (`jax.distributed`) are not supported: see docs/experiments.md.
"""

import dataclasses
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from . import cache, solve
from .errors import JtireError, UnderResolved
from .experiments.phases import Case
from .experiments.program import phase_traces


def _stack(trees):
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *trees)


def _index(tree, i):
    return jax.tree_util.tree_map(lambda a: a[i], tree)


def simulate_batch(exp, model, params, cases: Case, *, params_batched: bool = False):
    """exp.simulate for every case (leading axis of `cases`; of `params` too when params_batched).

    Traceable (vmap, jvp, jit all apply). Called eagerly -- as `run` does -- every phase runs through
    the shared compiled phase program (`experiments.program.run_one`), batched over the cases and
    partitioned over the devices that hold them (`shard`)."""
    return jax.vmap(lambda p, c: exp.simulate(model, p, c), in_axes=(0 if params_batched else None, 0))(params, cases)


def _case_by_case(exp, model, params, cases: Case, params_batched: bool):
    """The cases of a batch one after another, unbatched (the static solves): under vmap a Newton
    loop's conditional steps (refactorize or not, GMRES restarts) become selects that run both
    branches, so a vmapped solve costs several times an unbatched one even for one case
    (docs/design-notes.md). One compiled program serves any batch size."""
    n = jax.tree_util.tree_leaves(cases)[0].shape[0]
    # the cases are committed to their device (`shard`), so the programs run there; no default-device
    # context, which is part of a trace's key: every device then shares one trace of each program
    outs = [jax.device_get(exp.simulate(model, _index(params, i) if params_batched else params, _index(cases, i)))
            for i in range(n)]
    return jax.tree_util.tree_map(lambda *a: np.stack(a), *outs)


def shard(tree, n_devices: int, device: int = 0):
    """Place a batch (leading axis) across the first n_devices devices; the compiled phase programs
    then run each device's share of the cases on that device (XLA partitions the batch). One device:
    the device numbered `device`."""
    if n_devices <= 1:
        # committed to the device like every phase program's output: a compiled program is specific
        # to whether its inputs are committed, so uncommitted cases made the first phase trace apart
        return jax.device_put(tree, jax.devices()[device])
    mesh = Mesh(np.array(jax.devices()[:n_devices]), ("cases",))
    return jax.device_put(tree, NamedSharding(mesh, PartitionSpec("cases")))


def program_traces() -> int:
    """Times the shared phase program has been traced in this process (tests)."""
    return phase_traces()


def stable_steps(model, params_list, pressures, settle_damping) -> np.ndarray:
    """The explicit step (s) of each (params, pressure) pair (power iteration per distinct pair; one
    compiled program for any number of pairs)."""
    c = float(settle_damping)
    out, seen = [], {}
    for p, pr in zip(params_list, pressures):
        key = (id(p), float(pr))
        if key not in seen:
            w = float(_max_frequency(model, p, jnp.asarray(pr, dtype=jnp.float64)))
            z = c / (2 * w)
            seen[key] = solve.SAFETY * (2.0 / w) * (np.sqrt(1 + z * z) - z)
        out.append(seen[key])
    return np.array(out)


_max_frequency = eqx.filter_jit(solve.max_frequency)


def n_devices_for(n_cases: int, devices=None) -> int:
    """Devices used for a batch of n_cases: all available (or `devices`), at most one per case."""
    avail = len(jax.devices()) if devices is None else int(devices)
    return max(1, min(avail, n_cases))


@dataclasses.dataclass
class CaseFailure:
    """A condition whose simulation or reduction failed (the error message says where and when)."""

    condition: dict
    error: JtireError


def run(exp, tire, conditions: list, params_list=None, *, devices=None, batch: int = 0, on_result=None,
        on_batch=None, keep_outputs: bool = False, device: int | None = None):
    """Run `exp` for every condition; returns a list (one per condition) of ExperimentResult or
    CaseFailure, in order.

    params_list: None (the tire's parameters for every condition) or one MaterialParams per
    condition. batch: cases per batch (0: all at once; 1: case by case, each saved the moment it is
    done). on_result(i, result_or_failure) is called as soon as condition i is reduced;
    on_batch(n_conditions_done, n_total, wall_s) after every batch. keep_outputs: attach the raw
    per-case outputs (numpy) as result.outputs (for traced checks). device: run every case on this one
    device (a caller running several runs at once, `side_by_side`, gives each its own);
    None: with several devices and batches of one case (statics always, transients with batch = 1),
    the cases run side by side, one per device at a time. Larger transient batches take every device.
    """
    cache.release_programs_if_crowded()  # between runs: a process holding too many programs crashes
    if hasattr(exp, "components"):  # a composite (E11): its components' results combined per condition
        subs = [run(c, tire, conditions, params_list, devices=devices, batch=batch, keep_outputs=keep_outputs,
                    device=device) for c in exp.components]
        results = []
        for i, cond in enumerate(conditions):
            parts = [s[i] for s in subs]
            res = next((p for p in parts if isinstance(p, CaseFailure)), None) or exp.combine(dict(cond), parts)
            results.append(res)
            if on_result is not None:
                on_result(i, res)
        if on_batch is not None:
            on_batch(len(conditions), len(conditions), 0.0)
        return results
    model = tire.model
    plist = [tire.params] * len(conditions) if params_list is None else list(params_list)
    if len(plist) != len(conditions):
        raise ValueError(f"{len(plist)} parameter sets for {len(conditions)} conditions")
    params_batched = params_list is not None
    flat = []  # (condition index, case dict)
    for i, cond in enumerate(conditions):
        flat += [(i, c) for c in exp.cases(cond)]
    dts = (stable_steps(model, [plist[i] for i, _ in flat], [c["pressure_Pa"] for _, c in flat],
                        float(exp.proto.settle_damping)) if exp.time_stepped else np.full(len(flat), np.nan))
    size = len(flat) if batch <= 0 else min(batch, len(flat))
    if not exp.shardable:  # static solves run case by case anyway: each case is its own batch, so it is
        size = 1  # reduced and handed to on_result (saved) the moment it finishes
    n_dev = n_devices_for(size, devices) if exp.shardable and size > 1 else 1
    size = -(-size // n_dev) * n_dev  # a multiple of the device count
    starts = list(range(0, len(flat), size))

    def run_chunk(start, dev0=0):
        chunk = list(range(start, min(start + size, len(flat))))
        padded = chunk + [chunk[-1]] * (size - len(chunk))
        cases = _stack([Case.of(flat[k][1]["load_N"] if "load_N" in flat[k][1] else 0.0, flat[k][1]["pressure_Pa"],
                                dts[k], exp.aux(flat[k][1])) for k in padded])
        params = shard(_stack([plist[flat[k][0]] for k in padded]), n_dev, dev0) if params_batched else plist[0]
        t0 = time.perf_counter()
        if exp.shardable:
            # the cases committed to dev0 take the programs there, and what the plan makes between phases
            # follows them; no default-device context (part of a trace's key): one trace for every device
            outs = jax.device_get(simulate_batch(exp, model, params, shard(cases, n_dev, dev0),
                                                 params_batched=params_batched))
        else:
            outs = _case_by_case(exp, model, params, shard(cases, 1, dev0), params_batched)
        return chunk, outs, time.perf_counter() - t0

    pending = {}  # condition index -> {case index: outputs} (a condition may have several cases)
    results = [None] * len(conditions)
    done = 0

    def collect(chunk, outs, wall):
        nonlocal done
        for j, k in enumerate(chunk):
            i, case = flat[k]
            pending.setdefault(i, {})[k] = _index(outs, j) | {"dt": float(dts[k])}
            if len(pending[i]) == len(exp.cases(conditions[i])):
                got = pending.pop(i)
                res = _reduce(exp, tire, conditions[i], [got[c] for c in sorted(got)], keep_outputs, wall / len(chunk))
                if isinstance(res, CaseFailure) and isinstance(res.error, UnderResolved):
                    res = _refined(exp, tire, conditions[i], plist[i] if params_batched else None, keep_outputs, res,
                                   device)
                results[i] = res
                done += 1
                if on_result is not None:
                    on_result(i, res)
        if on_batch is not None:
            on_batch(done, len(conditions), wall)

    avail = len(jax.devices()) if devices is None else int(devices)
    if n_dev > 1 or device is not None or avail < 2 or len(starts) < 2:
        for start in starts:
            collect(*run_chunk(start, int(device or 0)))
        return results
    # Batches of one case (static solves always), several of them, several devices: side by side
    side_by_side([lambda d, st=st: run_chunk(st, d) for st in starts], lambda k, got: collect(*got), avail)
    return results


def side_by_side(jobs, on_done, devices=None) -> None:
    """Run `jobs` (callables job(device index) -> value) one per device at a time over the first
    `devices` devices (default all), taken in list order as devices come free; on_done(k, value) runs
    here, in the calling thread, as each finishes. Threads: JAX releases the GIL while a program runs,
    so the cases run side by side, faster than one after the other (docs/design-notes.md). An error
    in a job cancels the jobs not started and is raised here."""
    import queue
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    n = min(len(jax.devices()) if devices is None else int(devices), len(jax.devices()), len(jobs))
    if n <= 1:
        for k, job in enumerate(jobs):
            on_done(k, job(0))
        return
    free = queue.SimpleQueue()
    for d in range(n):
        free.put(d)

    def on_free_device(job):
        d = free.get()
        try:
            return job(d)
        finally:
            free.put(d)

    with ThreadPoolExecutor(n) as pool:
        todo = {pool.submit(on_free_device, job): k for k, job in enumerate(jobs)}
        try:
            while todo:
                fin, _ = wait(todo, return_when=FIRST_COMPLETED)
                for f in fin:
                    on_done(todo.pop(f), f.result())
        except BaseException:
            for f in todo:
                f.cancel()
            raise


MAX_REFINED_N_THETA = 256  # segments: a case whose result is under-resolved is rerun on up to this many


def _refined(exp, tire, condition, params, keep, failure, device=None):
    """A case that failed a discretization check of its own (`UnderResolved`) rerun on a ring with twice
    the segments (again, up to MAX_REFINED_N_THETA); the result says which ring gave it and why. The
    failure stands where the ring cannot be refined further."""
    from .tire import make_tire

    n = tire.spec.n_theta
    if 2 * n > MAX_REFINED_N_THETA:
        return failure
    fine = make_tire(dataclasses.replace(tire.spec, n_theta=2 * n))
    [res] = run(exp, fine, [condition], None if params is None else [params], batch=1, keep_outputs=keep, device=device)
    if not isinstance(res, CaseFailure):  # an inner refinement set n_theta; the first reason is kept
        res.info.setdefault("n_theta", fine.spec.n_theta)
        res.info |= {"refined_from_n_theta": n, "refined_because": str(failure.error)}
    return res


def _reduce(exp, tire, condition, outputs, keep, wall_per_case):
    try:
        res = exp.reduce(tire, dict(condition), outputs)
    except JtireError as e:
        return CaseFailure(dict(condition), e)
    res.info |= {"wall_s_per_case_in_batch": wall_per_case} | (
        {"dt_s": outputs[0]["dt"]} if np.isfinite(outputs[0]["dt"]) else {})
    if keep:
        res.outputs = outputs
    return res
