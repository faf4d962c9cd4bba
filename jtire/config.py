"""TOML configs -> frozen, validated, SI specs. The only place where units are converted.

A config is a tire file (`configs/tires/*.toml`) and an experiment file
(`configs/experiments/*.toml`) that names it. Every field is declared with its type, its unit and
its allowed range (`jtire.schema.Field`; experiment tables are declared by the experiments);
anything else (an unknown key, a wrong type, a value out of range, a missing field, an
inconsistent pair of fields) is a `ConfigError` naming the field and what is allowed, in one line.
Every input file is read through `read_toml` (decode and parse errors name the file and line).
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
from .schema import Field, validate


def mm(lo, hi, default=None):
    return Field(float, U.MM, lo, hi, default, "mm")


def mpa(lo, hi, default=None):
    return Field(float, U.MPA, lo, hi, default, "MPa")


MID_SURFACES = ("section_width", "carcass")

PART_SCHEMA = {
    "E_meridional_MPa": mpa(0.1, 2e5), "E_circumferential_MPa": mpa(0.1, 2e5), "G_shear_MPa": mpa(0.01, 2e4),
    "E_bending_MPa": mpa(0.1, 2e5), "thickness_mm": mm(0.5, 100), "loss": Field(float, 1, 0, 2, None, "(loss tangent)"),
}

TIRE_SCHEMA = {
    "tire": {
        "size": Field(str, default=""), "rim_diameter_mm": mm(200, 2000), "rim_width_mm": mm(50, 1000),
        "flange_height_mm": mm(0, 100), "section_width_mm": mm(50, 1000), "section_height_mm": mm(30, 800),
        "outer_diameter_mm": mm(300, 4000), "tread_depth_mm": mm(1, 100), "tread_width_mm": mm(20, 1000),
        "belt_width_mm": mm(20, 1000), "crown_radius_mm": mm(50, 1e5),
        # height of the section's widest point above the rim, as a fraction of the section height
        "widest_point_ratio": Field(float, 1, 0.2, 0.8, 0.5, "(of the section height)"),
        # where the sidewall mid-surface is widest: at section_width / 2 ("section_width", the first
        # mesh's choice) or half the mid-sidewall's thickness inside it ("carcass")
        "mid_surface": Field(str, default="section_width", choices=MID_SURFACES),
    },
    "mass": {
        "tire_kg": Field(float, 1, 1, 1e4, unit="kg"), "belt_kg": Field(float, 1, 0.1, 1e4, unit="kg"),
        "rim_kg": Field(float, 1, 0.1, 1e4, unit="kg"), "rim_Iy_kgm2": Field(float, 1, 1e-3, 1e4, unit="kg m^2"),
        "rim_Ixz_kgm2": Field(float, 1, 1e-3, 1e4, unit="kg m^2"),
    },
    "mesh": {
        "n_theta": Field(int, 1, 16, 1024), "n_side": Field(int, 1, 5, 100), "n_crown": Field(int, 1, 4, 100),
        "contact_subpoints": Field(int, 1, 1, 8),
    },
    "parts": {name: PART_SCHEMA for name in PART_NAMES},
    "undertread": {"E_MPa": mpa(0.1, 1e3), "thickness_mm": mm(0.1, 50)},
    "tread": {"E_MPa": mpa(0.1, 1e3), "G_MPa": mpa(0.01, 1e3), "loss": Field(float, 1, 0, 2), "friction": Field(float, 1, 0, 3)},
    "viscoelastic": {"relaxation_times_ms": Field(list, U.MS, 1e-3, 1e4, unit="ms")},
    # the study's explicit-code model form, not tire physics (optional table; 0 = off)
    "model_form": {"nodal_damping_per_s": Field(float, 1, 0, 100, 0.0, "1/s")},
    # the load index's load at its reference pressure (`jtire new-tire`); a label, never used by the physics
    "rated": {"load_index": Field(int, 1, 0, 300, 0), "load_kg": Field(float, 1, 0, 1e5, 0.0, "kg"),
              "pressure_kPa": Field(float, 1, 0, 2000, 0.0, "kPa")},
    "reference": {  # measured values reported beside the simulated ones; never used by the physics
        "belt_Iy_kgm2": Field(float, 1, 0, 1e4, 0.0), "belt_Ix_kgm2": Field(float, 1, 0, 1e4, 0.0),
        "footprint_length_mm": mm(0, 5000, 0.0), "footprint_width_mm": mm(0, 5000, 0.0),
    },
}


def read_text(path, what: str = "config file") -> str:
    """The text of an input file; a missing file, a folder, an unreadable or non-UTF-8 file is one
    ConfigError line naming the file (and the byte where the decoding failed)."""
    path = Path(path)
    if path.is_dir():
        raise ConfigError(f"{path}: is a folder, not a {what}")
    if not path.is_file():
        raise ConfigError(f"{path}: no such {what}")
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError as e:
        line = path.read_bytes()[: e.start].count(b"\n") + 1
        raise ConfigError(f"{path}: not UTF-8 text (byte 0x{e.object[e.start]:02x} at line {line})") from None
    except OSError as e:
        raise ConfigError(f"{path}: cannot read ({e.strerror or e})") from None


def read_toml(path, what: str = "config file") -> dict:
    """Parse a TOML input file (every config, tire, calibration and reference file goes through here)."""
    text = read_text(path, what)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ConfigError(f"{path}: not valid TOML ({e})") from None


load_toml = read_toml


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
        if not all(parts):
            raise ConfigError(f"--set {item!r}: the key must be a dotted field name, e.g. condition.pressure_psi=70")
        d = raw
        for p in parts[:-1]:
            d = d.setdefault(p, {})
            if not isinstance(d, dict):
                raise ConfigError(f"--set {key.strip()}: {p} is not a table")
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
    nodal_damping: float = 0.0  # 1/s: mass-proportional damping on road-frame velocity (the study's form)


def _check_geometry(g: Geometry) -> None:
    """Cross-field checks of the section: refuse what `jtire.mesh.section_profile` cannot build,
    or would build as something else than the file says, each as one line naming the field and
    its allowed range (mm, from the other fields). The mesh's rules: the sidewall leaves the rim at
    rim_radius + flange_height and is widest at widest_point_ratio of its height; the crown is an arc of transverse radius
    crown_radius across the belt (a parabola r = r_belt - y^2 / (2 R)); the tread sits on the part of
    the section above 3/4 of its height, over tread_width (tapering to zero over 30 mm)."""
    mm_ = 1e3
    if abs(g.outer_radius - g.rim_radius - g.section_height) > 0.02:
        raise ConfigError(f"tire.section_height_mm = {g.section_height * mm_:g}: must equal (outer_diameter_mm - "
                          f"rim_diameter_mm) / 2 = {(g.outer_radius - g.rim_radius) * mm_:g} within 20 mm")
    if not g.flange_height < g.widest_point_ratio * g.section_height:
        raise ConfigError(f"tire.flange_height_mm = {g.flange_height * mm_:g}: must be below the widest point, "
                          f"{g.widest_point_ratio * g.section_height * mm_:g} mm above the rim (widest_point_ratio "
                          f"{g.widest_point_ratio:g} of the section height)")
    if not g.rim_width < g.section_width:
        raise ConfigError(f"tire.rim_width_mm = {g.rim_width * mm_:g}: must be below tire.section_width_mm = "
                          f"{g.section_width * mm_:g}")
    if not g.rim_width < g.belt_width < g.section_width:
        raise ConfigError(f"tire.belt_width_mm = {g.belt_width * mm_:g}: must lie between tire.rim_width_mm = "
                          f"{g.rim_width * mm_:g} and tire.section_width_mm = {g.section_width * mm_:g}")
    if not g.belt_width <= g.tread_width <= g.section_width:
        # the tread covers the belt (the road touches the crown only through the tread) and lies on
        # the crown: a wider tread than the section would change nothing in the mesh
        raise ConfigError(f"tire.tread_width_mm = {g.tread_width * mm_:g}: must be in [tire.belt_width_mm = "
                          f"{g.belt_width * mm_:g}, tire.section_width_mm = {g.section_width * mm_:g}] (the tread "
                          "covers the belt and lies on the crown)")
    # the crown's room: from the belt's centre line down to the lowest point that carries tread
    room = g.outer_radius - g.rim_radius - 0.75 * g.section_height
    if not g.tread_depth < room:
        raise ConfigError(f"tire.tread_depth_mm = {g.tread_depth * mm_:g}: must be below {room * mm_:.4g} mm (the "
                          "belt must lie in the upper quarter of the section height, where the mesh puts the tread)")
    hb = 0.5 * g.belt_width
    r_min = max(hb, hb**2 / (2.0 * (room - g.tread_depth)))
    if not g.crown_radius > r_min:
        raise ConfigError(f"tire.crown_radius_mm = {g.crown_radius * mm_:g}: must be above {r_min * mm_:.4g} mm for "
                          f"this belt (half-width {hb * mm_:g} mm) and tread depth: a crown arc across the belt needs "
                          "a radius above its half-width, and must not drop the belt edge below the tread zone "
                          f"(room {(room - g.tread_depth) * mm_:.3g} mm)")
    # the shoulder rises from the widest point to the belt edge
    r_edge = g.outer_radius - g.tread_depth - hb**2 / (2.0 * g.crown_radius)
    hi = (r_edge - g.rim_radius) / g.section_height
    if not g.widest_point_ratio < hi:
        raise ConfigError(f"tire.widest_point_ratio = {g.widest_point_ratio:g}: must be below {hi:.4g} (the widest "
                          "point must lie below the belt edge)")
    if not g.belt_width / 2 < g.section_width / 2 - g.carcass_inset:
        raise ConfigError(f"tire.mid_surface = \"carcass\": the carcass ({g.carcass_inset * mm_:g} mm inside the section "
                          "width) must stay outside the belt edge")


def tire_from_dict(raw: dict) -> TireSpec:
    v = validate(raw, TIRE_SCHEMA)
    t = v["tire"]
    geometry = Geometry(
        rim_radius=t["rim_diameter_mm"] / 2, rim_width=t["rim_width_mm"], flange_height=t["flange_height_mm"],
        section_width=t["section_width_mm"], section_height=t["section_height_mm"],
        outer_radius=t["outer_diameter_mm"] / 2, tread_depth=t["tread_depth_mm"], tread_width=t["tread_width_mm"],
        belt_width=t["belt_width_mm"], crown_radius=t["crown_radius_mm"],
        widest_point_ratio=t["widest_point_ratio"],
        carcass_inset=0.5 * v["parts"]["mid_sidewall"]["thickness_mm"] if t["mid_surface"] == "carcass" else 0.0,
    )
    _check_geometry(geometry)
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
        reference=v["reference"], nodal_damping=v["model_form"]["nodal_damping_per_s"],
    )


def load_tire(path, overrides=()) -> TireSpec:
    """Read and validate a tire file (`configs/tires/*.toml`) into a `TireSpec` (SI).

    Args:
        path (str | Path): the tire TOML file.
        overrides (list[str]): `section.key=value` strings applied to the file before validation (the `tire.` of
            `--set tire.<section>.<key>` taken off).

    Returns:
        The validated TireSpec. A missing or unreadable file, or any bad field, is one `ConfigError`
        line naming the file and the field (see `read_tire_file`, which also returns the raw dict).
    """
    return read_tire_file(path, overrides)[1]


def read_tire_file(path, overrides=()) -> tuple:
    """(raw dict after overrides, TireSpec) of a tire file; overrides are `section.key=value`
    (the `tire.` of `--set tire.<section>.<key>` taken off). A bad field is named as `--set tire.<field>`
    would name it, with the file: every command that reads a tire file (run, sweep, characterize,
    calibrate) says it the same way."""
    path = Path(path)
    raw = apply_overrides(read_toml(path, "tire file"), overrides)
    try:
        return raw, tire_from_dict(raw)
    except ConfigError as e:
        raise ConfigError(f"tire file {path.name}: tire.{e}") from None


# ---- experiment configs ------------------------------------------------------------------------
CONDITION_SCHEMA = {
    # loads below ~50 kg deflect a truck tire by well under a millimetre: no experiment resolves them
    "load_kg": Field(float, U.G0, 50, 50000, None, "kg of load"), "load_kN": Field(float, U.KN, 0.5, 500, None, "kN"),
    "load_lbs": Field(float, U.LBF, 110, 110000, None, "lbs"),
    "pressure_psi": Field(float, U.PSI, 10, 250, None, "psi"), "pressure_kPa": Field(float, 1e3, 70, 1700, None, "kPa"),
    "pressure_bar": Field(float, 1e5, 0.7, 17, None, "bar"),
}

SOLVER_SCHEMA = {
    "settle_damping_per_s": Field(float, 1, 1, 1e4, 300.0, "1/s"),
    "ke_tol_J": Field(float, 1, 1e-9, 10, 1e-3, "J"),
    "inflate_ramp_s": Field(float, 1, 1e-3, 1, 0.04, "s"),
    "inflate_max_s": Field(float, 1, 0.01, 5, 0.4, "s"),
    "load_ramp_s": Field(float, 1, 1e-3, 5, 0.1, "s"),
    "settle_max_s": Field(float, 1, 0.01, 5, 0.5, "s"),
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
    else:
        for lk in ("load_kg", "load_kN", "load_lbs"):
            if lk in raw:
                CONDITION_SCHEMA[lk].parse(f"condition.{lk}", raw[lk])  # checked even when unused
    return out


def parse_solver(raw: dict) -> dict:
    v = validate(raw or {}, SOLVER_SCHEMA, "solver.")
    return {"settle_damping": v["settle_damping_per_s"], "ke_tol": v["ke_tol_J"], "inflate_ramp": v["inflate_ramp_s"],
            "inflate_max": v["inflate_max_s"], "load_ramp": v["load_ramp_s"], "settle_max": v["settle_max_s"]}


def validate_table(raw: dict, schema: dict, name: str) -> dict:
    """Validate an experiment's own table (e.g. [vertical_stiffness]) against its schema."""
    return validate({} if raw is None else raw, schema, name + ".")


