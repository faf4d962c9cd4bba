"""Static vertical load paths (E01, E02): the tire inflated, put on the road and pressed down by a
sequence of vertical rim loads, each level a static equilibrium (`jtire.equilibrium`).

A static quantity has no rate: these solves use the long-term moduli (no viscoelastic lag, nothing
to tune), each level is converged to a stated force residual (checked on the host: a level that did
not converge is an error naming it), and derivatives come from the implicit function theorem.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import equilibrium as EQ


N_LATERAL = 2  # lateral levels at the end of every static path (E09: F/2, F; E01, E02: zero force)


def _static_vertical_path(model, params, pressure, loads, lateral):
    """Inflation, first contact, static equilibrium under each vertical rim load of `loads` (N,
    ascending), then N_LATERAL lateral rim forces `lateral` (N, +y) at the last vertical load with
    rim y and z free. Levels: 0 inflated, 1 the touch (rim held 1 mm into the road), 2.. the loads,
    then the lateral forces. Returns arrays per vertical level (q, rim_force, contact, road_height,
    infos), the inflated state y_inflated, the state y after the last vertical load, and the lateral
    levels' q, contact, infos and end state (lateral_*)."""
    path = EQ.static_path(model, params, pressure, EQ.vertical_levels(pressure, loads),
                          EQ.lateral_levels(pressure, loads[-1], lateral))
    n = loads.shape[0] + 2
    vert = jax.tree_util.tree_map(lambda a: a[:n], path)
    lat = jax.tree_util.tree_map(lambda a: a[n:], path)
    last = lambda ys: jax.tree_util.tree_map(lambda a: a[-1], ys)  # noqa: E731
    return {"loads": loads, "q": vert.q, "rim_force": vert.rim_force, "contact": vert.contact,
            "road_height": vert.road_height, "infos": vert.infos, "y": last(vert.ys),
            "y_inflated": jax.tree_util.tree_map(lambda a: a[0], vert.ys),
            "lateral": lateral, "lateral_q": lat.q, "lateral_contact": lat.contact, "lateral_infos": lat.infos,
            "y_lateral": last(lat.ys)}


# One compiled program per number of load levels (and batch shape), shared by E01, E02 and E09's
# static part when their level counts agree (the defaults do: 13 vertical loads, then 2 lateral
# levels, at zero force for E01 and E02: a converged state re-solved, no Newton step): a Newton
# solver is long to compile, and to trace again in a new process (docs/design-notes.md).
_static_path_jit = eqx.filter_jit(_static_vertical_path)
STATIC_LOADS = 13  # E02's default: 12 levels to max_load + the stated load; E01 and E09 use as many


def static_vertical_path(model, params, pressure, loads, lateral=None):
    """`_static_vertical_path`, compiled; lateral: (N_LATERAL,) N, default zero (E01, E02)."""
    lateral = jnp.zeros(N_LATERAL, dtype=jnp.float64) if lateral is None else jnp.asarray(lateral, dtype=jnp.float64)
    return _static_path_jit(model, params, pressure, loads, lateral)


def static_summary(*infos, method="static"):
    """(checks, info) of one or more solved level sequences (StaticInfo, host arrays): converged at
    every level, the largest residual relative to the load scale, and the solver's work; the keys
    named after `method` (the steady-rolling levels share the solver and its infos)."""
    arr = lambda f: np.concatenate([np.atleast_1d(np.asarray(getattr(i, f))) for i in infos])  # noqa: E731
    checks = {f"{method}_converged": bool(np.all(arr("converged"))),
              f"{method}_residual_max_rel": float(np.max(arr("residual_max") / arr("load_scale")))}
    info = {"method": method, "newton_iterations": int(arr("iterations").sum()),
            "factorizations": int(arr("factorizations").sum()), "krylov_iterations": int(arr("krylov").sum())}
    return checks, info


def check_static_path(name, out):
    """Raise SimulationError naming the level of a static vertical path that did not converge."""
    loads = np.asarray(out["loads"])
    EQ.check_static(out["infos"], lambda k: f"{name}: inflation" if k == 0 else f"{name}: first contact" if k == 1
                 else f"{name}: load level {loads[k - 2] / 1e3:.4g} kN")
