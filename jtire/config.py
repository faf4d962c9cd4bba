"""TOML configs -> frozen, validated, SI specs. The only place where units are converted.

A config is a tire file (`configs/tires/*.toml`) and an experiment file
(`configs/experiments/*.toml`) that names it. Every field is declared below with its type, its
unit and its allowed range; anything else (an unknown key, a wrong type, a value out of range, a
missing field) is a `ConfigError` naming the field and what is allowed, in one line.
Overrides: `apply_overrides(raw, ["condition.pressure_psi=70"])` sets fields by dotted path
before validation, so they are checked exactly like the file.
"""

import dataclasses
import math
import tomllib
from pathlib import Path

from . import units as U
from .errors import ConfigError
from .mesh import PART_NAMES, Geometry, MassTargets


@dataclasses.dataclass(frozen=True)
class F:
    """A field: python type, SI factor, allowed range in the file's unit, default (None = required)."""

    type: type
    factor: float = 1.0
    lo: float = -math.inf
    hi: float = math.inf
    default: object = None
    unit: str = ""

    def parse(self, path, value):
        if self.type is float and isinstance(value, int) and not isinstance(value, bool):
            value = float(value)
        if self.type is list:
            if not isinstance(value, list) or not all(isinstance(v, (int, float)) for v in value) or not value:
                raise ConfigError(f"{path} = {value!r}: must be a non-empty list of numbers{self._range()}")
            for v in value:
                self._check_range(path, float(v))
            return tuple(float(v) * self.factor for v in value)
        if not isinstance(value, self.type) or (self.type is int and isinstance(value, bool)):
            raise ConfigError(f"{path} = {value!r}: must be {self.type.__name__}{self._range()}")
        if self.type in (int, float):
            self._check_range(path, float(value))
            return value * self.factor if self.type is float else value
        return value

    def _check_range(self, path, v):
        if not (self.lo <= v <= self.hi) or math.isnan(v):
            raise ConfigError(f"{path} = {v:g}: must be in [{self.lo:g}, {self.hi:g}]{' ' + self.unit if self.unit else ''}")

    def _range(self):
        if self.type in (int, float, list) and (self.lo > -math.inf or self.hi < math.inf):
            return f" in [{self.lo:g}, {self.hi:g}]{' ' + self.unit if self.unit else ''}"
        return ""


def mm(lo, hi, default=None):
    return F(float, U.MM, lo, hi, default, "mm")


def mpa(lo, hi, default=None):
    return F(float, U.MPA, lo, hi, default, "MPa")


PART_SCHEMA = {
    "E_meridional_MPa": mpa(0.1, 2e5), "E_circumferential_MPa": mpa(0.1, 2e5), "G_shear_MPa": mpa(0.01, 2e4),
    "E_bending_MPa": mpa(0.1, 2e5), "thickness_mm": mm(0.5, 100), "loss": F(float, 1, 0, 2, None, "(loss tangent)"),
}

TIRE_SCHEMA = {
    "tire": {
        "size": F(str, default=""), "rim_diameter_mm": mm(200, 2000), "rim_width_mm": mm(50, 1000),
        "flange_height_mm": mm(0, 100), "section_width_mm": mm(50, 1000), "section_height_mm": mm(30, 800),
        "outer_diameter_mm": mm(300, 4000), "tread_depth_mm": mm(1, 100), "tread_width_mm": mm(20, 1000),
        "belt_width_mm": mm(20, 1000), "crown_radius_mm": mm(50, 1e5),
    },
    "mass": {
        "tire_kg": F(float, 1, 1, 1e4, unit="kg"), "belt_kg": F(float, 1, 0.1, 1e4, unit="kg"),
        "rim_kg": F(float, 1, 0.1, 1e4, unit="kg"), "rim_Iy_kgm2": F(float, 1, 1e-3, 1e4, unit="kg m^2"),
        "rim_Ixz_kgm2": F(float, 1, 1e-3, 1e4, unit="kg m^2"),
    },
    "mesh": {
        "n_theta": F(int, 1, 16, 1024), "n_side": F(int, 1, 5, 100), "n_crown": F(int, 1, 4, 100),
        "contact_subpoints": F(int, 1, 1, 8),
    },
    "parts": {name: PART_SCHEMA for name in PART_NAMES},
    "undertread": {"E_MPa": mpa(0.1, 1e3), "thickness_mm": mm(0.1, 50)},
    "tread": {"E_MPa": mpa(0.1, 1e3), "G_MPa": mpa(0.01, 1e3), "loss": F(float, 1, 0, 2), "friction": F(float, 1, 0, 3)},
    "viscoelastic": {"relaxation_times_ms": F(list, U.MS, 1e-3, 1e4, unit="ms")},
    "reference": {  # measured values reported beside the simulated ones; never used by the physics
        "belt_Iy_kgm2": F(float, 1, 0, 1e4, 0.0), "belt_Ix_kgm2": F(float, 1, 0, 1e4, 0.0),
        "footprint_length_mm": mm(0, 5000, 0.0), "footprint_width_mm": mm(0, 5000, 0.0),
    },
}