# ---- run configs: an experiment file + its tire file -----------------------------------------------
TOP_KEYS = {"experiment", "experiments", "tire_file", "condition", "solver", "description", "sweep"}


@dataclasses.dataclass(frozen=True)
class RunConfig:
    """A validated run config: the tire, the experiments (each built from its table), the condition
    (SI), the solver protocol (dict, SI), the raw [sweep] table, and the file it came from."""

    tire: TireSpec
    experiments: tuple  # of Experiment instances
    condition: dict
    solver: dict
    sweep: dict
    path: Path
    tables: dict = dataclasses.field(default_factory=dict)  # experiment name -> its validated table (SI)


def experiment_names(raw: dict, path: Path, registry) -> list:
    has_one, has_many = "experiment" in raw, "experiments" in raw
    if has_one and has_many:
        raise ConfigError(f"{path.name}: give experiment = NAME or experiments = [NAMES], not both")
    names = raw.get("experiments", [raw["experiment"]] if has_one else None)
    if isinstance(names, str):
        names = [names]
    if not names or not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ConfigError(f"{path.name}: needs experiment = NAME or experiments = [NAMES] (known: {', '.join(registry)})")
    for n in names:
        if n not in registry:
            raise ConfigError(f"experiment = {n!r}: unknown (known: {', '.join(registry)})")
    if len(set(names)) != len(names):
        raise ConfigError(f"experiments = {names}: each experiment at most once")
    return names


