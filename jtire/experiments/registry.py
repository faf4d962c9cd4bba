"""Name -> experiment: the schema of its own config table and the function that runs it.

Each runner takes (tire, condition, protocol, **table) with SI values and returns an
ExperimentResult. Dynamic experiments register here too, so `jtire run` needs no changes.
"""

import dataclasses
from typing import Callable

from .. import units as U
from ..config import F
from . import static


@dataclasses.dataclass(frozen=True)
class Experiment:
    name: str
    runner: Callable
    schema: dict  # field -> F, for the experiment's table
    needs_load: bool = True
    description: str = ""


def _vertical(tire, condition, proto, max_load_kN, stated_load_kN, ramp_s, fit_range_kN):
    stated = condition["load_N"] if stated_load_kN <= 0 else stated_load_kN
    if not 0 < stated <= max_load_kN:
        from ..errors import ConfigError

        raise ConfigError(f"vertical_stiffness.stated_load_kN = {stated / 1e3:g}: must be in (0, max_load_kN = {max_load_kN / 1e3:g}]")
    return static.run_vertical_stiffness(tire, condition, proto, max_load_kN, stated, ramp_s, fit_range_kN)


REGISTRY = {
    "footprint": Experiment("footprint", lambda tire, c, p: static.run_footprint(tire, c, p), {},
                            description="E01 contact patch length and width"),
    "vertical_stiffness": Experiment(
        "vertical_stiffness", _vertical,
        {"max_load_kN": F(float, U.KN, 1, 500, 60.0, "kN"),
         "stated_load_kN": F(float, U.KN, 0, 500, 0.0, "kN (0: the condition's load)"),
         "ramp_s": F(float, 1, 0.02, 5, 0.9, "s"),  # 0.3 s read 4.8 % stiff at 45 kN (viscoelastic lag), 0.9 s 1.0 %
         "fit_range_kN": F(list, U.KN, 0, 500, [10.0, 60.0], "kN")},
        description="E02 total static vertical stiffness k_sv"),
    "lateral_stiffness": Experiment(
        "lateral_stiffness",
        lambda tire, c, p, force_kN, decay_s, release_ramp_ms, mass_kg: static.run_lateral_stiffness(
            tire, c, p, force_kN, decay_s, release_ramp_ms, mass_kg),
        {"force_kN": F(float, U.KN, 0.01, 100, 5.0, "kN"),
         "decay_s": F(float, 1, 0, 3, 0.3, "s of free decay after the release (0: static part only)"),
         "release_ramp_ms": F(float, U.MS, 0, 20, 1.0, "ms (0: a step)"),
         "mass_kg": F(float, 1, 0, 1e4, 111.25, "kg, m_wheel for C_l (0: the model's wheel mass)")},
        description="E09 lateral stiffness k_l and damping C_l (release decay)"),
}


def register(exp: Experiment):
    REGISTRY[exp.name] = exp


def _load_plugins():
    """Experiment modules register themselves on import; missing ones are simply not offered."""
    import importlib

    for mod in ("sidewall", "drop", "rolling", "cornering", "drum_cleat", "traction"):
        name = f"jtire.experiments.{mod}"
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as e:
            if e.name != name:
                raise


_load_plugins()
