"""Calibration configs (configs/calibration/*.toml) -> a validated `CalibrationSpec`.

Layout (every field checked; a bad one is a ConfigError naming it, one line):

    tire_file = "../tires/xone_xda.toml"     # relative to this config
    description = "..."
    method = "arsm"                          # or "lm" (the gradient route)
    [targets.NAME] ...                       # calibration.targets
    [checks.NAME] ...                        # optional: measured responses in the same form, not
                                             # fitted: simulated once at the calibrated point and
                                             # reported beside the targets (e.g. the footprint)
    [[free]] name = ..., factor|bounds = [lo, hi], why = "..."   # calibration.tire.space
    [objective] weights = { NAME = 1.0 }     # optional; equal weights by default
    [arsm] budget, seed, batch_size, n_initial, surface, region_rule, fill, weighting,
           min_width, min_shrink, initial_width, tol_percent
    [gradient] max_iterations, forward_budget, lambda0, tol_percent, min_step
    [sensitivity] quantities = [...]         # default: the target responses
    [anchor.NAME] simulated = ..., error_percent = ...   # the study's Table 4-4, shown beside ours
    extends = "study.toml"                   # optional: another config's fields, this file's on top
    tire_overrides = ["mesh.n_theta=32"]     # optional: set on the tire file, as --set tire.mesh.n_theta=32
    free_only = ["tread.G", ...]             # optional: keep only these of the [[free]] entries

`--set` overrides apply to this file; `--set tire.<table>.<key>=...` to the tire file.
"""

import dataclasses
import math
from pathlib import Path

from ...schema import Field as F
from ...config import apply_overrides, load_toml, read_tire_file, validate_table
from ...errors import ConfigError
from .arsm_multi import DEFAULT_SURFACE, FILLS, RULES, WEIGHTINGS
from .response_surfaces import KINDS
from .space import ParamSpace
from .targets import parse_targets

__all__ = ["CalibrationSpec", "load_calibration", "ARSM_SCHEMA", "GRADIENT_SCHEMA", "METHODS"]

METHODS = ("arsm", "lm")
TOP_KEYS = {"tire_file", "description", "method", "targets", "checks", "free", "objective", "arsm",
            "gradient", "sensitivity", "anchor"}
ARSM_SCHEMA = {
    "budget": F(int, 1, 2, 100000, 45, "evaluations"),
    "seed": F(int, 1, 0, 2**31 - 1, 0),
    "batch_size": F(int, 1, 1, 10000, 4, "points per iteration"),
    "n_initial": F(int, 1, 0, 100000, 0, "points (0: d + 2)"),
    "surface": F(str, default=DEFAULT_SURFACE),
    "region_rule": F(str, default="arsm"),
    "fill": F(str, default="local"),
    "weighting": F(str, default="distance"),
    "min_width": F(float, 1, 1e-6, 1, 1e-3, "(unit box)"),
    "min_shrink": F(float, 1, 0.05, 1, 0.5),
    "initial_width": F(float, 1, 0.01, 1, 1.0, "(unit box)"),
    "tol_percent": F(float, 1, 0, 1e4, 0.0, "% total error"),
}
GRADIENT_SCHEMA = {
    "max_iterations": F(int, 1, 1, 100000, 30),
    "forward_budget": F(float, 1, 1, 1e9, 2000.0, "forward-run equivalents"),
    "lambda0": F(float, 1, 1e-12, 1e6, 1e-2),
    "tol_percent": F(float, 1, 0, 1e4, 0.01, "% total error"),
    "min_step": F(float, 1, 0, 1, 1e-8, "(unit box)"),
}


