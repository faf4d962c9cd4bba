"""Static vertical load paths (E01, E02): the tire inflated, put on the road and pressed down by a
sequence of vertical rim loads, each level a static equilibrium (`jtire.equilibrium`).

A static quantity has no rate: these solves use the long-term moduli (no viscoelastic lag, nothing
to tune), each level is converged to a stated force residual (checked on the host: a level that did
not converge is an error naming it), and derivatives come from the implicit function theorem.
"""

import equinox as eqx
import jax
import numpy as np

from .. import equilibrium as EQ


def _static_vertical_path(model, params, pressure, loads):
    """Inflation, first contact, then static equilibrium under each vertical rim load of `loads`
    (N, ascending). Levels: 0 inflated, 1 the touch (rim held 1 mm into the road), 2.. the loads.
    Returns arrays per level (q, rim_force, contact, road_height, infos) and the last state y."""
    path = EQ.static_path(model, params, pressure, EQ.vertical_levels(pressure, loads))
    y = jax.tree_util.tree_map(lambda a: a[-1], path.ys)
    return {"loads": loads, "q": path.q, "rim_force": path.rim_force, "contact": path.contact,
            "road_height": path.road_height, "infos": path.infos, "y": y}


# One compiled program per number of load levels (and batch shape), shared by E01 and E02 when their
# level counts agree (the defaults do: 13 loads): a Newton solver costs ~60 s of compilation here.
static_vertical_path = eqx.filter_jit(_static_vertical_path)
STATIC_LOADS = 13  # E02's default: 12 levels to max_load + the stated load; E01 uses as many


def check_static_path(name, out):
    """Raise SimulationError naming the level of a static vertical path that did not converge."""
    loads = np.asarray(out["loads"])
    EQ.check_static(out["infos"], lambda k: f"{name}: inflation" if k == 0 else f"{name}: first contact" if k == 1
                 else f"{name}: load level {loads[k - 2] / 1e3:.4g} kN")
