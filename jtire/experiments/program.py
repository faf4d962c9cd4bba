"""An experiment's simulation as one traced program: its phases run by a single scan.

Every experiment is a fixed sequence of phases (inflate, load, hold, release, roll, ...). Each phase
is described by a *branch*: a function (y, t, mem) -> (Phase, mem) that builds the phase's drive and
start state from where the previous phase ended (y: TireState, t: time, mem: a dict of scalars the
experiment carries between phases, e.g. the road height found at first contact). `run_plan` runs the
branches in order; each phase's integration is `run_one`, one compiled program shared by every phase
of the same structure in every experiment. Phase ends come from events (settled, unstable), the
first contact height, release times, spin-up: everything is JAX code on traced values, so a whole
experiment vmaps over cases and parameter sets and can be differentiated.

Outputs are stacked over phases (`PhaseOut`, leading axis = phase): the end state, start and end
times, steps, the settled / unstable flags and the `solve.observe` samples at `n_save` uniform times
over the phase's maximum span (samples after an early end are inf).
"""

import contextlib
import contextvars

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import solve
from ..errors import SimulationError
from ..mesh import PART_NAMES
from ..state import Drive, TireState


class Phase(eqx.Module):
    """What a branch returns: the drive, the start state, the longest duration (s) and the time
    after the phase start (s) from which a settled state ends it (inf: the phase runs to its end)."""

    drive: Drive
    y0: TireState
    duration: jax.Array = eqx.field(converter=lambda v: jnp.asarray(v, dtype=jnp.float64))
    settle_after: jax.Array = eqx.field(converter=lambda v: jnp.asarray(v, dtype=jnp.float64))


class PhaseOut(eqx.Module):
    """One phase's result (stacked over phases by `run_plan`): times (s), steps, flags, the kinetic
    energy at its end (J), the fastest node at its end (speed m/s, segment, section node) and the
    saved samples. The full end state is returned for the last phase only (`run_plan`)."""

    t0: jax.Array
    t_end: jax.Array
    n_steps: jax.Array
    settled: jax.Array
    blew_up: jax.Array
    ke_end: jax.Array
    q_end: jax.Array  # (6,) rim coordinates at the end
    qd_end: jax.Array  # (6,)
    speed_max: jax.Array
    where_max: jax.Array  # (2,) int: segment, free-node column of the fastest node
    saved: dict
    frames: dict = None  # whole frames at n_frames uniform times + the end (only under `recording_frames`)


def f64(x):
    """A float64 array (never weakly typed: a weak leaf would retrace the program)."""
    return jnp.asarray(x, dtype=jnp.float64)


def _run_one(model, params, ph: Phase, t, ke_tol, n_save: int, n_frames: int = 0, adjoint=None):
    """One phase from its branch's description: integrate, summarize. Returns (PhaseOut, end state)."""
    t1 = t + ph.duration
    ts = jnp.linspace(t, t1, n_save)
    frame_ts = jnp.linspace(t, t1, n_frames) if n_frames else None
    res = solve.run_phase(model, params, ph.drive, ph.y0, t, t1, ts, t + ph.settle_after, ke_tol, solve.MAX_STEPS,
                          frame_ts, adjoint)
    v = res.y.v
    speed = jnp.sqrt(v.x**2 + v.y**2 + v.z**2)
    speed = jnp.where(jnp.isfinite(speed), speed, jnp.inf)
    k_max = jnp.argmax(speed)
    out = PhaseOut(t0=t, t_end=res.t_end, n_steps=res.n_steps, settled=res.settled, blew_up=res.blew_up,
                   ke_end=solve.kinetic_energy(model, res.y), q_end=res.y.q, qd_end=res.y.qd,
                   speed_max=speed.reshape(-1)[k_max], where_max=jnp.stack(jnp.unravel_index(k_max, speed.shape)),
                   saved=res.saved, frames=_with_end_frame(model, params, ph, res))
    return out, res.y


