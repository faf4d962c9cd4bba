"""Static equilibrium solves for the static experiments (inflation, loads on a road, belt holds).

    from jtire import equilibrium as eq
    path = eq.static_path(model, params, p, eq.vertical_levels(p, loads))   # E01 / E02
    eq.check_static(path.infos, lambda k: f"E02 level {k}")                 # on the host

`residual` (the static force balance, friction anchors), `linalg` (block-banded Jacobian and its
solve), `newton` (the solver, tolerance, implicit derivatives), `sequences` (load paths).
"""

from .newton import NewtonOptions, StaticInfo, check_static, solve_static, solve_static_full
from .residual import Anchors, StaticSetup, make_setup
from .sequences import (Levels, Path, anchors_of, belt_levels, concat, contact_force, first_contact_height,
                        fore_aft_levels, inflate_levels, lateral_levels, run_levels, static_path, tire_on_rim,
                        vertical_levels)

__all__ = ["Anchors", "StaticSetup", "make_setup", "solve_static", "solve_static_full", "check_static", "NewtonOptions", "StaticInfo", "Levels",
           "Path", "run_levels", "static_path", "inflate_levels", "vertical_levels", "lateral_levels", "belt_levels",
           "fore_aft_levels",
           "concat", "anchors_of", "first_contact_height", "contact_force", "tire_on_rim"]
