"""E14 longitudinal tire stiffness C_x at standstill (jtire's addition; MF-Swift's LONGITUDINAL_STIFFNESS):
the static load path of E01 (`static_path`: inflation, first contact, STATIC_LOADS vertical levels to the
load), then a fore-aft rim force in two static levels (F/2, F) with rim x and z free, its spin held and
the patch held by friction carried from level to level: C_x = F / x, on the long-term moduli. Checks:
the road carries the load and the fore-aft force; C_x at F/2 over C_x at F says how linear the push is.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import equilibrium as EQ
from .. import units as U
from ..schema import Field
from .base import Experiment
from .program import f64, require_equilibrium
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary

def _fore_aft_path(model, params, pressure, loads, forces):
    """E01's vertical levels to loads[-1], then the fore-aft rim forces `forces` (N, +x) at that load.
    Returns the last vertical level's q, the fore-aft levels' q and contact force, and every info."""
    path = EQ.static_path(model, params, pressure, EQ.vertical_levels(pressure, loads),
                          EQ.fore_aft_levels(pressure, loads[-1], forces))
    m = loads.shape[0] + 2
    vert = jax.tree_util.tree_map(lambda a: a[:m], path)
    fa = jax.tree_util.tree_map(lambda a: a[m:], path)
    return {"loads": loads, "q": vert.q, "contact": vert.contact, "infos": vert.infos, "forces": forces,
            "fore_aft_q": fa.q, "fore_aft_contact": fa.contact, "fore_aft_infos": fa.infos}


_fore_aft_path_jit = eqx.filter_jit(_fore_aft_path)


class LongitudinalStiffness(Experiment):
    name = "longitudinal_stiffness"
    study_id = "E14"
    description = "E14 longitudinal (fore-aft) stiffness C_x at standstill"
    schema = {"force_kN": Field(float, U.KN, 0.01, 100, 2.0, "kN (the push's second level; the first is half)"),
              "direction": Field(str, default="forward", choices=("forward", "backward"))}
    traced_names = ("C_x_N_per_m", "longitudinal_deflection_m")
    quantity_names = ("C_x_N_per_m", "longitudinal_deflection_m", "longitudinal_force_N", "C_x_half_over_full")

    force: jax.Array  # N, > 0
    sign: float = eqx.field(static=True, default=1.0)  # +1 forward (+x), -1 backward
    # static levels only: with it, `time_stepped` and `shardable` say no explicit step and an unbatched run
    method: str = eqx.field(static=True, default="static")

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        return cls(proto=proto, force=f64(table["force_kN"]), sign=1.0 if table["direction"] == "forward" else -1.0)

    def simulate(self, model, params, case):
        loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
        levels = self.sign * self.force * jnp.array([0.5, 1.0])
        return {"static": _fore_aft_path_jit(model, params, case.pressure, loads, levels)}

    def traced(self, model, params, condition_cases, outputs):
        st = outputs[0]["static"]
        x = jnp.abs(st["fore_aft_q"][-1, 0] - st["q"][-1, 0])
        return {"C_x_N_per_m": self.force / x, "longitudinal_deflection_m": x}

    def reduce(self, tire, condition, outputs):
        st = outputs[0]["static"]
        load, force = condition["load_N"], float(self.force)
        check_static_path("longitudinal_stiffness", st)
        forces = np.abs(np.asarray(st["forces"]))
        EQ.check_static(st["fore_aft_infos"],
                        lambda k: f"longitudinal_stiffness: fore-aft level {forces[k] / 1e3:.4g} kN")
        fz = float(np.asarray(st["contact"])[-1, 2])
        require_equilibrium("longitudinal_stiffness: vertical load", fz, load)
        f_c = np.asarray(st["fore_aft_contact"])
        for k, fk in enumerate(forces):  # the patch carries each fore-aft level (friction holds it)
            require_equilibrium(f"longitudinal_stiffness: fore-aft level {fk / 1e3:.4g} kN", abs(float(f_c[k, 0])), fk)
        x = np.abs(np.asarray(st["fore_aft_q"])[:, 0] - np.asarray(st["q"])[-1, 0])
        checks, info = static_summary(st["infos"], st["fore_aft_infos"])
        checks |= {"contact_force_N": fz, "contact_vs_load_rel_error": abs(fz - load) / load,
                   "contact_fore_aft_force_N": float(f_c[-1, 0]),
                   "contact_vs_fore_aft_rel_error": abs(abs(float(f_c[-1, 0])) - force) / force}
        q = {"C_x_N_per_m": force / x[-1], "longitudinal_deflection_m": float(x[-1]), "longitudinal_force_N": force,
             "C_x_half_over_full": float((forces[0] / x[0]) / (force / x[-1]))}
        sig = {"longitudinal_force_N": forces, "rim_x_m": x}
        info |= {"levels": int(len(np.asarray(st["loads"])) + 2 + len(forces)),
                 "direction": "forward" if self.sign > 0 else "backward"}
        return ExperimentResult(self.name, condition, q, signals=sig, checks=checks, info=info)
