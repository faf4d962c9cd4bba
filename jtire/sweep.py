"""Sweeps over conditions (load x pressure), vmapped: every case runs in one batched program.

The static experiments (E01 footprint, E02 vertical stiffness, E09 lateral stiffness) run as a
batch: each phase of the sequence (inflate, load, lateral) is one `jax.vmap` of the phase solver
over the cases, compiled once for the batch size, then every case is reduced on the host with the
same reduction as a single run. All cases share one step, the smallest stable step of the grid.
(On a CPU a batch costs about what the cases cost one after another, physics notes: vmap is for
one compilation and for accelerators, not for CPU speed.)
"""

import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import solve
from .experiments import phases, static
from .experiments.result import ExperimentResult
from .state import TireState

VMAPPED = ("footprint", "vertical_stiffness", "lateral_stiffness")
TRACES = 0  # times `batched_phase` has been traced (a test checks a sweep traces it once)


def stack(trees):
    """Stack a list of equal-structure pytrees along a new leading axis."""
    return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *trees)


def index(tree, i):
    return jax.tree_util.tree_map(lambda a: a[i] if eqx.is_array(a) else a, tree)


@eqx.filter_jit
def batched_phase(model, params, drive, y0, t0, t1, ts, settle_after, ke_tol, max_steps: int):
    """solve.run_phase over a batch: drive, y0, t0, t1, ts, settle_after carry a leading case axis."""
    global TRACES
    TRACES += 1  # runs at trace time only
    def one(d, y, a, b, c, s):
        return solve.run_phase(model, params, d, y, a, b, c, s, ke_tol, max_steps)

    return jax.vmap(one)(drive, y0, t0, t1, ts, settle_after)


def _ts(t0, t1):
    """Save times per case; t1 is the very array passed as the phase end (no rounding mismatch)."""
    return jnp.stack([jnp.linspace(a, b, solve.N_SAVE) for a, b in zip(jnp.asarray(t0), jnp.asarray(t1))])


def run_static_batch(tire, conditions, proto, experiment, table):
    """Run one static experiment for every condition in a single vmapped batch.

    conditions: list of {"pressure_Pa", "load_N"}; table: the experiment's validated config table.
    Returns a list of ExperimentResults, one per condition, in order.
    """
    if experiment not in VMAPPED:
        raise ValueError(f"{experiment}: not a vmapped sweep experiment ({', '.join(VMAPPED)})")
    model, params = tire.model, tire.params
    n = len(conditions)
    ps = np.array([c["pressure_Pa"] for c in conditions])
    loads = np.array([c["load_N"] for c in conditions])
    c_settle = float(proto.settle_damping)
    dt = min(solve.stable_step(model, params, p, c_settle) for p in np.unique(ps))
    ramp = float(table.get("ramp_s", proto.load_ramp))
    hold = float(proto.settle_max)
    target = np.full(n, table["max_load_kN"]) if experiment == "vertical_stiffness" else loads
    ms = solve.MAX_STEPS
    t_start = time.perf_counter()

    drives = stack([phases.make_drive(p, dt, proto, pressure0=0.0, t0=0.0, t1=proto.inflate_ramp,
                                      surface=phases.far_road()) for p in ps])
    y0 = stack([TireState.at_rest(model, len(params.relaxation_times))] * n)
    zeros = jnp.zeros(n)
    t_inf = jnp.full(n, proto.inflate_max)
    inf = batched_phase(model, params, drives, y0, zeros, t_inf, _ts(zeros, t_inf), jnp.full(n, proto.inflate_ramp),
                        proto.ke_tol, ms)
    z0 = jax.vmap(lambda y: phases.first_contact_height(model, y))(inf.y)
    t1 = np.asarray(inf.t_end)
    drives = stack([phases.make_drive(ps[i], dt, proto, force1=target[i] * static.DOWN, t0=t1[i], t1=t1[i] + ramp,
                                      rim_free=phases.RIM_Z, surface=phases.flat_road(z0[i])) for i in range(n)])
    t_ld = jnp.asarray(t1 + ramp + hold)
    ld = batched_phase(model, params, drives, inf.y, jnp.asarray(t1), t_ld, _ts(t1, t_ld), jnp.asarray(t1 + ramp),
                       proto.ke_tol, ms)
    lat = None
    if experiment == "lateral_stiffness":
        t2 = np.asarray(ld.t_end)
        F = table["force_kN"]
        lr = float(proto.load_ramp)
        drives = stack([phases.make_drive(ps[i], dt, proto, force0=loads[i] * static.DOWN,
                                          force1=loads[i] * static.DOWN + F * static.LEFT, t0=t2[i], t1=t2[i] + lr,
                                          rim_free=phases.RIM_YZ, surface=phases.flat_road(z0[i])) for i in range(n)])
        t_lat = jnp.asarray(t2 + lr + hold)
        lat = batched_phase(model, params, drives, ld.y, jnp.asarray(t2), t_lat, _ts(t2, t_lat), jnp.asarray(t2 + lr),
                            proto.ke_tol, ms)
    jax.block_until_ready((inf, ld, lat))
    wall = (time.perf_counter() - t_start) / n

    out = []
    for i, cond in enumerate(conditions):
        inf_i, ld_i = index(inf, i), index(ld, i)
        if experiment == "footprint":
            res = static.reduce_footprint(tire, cond, inf_i, float(z0[i]), ld_i, dt, wall)
        elif experiment == "vertical_stiffness":
            stated = cond["load_N"] if table["stated_load_kN"] <= 0 else table["stated_load_kN"]
            res = static.reduce_vertical(tire, cond, proto, inf_i, ld_i, table["max_load_kN"], stated,
                                         ramp, table["fit_range_kN"], dt, wall)
        else:
            lat_i = index(lat, i)
            checks = {}
            for name, r in (("inflate", inf_i), ("load", ld_i), ("lateral", lat_i)):
                solve.check_phase(name, r, model)
                checks[f"{name}_settled"] = bool(r.settled)
            y_ss = abs(float(lat_i.y.q[1] - ld_i.y.q[1]))
            q = {"k_l_N_per_m": F / y_ss, "lateral_deflection_m": y_ss, "lateral_force_N": F}
            res = ExperimentResult("lateral_stiffness", cond, q, checks=checks,
                                   info={"dt_s": dt, "wall_s_per_case_including_compile": wall})
        res.info["sweep"] = "vmapped batch"
        out.append(res)
    return out