def _with_end_frame(model, params, ph, res):
    """The recorded frames plus the phase's end state (a phase that settles early reaches only
    some of its uniform frame times; its end is always shown)."""
    if res.frames is None:
        return None
    from ..frames import frame_fields

    y = res.y
    nodes, p, energy = frame_fields(model, params, y, jnp.nan, res.t_end, surface=ph.drive.surface)
    end = {"t": res.t_end, "x": jnp.stack([y.x.x, y.x.y, y.x.z], axis=-1), "q": y.q, "nodes": nodes,
           "contact_pressure_Pa": p, "energy_density_J_per_m2": energy}
    return {k: jnp.concatenate([res.frames[k], end[k][None]]) for k in res.frames}


# One compiled program per phase *structure* (surface type, rigid belt, belt loads, samples per phase,
# batch shape, sharding), shared by every phase of every experiment that has it: the flat-road
# experiments (E01, E02, E04, E09-E12) all run through one program, the rigid-belt ones (E05, E07,
# E08) through another. Compiling each experiment as a whole (all its phases inlined into one XLA
# program) costs far more (docs/design-notes.md); shared phases compile a few times in all.
_run_one_counted = eqx.debug.assert_max_traces(_run_one, max_traces=None)
run_one = eqx.filter_jit(_run_one_counted)


def phase_traces() -> int:
    """Times the phase program has been traced in this process (a test proves a grid traces it once)."""
    return eqx.debug.get_num_traces(_run_one_counted)


_N_FRAMES = contextvars.ContextVar("jtire_n_frames", default=0)


@contextlib.contextmanager
def recording_frames(n: int):
    """Within this block every phase also saves whole frames (`PhaseOut.frames`), for `jtire run
    --frames`: at n uniform times over the phase's longest span (those after a settled phase's early
    end are not reached) and at its end. A separate compiled program (n is static)."""
    token = _N_FRAMES.set(int(n))
    try:
        yield
    finally:
        _N_FRAMES.reset(token)


_ADJOINT = contextvars.ContextVar("jtire_adjoint", default=None)


@contextlib.contextmanager
def reverse_mode(checkpoints: int = 1024):
    """Within this block every transient phase is traced for reverse-mode autodiff (jax.grad, jacrev,
    vjp): diffrax's RecursiveCheckpointAdjoint keeps `checkpoints` states of the phase and recomputes
    the steps between them on the way back (treeverse: with c states and n steps each step is run
    about r + 1 times, r the smallest with C(c + r, r) >= n; for the default 1024 states and E12's
    ~20,000 steps, r = 2). Memory: c states (~0.2 MB each at the default mesh). Outside the block the
    phases use forward mode (jvp / jacfwd), which stores nothing. A separate compiled program."""
    import diffrax

    token = _ADJOINT.set(diffrax.RecursiveCheckpointAdjoint(checkpoints=int(checkpoints)))
    try:
        yield
    finally:
        _ADJOINT.reset(token)


def run_plan(model, params, branches, y0, mem0: dict, ke_tol, n_save: int):
    """Run `branches` in order from state y0 at t = 0. Returns (PhaseOut stacked over phases, the
    end state of the last phase, mem).

    branches: list of (y, t, mem) -> (Phase, mem). The branches are plain JAX code, the integration
    of each phase is the shared compiled program `run_one`; the whole plan is traceable (vmap, jvp,
    jit) and, called eagerly under vmap, reuses the compiled phase program for every phase.
    n_save: samples saved per phase (static).
    """
    y, t = y0, f64(0.0)
    mem = {k: f64(v) for k, v in mem0.items()}
    outs = []
    for branch in branches:
        ph, mem = branch(y, t, mem)
        # Tie every input of the phase program to the case (+ 0 dt): under vmap every leaf then carries
        # the batch axis and the batch's sharding. A compiled (vmapped) program is specific to which
        # of its inputs are batched and how they are placed, so without this each experiment (a load
        # that is a case value in one and a table setting in another, a surface that moves in one and
        # not in another) and even each phase of one experiment (the first one's unbatched start
        # state) compiled a program of its own, and sharded batches traced it again per pattern.
        z = 0.0 * ph.drive.dt
        ph = jax.tree_util.tree_map(lambda a: a + z.astype(a.dtype), ph)
        out, y = run_one(model, params, ph, t + z, ke_tol + z, n_save, _N_FRAMES.get(), _ADJOINT.get())
        outs.append(out)
        t = out.t_end
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *outs), y, mem