@dataclasses.dataclass(frozen=True)
class CalibrationSpec:
    """A validated calibration config (SI inside).

    path: the config file; raw: the config dict after overrides (for the fingerprint);
    tire_path, tire_raw, tire: the tire file, its dict after overrides, its TireSpec;
    base_params: MaterialParams of the tire; space: ParamSpace; targets: tuple of Target;
    weights: (m,) objective weights; method: "arsm" or "lm"; arsm, gradient: option dicts;
    sensitivity_quantities: names; anchor: {target: {"simulated", "error_percent"}} or {};
    checks: tuple of Target reported at the calibrated point, not fitted.
    """

    path: Path
    raw: dict
    tire_path: Path
    tire_raw: dict
    tire: object
    base_params: object
    space: ParamSpace
    targets: tuple
    weights: tuple
    method: str
    arsm: dict
    gradient: dict
    sensitivity_quantities: tuple
    anchor: dict
    description: str = ""
    checks: tuple = ()

    @property
    def response_names(self) -> tuple:
        return tuple(t.name for t in self.targets)

    def fingerprint(self, simulator=None) -> dict:
        """Everything that determines a calibration's numbers (budget excluded: it may grow)."""
        from ...fingerprint import code_version

        opts = {"arsm": {k: v for k, v in self.arsm.items() if k != "budget"},
                "gradient": {k: v for k, v in self.gradient.items()
                             if k not in ("max_iterations", "forward_budget")}}
        return {"method": self.method, "options": opts[self.method if self.method == "arsm"
                                                       else "gradient"],
                "targets": [t.as_dict() for t in self.targets], "weights": list(self.weights),
                "space": self.space.as_dict(), "tire": self.tire_raw,
                "simulator": None if simulator is None else simulator.fingerprint(),
                "jtire_version": code_version()}


def _is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _with_base(path: Path) -> dict:
    """A calibration config with its `extends = "BASE.toml"` merged in (one level): the base's fields, each table
    updated key by key with this file's, every other field (a list such as `free`, a value) replaced; the base's
    tire_file stays relative to the base."""
    raw = load_toml(path)
    if "extends" not in raw:
        return raw
    name = raw.pop("extends")
    if not isinstance(name, str):
        raise ConfigError("extends: must be the path of a calibration config, relative to this file")
    base_path = (path.parent / name).resolve()
    base = load_toml(base_path)
    if "extends" in base:
        raise ConfigError(f"extends = {name!r}: that config extends another; one level only")
    if isinstance(base.get("tire_file"), str):
        base["tire_file"] = str((base_path.parent / base["tire_file"]).resolve())
    for key, value in raw.items():
        both = isinstance(value, dict) and isinstance(base.get(key), dict)
        base[key] = {**base[key], **value} if both else value
    return base


def _string_list(value, field: str) -> list:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ConfigError(f"{field}: must be a list of strings")
    return list(value)


