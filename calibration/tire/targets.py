"""Calibration targets: which experiment, at which condition, gives which quantity, measured as what.

A target table in a calibration config ([targets.NAME]):

    experiment = "vertical_stiffness"       # a jtire experiment (jtire.experiments.REGISTRY)
    quantity = "deflection_m"               # optional: the experiment's default response below
    condition = { load_kg = 4625.0, pressure_psi = 120.0 }
    table = { stated_load_kN = 50.0 }       # the experiment's own table (validated, SI inside)
    measured_mm = 39.0625                   # measured_<unit> with unit in MEASURED_UNITS, or
    measured_from = "track_linear"          # (rolling resistance) the 120 psi track trend at the load
    why = "..."

The objective is the study's: the sum over targets of |simulated - measured| / measured * 100,
equal weights unless the config gives [objective] weights.
"""

import dataclasses
import math

import numpy as np

from ...config import parse_condition, validate_table
from ...errors import ConfigError

__all__ = ["Target", "parse_targets", "percent_errors", "total_error", "derived_quantity",
           "DEFAULT_QUANTITY", "MEASURED_UNITS"]

# Experiment -> the response a calibration reads from it by default.
DEFAULT_QUANTITY = {"vertical_stiffness": "deflection_m", "lateral_stiffness": "lateral_deflection_m",
                    "rolling_resistance": "rolling_resistance_N", "footprint": "contact_length_m"}
# measured_<unit> keys: unit -> (SI factor, the SI suffix of the quantity it may measure)
MEASURED_UNITS = {"m": (1.0, "_m"), "mm": (1e-3, "_m"), "N": (1.0, "_N"), "kN": (1e3, "_N"),
                  "N_per_m": (1.0, "_N_per_m"), "kN_per_m": (1e3, "_N_per_m"), "": (1.0, "")}
MEASURED_FROM = ("track_linear",)
_KEYS = {"experiment", "quantity", "condition", "table", "measured_from", "why"} | {
    f"measured_{u}" if u else "measured" for u in MEASURED_UNITS}


@dataclasses.dataclass(frozen=True)
class Target:
    """One calibration target, SI.

    name: the config's key (the response name); experiment, quantity: where the number comes
    from; condition: {"load_N", "pressure_Pa"}; table: the experiment's validated table (SI);
    measured: SI value (> 0); unit, unit_factor: the unit it is shown in and SI per that unit;
    source: where the measured number comes from (config value, or the data fit used).
    """

    name: str
    experiment: str
    quantity: str
    condition: dict
    table: dict
    measured: float
    unit: str
    unit_factor: float
    source: str
    why: str = ""

    def as_dict(self) -> dict:
        """For files people read (the fingerprint): the condition in SI with SI names, the table
        under the config's own field names, so in the config's units (max_load_kN: 60.0, not the
        60000.0 N held inside)."""
        return {"name": self.name, "experiment": self.experiment, "quantity": self.quantity,
                "condition": self.condition, "table": _in_file_units(self.experiment, self.table),
                "measured": self.measured, "unit": self.unit, "source": self.source}


def _in_file_units(experiment: str, table: dict) -> dict:
    from ...experiments import REGISTRY

    schema = REGISTRY[experiment].schema
    out = {}
    for k, v in table.items():
        f = schema.get(k)
        if f is not None and f.factor != 1.0 and not isinstance(v, (bool, str)):
            v = [x / f.factor for x in v] if isinstance(v, (tuple, list)) else v / f.factor
        out[k] = v
    return out


def _quantity_suffix(q: str) -> str:
    for s in ("_N_per_m", "_m", "_N"):
        if q.endswith(s):
            return s
    return ""


def _track_linear(load_n: float, data_dir=None) -> tuple:
    """(force N, description) from the 120 psi linear track trend RRC(F_z) at load_n."""
    from ...data import analyze  # the measured tables; loaded only when a config asks for them

    fit = analyze(data_dir).fits["track_120psi"].linear
    rrc = float(fit.predict(load_n).mean[0])
    return rrc * load_n, (f"jtire data: track_120psi linear fit, RRC {rrc:.5f} at "
                          f"{load_n / 1e3:g} kN (RRC = {fit.a:.5g} + {fit.b:.5g} Fz_N)")