def run_plan_vmapped(model, params, make_branches, case, y0, mem0: dict, ke_tol, n_save: int):
    """`run_plan` of the branches `make_branches(case)` from state y0, vmapped over a batch of this one
    case: the phase program the transient experiments run with a batch of one (`batch.simulate_batch`),
    so a transient started from a static state (computed unbatched: a vmapped Newton loop runs both
    branches of its conditionals) shares it, and two such cases side by side on two cores do not
    contend as two unbatched programs do (docs/speed.md). Returns what run_plan does, unbatched."""
    one = lambda a: jnp.asarray(a)[None]  # noqa: E731
    out = jax.vmap(lambda c, y: run_plan(model, params, make_branches(c), y, mem0, ke_tol, n_save))(
        jax.tree_util.tree_map(one, case), jax.tree_util.tree_map(one, y0))
    return jax.tree_util.tree_map(lambda a: a[0], out)


# ---- host side -------------------------------------------------------------------------------------
def phase(outs: PhaseOut, i: int) -> PhaseOut:
    """Phase i of stacked (host, numpy) outputs."""
    return jax.tree_util.tree_map(lambda a: a[i], outs)


def last_valid(saved: dict) -> int:
    """Index of the last saved sample of a phase (a phase that settled early leaves inf behind)."""
    ok = np.isfinite(np.asarray(saved["ke"]))
    return int(np.nonzero(ok)[0][-1]) if ok.any() else 0


def check_phase(name: str, out: PhaseOut, model, require_settled: bool = True, where: str = ""):
    """Raise SimulationError when phase `out` (numpy leaves) blew up, or did not settle when it
    had to; the message says which phase, when, and where on the tire."""
    label = f"{where}{name}"
    if bool(out.blew_up) or not np.isfinite(float(out.speed_max)) or not np.isfinite(float(out.ke_end)):
        i, j = (int(v) for v in np.asarray(out.where_max))
        part = PART_NAMES[model.node_part_t[j + 1]]
        raise SimulationError(
            f"{label}: unstable at t = {float(out.t_end):.5f} s: node speed {float(out.speed_max):.3g} m/s "
            f"(limit {solve.V_MAX} m/s) at segment {i}, section node {j + 1} ({part})")
    if require_settled and not bool(out.settled):
        ke = float(out.ke_end)
        raise SimulationError(
            f"{label}: did not settle by t = {float(out.t_end):.4f} s: kinetic energy {ke:.3g} J above "
            f"the tolerance (raise solver.settle_max_s or the settle damping)")


def phase_checks(name: str, out: PhaseOut, model) -> dict:
    """The settled flag, end time, kinetic energy and steps of a phase, for result.json."""
    return {f"{name}_settled": bool(out.settled), f"{name}_t_end_s": float(out.t_end),
            f"{name}_kinetic_energy_J": float(out.ke_end),
            f"{name}_steps": int(out.n_steps)}


# A settled state must also be in equilibrium: the kinetic-energy event can fire at a turning point of
# a still-ringing state (a heavily under-damped settle), so the force balance is checked as well. 1 %:
# the settle tolerance (1e-3 J) leaves residual forces far below it on every experiment measured; a
# failure means the state is not static, whatever the event said.
EQUILIBRIUM_TOL = 0.01


def require_equilibrium(label: str, got: float, want: float, tol: float = EQUILIBRIUM_TOL) -> float:
    """Relative force-balance error |got - want| / |want|; raises SimulationError above `tol`."""
    err = abs(got - want) / abs(want)
    if not err <= tol:
        raise SimulationError(f"{label}: not in equilibrium: {got:.6g} N carried against {want:.6g} N applied "
                              f"({100 * (got - want) / abs(want):+.2f} %, tolerance {100 * tol:g} %)")
    return err


def contact_check(saved, load):
    """(F_z, relative error against the load, F_y) at the last saved sample of a settled phase."""
    i = last_valid(saved)
    f = np.asarray(saved["contact_force"])[i]
    return float(f[2]), abs(float(f[2]) - load) / load, float(f[1])


def run_info(phases) -> dict:
    """Steps, simulated time and step size of a run (host)."""
    n = np.asarray(phases.n_steps)
    return {"steps": int(n.sum()), "simulated_s": float(np.asarray(phases.t_end)[-1]),
            "phase_steps": [int(v) for v in n]}