def load_run_config(path, overrides=(), registry=None) -> RunConfig:
    """Parse an experiment config (+ `--set` overrides): every table is validated (the tables of
    experiments the config does not run too), every experiment built, before anything runs.

    Overrides `tire.<section>.<key>=v` go to the tire file; the others to the experiment file.
    registry: name -> Experiment class (default `jtire.experiments.REGISTRY`).
    """
    from .experiments import REGISTRY
    from .experiments.phases import Protocol

    registry = REGISTRY if registry is None else registry
    path = Path(path)
    raw = read_toml(path)
    tire_over = [o[len("tire."):] for o in overrides if o.startswith("tire.")]
    apply_overrides(raw, [o for o in overrides if not o.startswith("tire.")])
    names = experiment_names(raw, path, registry)
    for key in raw:
        if key not in TOP_KEYS and key not in registry:
            raise ConfigError(f"{key}: unknown field (allowed: {', '.join(sorted(TOP_KEYS))} and experiment tables "
                              f"{', '.join(registry)})")
    if not isinstance(raw.get("description", ""), str):
        raise ConfigError("description: must be a string")
    if "tire_file" not in raw or not isinstance(raw["tire_file"], str):
        raise ConfigError("tire_file: missing (path of the tire TOML, relative to this config)")
    _, tire = read_tire_file((path.parent / raw["tire_file"]).resolve(), tire_over)
    solver = parse_solver(raw.get("solver", {}))
    proto = Protocol.from_dict(solver)
    tables = {n: validate_table(raw.get(n, {}), registry[n].schema, n) for n in registry if n in raw or n in names}
    exps = tuple(registry[n].from_table(tables[n], proto, tire) for n in names)
    condition = parse_condition(raw.get("condition", {}), need_load=any(e.needs_load for e in exps))
    for e in exps:
        check = getattr(e, "check_condition", None)
        if check is not None:
            check(condition)
    sweep = raw.get("sweep", {})
    if not isinstance(sweep, dict):
        raise ConfigError("sweep: must be a table")
    return RunConfig(tire, exps, condition, solver, sweep, path, {n: tables[n] for n in names})
