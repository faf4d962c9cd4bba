"""E01 footprint: contact patch length 2a and width w under the condition's load on a flat road.

Method "static" (default): inflation, first contact and the load applied in STATIC_LOADS equal
static levels (`static_path`: static equilibrium, long-term moduli, friction carried from level to
level; one compiled program shared with E02). Method "transient": inflate (rim held) -> the road
placed at the first contact height -> the load ramped onto the rim (z free) and settled. Reduction: the patch extent of the settled state (`patch`), the rim
deflection, and the checks that the road carries the load and no lateral force (a mirror-symmetric
tire). Internal ISO axes (z up); lengths and deflections are reported as positive magnitudes.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .. import solve
from ..errors import SimulationError
from . import patch
from ..schema import Field
from .base import Experiment
from .phases import loaded_plan
from .program import check_phase, contact_check, phase, phase_checks, require_equilibrium, run_info
from .result import ExperimentResult
from .static_path import STATIC_LOADS, check_static_path, static_summary, static_vertical_path


class Footprint(Experiment):
    name = "footprint"
    study_id = "E01"
    description = "E01 contact patch length and width"
    schema = {"method": Field(str, default="static", choices=("static", "transient"))}
    traced_names = ("contact_length_m", "contact_width_m", "deflection_m")
    quantity_names = ("contact_length_m", "contact_width_m", "contact_half_length_m", "contact_area_m2",
                      "deflection_m", "k_secant_N_per_m", "geometric_chord_m", "measured_contact_length_m",
                      "measured_contact_width_m")

    method: str = eqx.field(static=True, default="static")
    n_save: int = eqx.field(static=True, default=solve.N_SAVE)

    @classmethod
    def from_table(cls, table, proto, tire_spec):
        return cls(proto=proto, method=table["method"])

    def simulate(self, model, params, case):
        if self.method == "static":
            loads = case.load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
            out = static_vertical_path(model, params, case.pressure, loads)
            return {"static": out, "y": out["y"], "z_road": out["road_height"][-1]}
        outs, y, mem = loaded_plan(model, params, case, self.proto, case.load, self.n_save)
        return {"phases": outs, "y": y, "z_road": mem["z_road"]}

    def traced(self, model, params, condition_cases, outputs):
        out = outputs[0]
        length, width = patch.extent_traced(model, out["y"], patch.flat_gap(out["z_road"]))
        return {"contact_length_m": length, "contact_width_m": width, "deflection_m": -out["y"].q[2]}

    def reduce(self, tire, condition, outputs):
        out = outputs[0]
        model, load = tire.model, condition["load_N"]
        if self.method == "static":
            st = out["static"]
            check_static_path("footprint", st)
            fz, fy = float(np.asarray(st["contact"])[-1, 2]), float(np.asarray(st["contact"])[-1, 1])
            err = abs(fz - load) / load
            checks, info = static_summary(st["infos"])
            info["levels"] = int(len(np.asarray(st["loads"])) + 2)
        else:
            inf, ld = phase(out["phases"], 0), phase(out["phases"], 1)
            check_phase("inflate", inf, model)
            check_phase("load", ld, model)
            checks = phase_checks("inflate", inf, model) | phase_checks("load", ld, model)
            fz, err, fy = contact_check(ld.saved, load)
            info = run_info(out["phases"])
        require_equilibrium("footprint: load phase", fz, load)
        z_road = float(out["z_road"])
        length, width, area = patch.extent(model, out["y"], patch.flat_gap(z_road))
        deflection = -float(out["y"].q[2])
        checks |= {"contact_force_N": fz, "contact_vs_load_rel_error": err, "contact_lateral_force_N": fy}
        if length <= 0 or width <= 0:
            raise SimulationError(f"footprint: no contact patch (length {length:.3g} m, width {width:.3g} m) "
                                  f"while the road carries {fz:.4g} N: degenerate tire geometry")
        R = tire.spec.geometry.outer_radius
        ref = tire.spec.reference
        q = {"contact_length_m": length, "contact_width_m": width, "contact_half_length_m": length / 2,
             "contact_area_m2": area, "deflection_m": deflection, "k_secant_N_per_m": load / deflection,
             "geometric_chord_m": 2 * np.sqrt(max(R**2 - (R - deflection) ** 2, 0.0)),
             "measured_contact_length_m": ref["footprint_length_mm"] or None,
             "measured_contact_width_m": ref["footprint_width_mm"] or None}
        return ExperimentResult(self.name, condition, q, checks=checks, info=info)