def parse_targets(raw, data_dir=None, where: str = "targets") -> tuple:
    """[targets.*] (or [checks.*], where="checks") -> tuple of Target, in config order."""
    from ...experiments import REGISTRY  # the experiments and their table schemas

    if not isinstance(raw, dict) or not raw:
        raise ConfigError(f"{where}: missing; give one table [{where}.NAME] per measured response")
    out = []
    for name, t in raw.items():
        at = f"{where}.{name}"
        if not isinstance(t, dict):
            raise ConfigError(f"{at}: must be a table")
        for key in t:
            if key not in _KEYS:
                raise ConfigError(f"{at}.{key}: unknown field (allowed: {', '.join(sorted(_KEYS))})")
        exp = t.get("experiment")
        if exp not in REGISTRY:
            raise ConfigError(f"{at}.experiment = {exp!r}: no such experiment (known: "
                              f"{', '.join(REGISTRY)})")
        quantity = t.get("quantity", DEFAULT_QUANTITY.get(exp))
        if not isinstance(quantity, str):
            raise ConfigError(f"{at}.quantity: missing (the result quantity of {exp} to match, "
                              "e.g. deflection_m)")
        condition = parse_condition(t.get("condition", {}), need_load=REGISTRY[exp].needs_load)
        if not isinstance(t.get("table", {}), dict):
            raise ConfigError(f"{at}.table: must be a table (the fields of [{exp}])")
        table = validate_table(t.get("table", {}), REGISTRY[exp].schema, f"{at}.table")
        produced = REGISTRY[exp].produces(table)
        if quantity not in produced:  # a typo would otherwise end the first simulation in a KeyError
            raise ConfigError(f"{at}.quantity = {quantity!r}: not a quantity {exp} produces (allowed: "
                              f"{', '.join(produced)})")
        given = [k for k in t if k.startswith("measured")]
        if len(given) != 1:
            raise ConfigError(f"{at}: give exactly one of measured_<unit> (unit in "
                              f"{', '.join(u for u in MEASURED_UNITS if u)}) or measured_from "
                              f"(got {len(given)})")
        key = given[0]
        if key == "measured_from":
            src = t[key]
            if src not in MEASURED_FROM or _quantity_suffix(quantity) != "_N" or "load_N" not in condition:
                raise ConfigError(f"{at}.measured_from = {src!r}: allowed {MEASURED_FROM} for a "
                                  "force quantity at a stated load")
            measured, source = _track_linear(condition["load_N"], data_dir)
            unit, factor = "N", 1.0
        else:
            unit = key[len("measured_"):] if key != "measured" else ""
            factor, suffix = MEASURED_UNITS[unit]
            if suffix != _quantity_suffix(quantity):
                raise ConfigError(f"{at}.{key}: unit does not fit quantity {quantity!r}")
            v = t[key]
            if not (isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                    and v > 0):
                raise ConfigError(f"{at}.{key} = {v!r}: must be a number > 0 (percentage errors "
                                  "are taken relative to it)")
            measured, source = float(v) * factor, "config"
        why = t.get("why", "")
        out.append(Target(name, exp, quantity, condition, table, measured, unit, factor, source,
                          why if isinstance(why, str) else ""))
    return tuple(out)


def percent_errors(values, targets) -> np.ndarray:
    """|simulated - measured| / measured * 100, values (..., m) -> (..., m); nan stays nan."""
    meas = np.array([t.measured for t in targets])
    return np.abs(np.asarray(values, float) - meas) / meas * 100.0


def total_error(values, targets, weights=None) -> np.ndarray:
    """The study's objective: sum of the (weighted) percentage errors, (..., m) -> (...)."""
    w = np.ones(len(targets)) if weights is None else np.asarray(weights, float)
    return np.sum(percent_errors(values, targets) * w, axis=-1)


def derived_quantity(target: Target, value):
    """What an engineer reads off a target's response: (label, value(s), unit).

    Static deflections become stiffnesses (applied force / deflection: k_sv at the stated load,
    k_l at the lateral force), rolling-resistance forces an RRC (force / vertical load).
    Other responses are returned as they are, in the target's unit.
    """
    v = np.asarray(value, float)
    if target.experiment == "vertical_stiffness" and target.quantity == "deflection_m":
        force = target.table.get("stated_load_kN") or target.condition["load_N"]
        return "k_sv", force / v / 1e3, "kN/m"
    if target.experiment == "lateral_stiffness" and target.quantity == "lateral_deflection_m":
        return "k_l", target.table["force_kN"] / v / 1e3, "kN/m"
    if target.experiment == "rolling_resistance" and target.quantity == "rolling_resistance_N":
        return f"RRC at {target.condition['load_N'] / 1e3:g} kN", v / target.condition["load_N"], ""
    return target.name, v / target.unit_factor, target.unit