def load_calibration(path, overrides=(), data_dir=None, tire_path=None) -> CalibrationSpec:
    """Read and validate a calibration config (+ `--set` overrides). tire_path: a tire TOML to use
    instead of the config's tire_file (e.g. a calibrated tire to check against the targets)."""
    from ...tire import params_from_spec

    path = Path(path)
    raw = _with_base(path)
    overrides = list(overrides or ())
    apply_overrides(raw, [o for o in overrides if not o.startswith("tire.")])
    tire_overrides = _string_list(raw.pop("tire_overrides", []), "tire_overrides")
    only = raw.pop("free_only", None)
    if only is not None:
        only = _string_list(only, "free_only")
        known = [f.get("name") for f in raw.get("free", []) if isinstance(f, dict)]
        for name in only:
            if name not in known:
                raise ConfigError(f"free_only: {name!r} is not a free parameter of the config (known: {', '.join(known)})")
        raw["free"] = [f for f in raw.get("free", []) if isinstance(f, dict) and f.get("name") in only]
    for key in raw:
        if key not in TOP_KEYS:
            raise ConfigError(f"{key}: unknown field (allowed: {', '.join(sorted(TOP_KEYS))})")
    if not isinstance(raw.get("tire_file"), str):
        raise ConfigError("tire_file: missing (path of the tire TOML, relative to this config)")
    tire_path = Path(tire_path).resolve() if tire_path is not None else (path.parent / raw["tire_file"]).resolve()
    tire_raw, tire = read_tire_file(tire_path, tire_overrides + [o[5:] for o in overrides if o.startswith("tire.")])
    base = params_from_spec(tire)
    method = raw.get("method", "arsm")
    if method not in METHODS:
        raise ConfigError(f"method = {method!r}: must be one of {METHODS}")
    targets = parse_targets(raw.get("targets"), data_dir)
    checks = parse_targets(raw["checks"], data_dir, "checks") if "checks" in raw else ()
    clash = sorted({t.name for t in targets} & {c.name for c in checks})
    if clash:
        raise ConfigError(f"checks.{clash[0]}: also a target; a response is fitted or checked, not both")
    space = ParamSpace.from_config(raw.get("free"), base, targets=targets, geometry=tire.geometry)
    names = [t.name for t in targets]
    obj = raw.get("objective", {})
    if not isinstance(obj, dict) or any(k != "weights" for k in obj):
        raise ConfigError("objective: only `weights = { TARGET = number }` is allowed")
    wt = obj.get("weights", {})
    for k, v in (wt.items() if isinstance(wt, dict) else [("weights", wt)]):
        if k not in names or not (_is_num(v) and v >= 0):
            raise ConfigError(f"objective.weights.{k} = {v!r}: must name a target ({', '.join(names)})"
                              " and be a number >= 0")
    weights = tuple(float(wt.get(n, 1.0)) for n in names)
    arsm = validate_table(raw.get("arsm", {}), ARSM_SCHEMA, "arsm")
    if arsm["surface"] not in KINDS:
        raise ConfigError(f"arsm.surface = {arsm['surface']!r}: must be one of {KINDS}")
    if arsm["region_rule"] not in RULES:
        raise ConfigError(f"arsm.region_rule = {arsm['region_rule']!r}: must be one of {RULES}")
    for key, allowed in (("fill", FILLS), ("weighting", WEIGHTINGS)):
        if arsm[key] not in allowed:
            raise ConfigError(f"arsm.{key} = {arsm[key]!r}: must be one of {allowed}")
    if arsm["n_initial"] and not 2 <= arsm["n_initial"] <= arsm["budget"]:
        raise ConfigError(f"arsm.n_initial = {arsm['n_initial']}: must be 0 or in [2, arsm.budget "
                          f"= {arsm['budget']}]")
    gradient = validate_table(raw.get("gradient", {}), GRADIENT_SCHEMA, "gradient")
    sens = raw.get("sensitivity", {})
    if not isinstance(sens, dict) or any(k != "quantities" for k in sens):
        raise ConfigError("sensitivity: only `quantities = [names]` is allowed")
    quantities = sens.get("quantities", names)
    if not (isinstance(quantities, list) or isinstance(quantities, tuple)) or not quantities or \
            not all(isinstance(q, str) for q in quantities):
        raise ConfigError(f"sensitivity.quantities = {quantities!r}: must be a non-empty list of names")
    anchor = raw.get("anchor", {})
    for k, a in anchor.items():
        if k not in names and k != "total":
            raise ConfigError(f"anchor.{k}: must name a target ({', '.join(names)}) or total")
        if not (isinstance(a, dict) and all(_is_num(v) for kk, v in a.items() if kk != "note")):
            raise ConfigError(f"anchor.{k}: must be a table of numbers (simulated, error_percent)")
    desc = raw.get("description", "")
    return CalibrationSpec(path=path, raw=raw, tire_path=tire_path, tire_raw=tire_raw, tire=tire,
                           base_params=base, space=space, targets=targets, weights=weights,
                           method=method, arsm=arsm, gradient=gradient,
                           sensitivity_quantities=tuple(quantities), anchor=dict(anchor),
                           description=desc if isinstance(desc, str) else "", checks=checks)