def _validate(raw: dict, schema: dict, prefix: str = "") -> dict:
    if not isinstance(raw, dict):
        raise ConfigError(f"{prefix.rstrip('.') or 'config'}: must be a table")
    out = {}
    for key in raw:
        if key not in schema:
            allowed = ", ".join(sorted(schema))
            raise ConfigError(f"{prefix}{key}: unknown field (allowed here: {allowed})")
    for key, sub in schema.items():
        path = prefix + key
        if isinstance(sub, dict):
            if key not in raw:
                if all(isinstance(f, F) and f.default is not None for f in sub.values()):
                    out[key] = _validate({}, sub, path + ".")
                    continue
                raise ConfigError(f"{path}: missing table")
            out[key] = _validate(raw[key], sub, path + ".")
        elif key in raw:
            out[key] = sub.parse(path, raw[key])
        elif sub.default is not None:
            out[key] = sub.parse(path, sub.default)  # defaults are in the file's units too
        else:
            raise ConfigError(f"{path}: missing field{sub._range()}")
    return out


def load_toml(path) -> dict:
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"{path}: no such config file")
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: not valid TOML ({e})") from None


def _coerce(text: str):
    """Parse an override value as TOML (numbers, booleans, strings, lists); bare words are strings."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_overrides(raw: dict, overrides) -> dict:
    """Set `section.key=value` fields (value parsed as TOML) on a raw config dict, in place."""
    for item in overrides or ():
        if "=" not in item:
            raise ConfigError(f"--set {item!r}: must be KEY=VALUE, e.g. condition.pressure_psi=70")
        key, value = item.split("=", 1)
        parts = key.strip().split(".")
        d = raw
        for p in parts[:-1]:
            d = d.setdefault(p, {})
            if not isinstance(d, dict):
                raise ConfigError(f"--set {key}: {p} is not a table")
        d[parts[-1]] = _coerce(value.strip())
    return raw


@dataclasses.dataclass(frozen=True)
class TireSpec:
    """The validated tire, SI."""

    size: str
    geometry: Geometry
    masses: MassTargets
    n_theta: int
    n_side: int
    n_crown: int
    contact_subpoints: int
    parts: dict  # part -> {E_meridional, E_circumferential, G_shear, E_bending, thickness, loss}
    undertread_E: float
    undertread_thickness: float
    tread_E: float
    tread_G: float
    tread_loss: float
    friction: float
    relaxation_times: tuple
    reference: dict


def tire_from_dict(raw: dict) -> TireSpec:
    v = _validate(raw, TIRE_SCHEMA)
    t = v["tire"]
    geometry = Geometry(
        rim_radius=t["rim_diameter_mm"] / 2, rim_width=t["rim_width_mm"], flange_height=t["flange_height_mm"],
        section_width=t["section_width_mm"], section_height=t["section_height_mm"],
        outer_radius=t["outer_diameter_mm"] / 2, tread_depth=t["tread_depth_mm"], tread_width=t["tread_width_mm"],
        belt_width=t["belt_width_mm"], crown_radius=t["crown_radius_mm"],
    )
    if abs(geometry.outer_radius - geometry.rim_radius - geometry.section_height) > 0.02:
        raise ConfigError("tire.section_height_mm: must equal (outer_diameter_mm - rim_diameter_mm) / 2 within 20 mm")
    if not geometry.rim_width < geometry.belt_width < geometry.section_width:
        raise ConfigError("tire.belt_width_mm: must lie between tire.rim_width_mm and tire.section_width_mm")
    m = v["mass"]
    if m["belt_kg"] >= m["tire_kg"]:
        raise ConfigError(f"mass.belt_kg = {m['belt_kg']:g}: must be below mass.tire_kg = {m['tire_kg']:g}")
    masses = MassTargets(m["tire_kg"], m["belt_kg"], m["rim_kg"], m["rim_Iy_kgm2"], m["rim_Ixz_kgm2"])
    me = v["mesh"]
    if me["n_side"] % (len(PART_NAMES) - 1):
        raise ConfigError(f"mesh.n_side = {me['n_side']}: must be a multiple of {len(PART_NAMES) - 1} (one element per sidewall part at least)")
    if me["n_crown"] % 2:
        raise ConfigError(f"mesh.n_crown = {me['n_crown']}: must be even (a node on the centre line)")
    parts = {name: {k.rsplit("_", 1)[0] if k.endswith(("_MPa", "_mm")) else k: val for k, val in p.items()}
             for name, p in v["parts"].items()}
    return TireSpec(
        size=t["size"], geometry=geometry, masses=masses, n_theta=me["n_theta"], n_side=me["n_side"],
        n_crown=me["n_crown"], contact_subpoints=me["contact_subpoints"], parts=parts,
        undertread_E=v["undertread"]["E_MPa"], undertread_thickness=v["undertread"]["thickness_mm"],
        tread_E=v["tread"]["E_MPa"], tread_G=v["tread"]["G_MPa"], tread_loss=v["tread"]["loss"],
        friction=v["tread"]["friction"], relaxation_times=v["viscoelastic"]["relaxation_times_ms"],
        reference=v["reference"],
    )


def load_tire(path, overrides=()) -> TireSpec:
    return tire_from_dict(apply_overrides(load_toml(path), overrides))


# ---- experiment configs ------------------------------------------------------------------------
CONDITION_SCHEMA = {
    "load_kg": F(float, U.G0, 0, 50000, None, "kg of load"), "load_kN": F(float, U.KN, 0, 500, None, "kN"),
    "load_lbs": F(float, U.LBF, 0, 110000, None, "lbs"),
    "pressure_psi": F(float, U.PSI, 10, 250, None, "psi"), "pressure_kPa": F(float, 1e3, 70, 1700, None, "kPa"),
    "pressure_bar": F(float, 1e5, 0.7, 17, None, "bar"),
}

SOLVER_SCHEMA = {
    "settle_damping_per_s": F(float, 1, 1, 1e4, 300.0, "1/s"),
    "ke_tol_J": F(float, 1, 1e-9, 10, 1e-3, "J"),
    "inflate_ramp_s": F(float, 1, 1e-3, 1, 0.04, "s"),
    "inflate_max_s": F(float, 1, 0.01, 5, 0.4, "s"),
    "load_ramp_s": F(float, 1, 1e-3, 5, 0.1, "s"),
    "settle_max_s": F(float, 1, 0.01, 5, 0.5, "s"),
}


def _one_of(table: dict, keys, what: str, path: str):
    given = [k for k in keys if k in table]
    if len(given) != 1:
        raise ConfigError(f"{path}: give exactly one of {', '.join(keys)} for the {what} (got {len(given)})")
    return given[0]


def parse_condition(raw: dict, need_load: bool = True) -> dict:
    """[condition] -> {"load_N", "pressure_Pa"} (SI), each given in exactly one unit."""
    if not isinstance(raw, dict):
        raise ConfigError("condition: must be a table")
    for key in raw:
        if key not in CONDITION_SCHEMA:
            raise ConfigError(f"condition.{key}: unknown field (allowed: {', '.join(CONDITION_SCHEMA)})")
    out = {}
    pk = _one_of(raw, ("pressure_psi", "pressure_kPa", "pressure_bar"), "inflation pressure", "condition")
    out["pressure_Pa"] = CONDITION_SCHEMA[pk].parse(f"condition.{pk}", raw[pk])
    if need_load:
        lk = _one_of(raw, ("load_kg", "load_kN", "load_lbs"), "vertical load", "condition")
        out["load_N"] = CONDITION_SCHEMA[lk].parse(f"condition.{lk}", raw[lk])
        if out["load_N"] <= 0:
            raise ConfigError(f"condition.{lk} = {raw[lk]}: must be > 0")
    return out


def parse_solver(raw: dict) -> dict:
    v = _validate(raw or {}, SOLVER_SCHEMA, "solver.")
    return {"settle_damping": v["settle_damping_per_s"], "ke_tol": v["ke_tol_J"], "inflate_ramp": v["inflate_ramp_s"],
            "inflate_max": v["inflate_max_s"], "load_ramp": v["load_ramp_s"], "settle_max": v["settle_max_s"]}


def validate_table(raw: dict, schema: dict, name: str) -> dict:
    """Validate an experiment's own table (e.g. [vertical_stiffness]) against its schema."""
    return _validate(raw or {}, schema, name + ".")
