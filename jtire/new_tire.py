"""`jtire new-tire`: a tire file and its run and characterization configs from a size designation.

The section follows from the designation (`jtire.sizes`); widths, crown radius, masses and the rim are
scaled from the shipped truck tire (tires/xone_xda.toml), whose materials a truck size takes, or from the
passenger template (tires/passenger_materials.toml). The configs put the tire at its rated condition (the
load index's load at the reference pressure) and scale every load-like table field with the rated load
by the study's own ratios, so the same experiments run on a 205/55R16 as on the 445/50R22.5.
"""

import dataclasses
import math
import re

from . import sizes as S
from . import units as U
from .config import read_toml, tire_from_dict
from .errors import ConfigError
from .resources import config_path

TRUCK_TEMPLATE = ("tires", "xone_xda.toml")
PASSENGER_TEMPLATE = ("tires", "passenger_materials.toml")

# per kind: rubber above the belt mid-surface (mm), tread and belt width / section width, rim flange
# height (mm), and the tire mass (kg) of a reference size whose areal density the new size takes
KIND = {
    "truck": {"tread_depth_mm": 25.0, "tread": 390.0 / 445.0, "belt": 360.0 / 445.0, "flange_mm": 12.7},
    "passenger": {"tread_depth_mm": 12.0, "tread": 0.84, "belt": 0.82, "flange_mm": 17.5,
                  "ref_size": "205/55R16", "ref_tire_kg": 9.0, "belt_share": 0.75},
}
CROWN_RADIUS_PER_WIDTH = 2000.0 / 445.0  # the shipped tire's transverse crown radius per section width
RIGID_BELT_TESTS = ("inplane_rotation", "sidewall_translation", "sidewall_camber", "sidewall_longitudinal")
RIM_GYRATION = 0.2266 / 0.28575  # the shipped rim's radius of gyration (1.6 kg m^2 at 31.17 kg) per rim radius


@dataclasses.dataclass(frozen=True)
class Rated:
    load_index: int
    load_kg: float
    pressure_kPa: float

    @property
    def load_N(self) -> float:
        return self.load_kg * U.G0


def rated_condition(size: S.Size, load_index=None, pressure_kPa=None) -> Rated:
    known = S.KNOWN_SIZES.get(size.text)
    if load_index is None:
        if known is None:
            raise ConfigError(f"--load-index: needed for {size.text} (known without it: {', '.join(S.KNOWN_SIZES)}); "
                              f"an integer from {S.LOAD_INDEX_RANGE[0]} to {S.LOAD_INDEX_RANGE[1]}, from the sidewall")
        load_index = known[1]
    if pressure_kPa is None:
        pressure_kPa = known[2] if known is not None else S.DEFAULT_PRESSURE_KPA[size.kind]
    if not 70.0 <= pressure_kPa <= 1700.0:
        raise ConfigError(f"--pressure-kPa {pressure_kPa:g}: out of range (70 to 1700 kPa)")
    return Rated(load_index, S.load_index_kg(load_index), float(pressure_kPa))


def _torus_area(width, height, outer_diameter) -> float:
    """Outer surface of the section swept around the axle: (section perimeter ~ W + 2 H) x mean circumference."""
    return (width + 2.0 * height) * math.pi * (outer_diameter - height)


def _template_materials(kind: str) -> str:
    """The material sections of the kind's template, verbatim with their comments."""
    if kind == "passenger":
        return config_path(*PASSENGER_TEMPLATE).read_text()
    text = config_path(*TRUCK_TEMPLATE).read_text()
    start, end = text.find("# Per-part shell parameters"), text.find("[model_form]")
    if start < 0 or end < start:
        raise RuntimeError(f"{config_path(*TRUCK_TEMPLATE)}: its materials block moved; update jtire.new_tire")
    return text[start:end].rstrip() + "\n"


def tire_text(size: S.Size, rated: Rated, rim_width_in=None) -> str:
    """The tire file of a size, as TOML text with a reason beside every value."""
    k = KIND[size.kind]
    mm = lambda x: round(x / U.MM, 1)  # noqa: E731
    w, h, od, rim_d = size.section_width, size.section_height, size.outer_diameter, size.rim_diameter
    rim_in = S.measuring_rim_in(size) if rim_width_in is None else float(rim_width_in)
    rim_w = rim_in * U.INCH
    if not 0.4 * w < rim_w < w:
        raise ConfigError(f"--rim-width-in {rim_in:g}: must lie between 40 % and 100 % of the section width "
                          f"({0.4 * w / U.INCH:.2f} to {w / U.INCH:.2f} in)")
    belt = max(k["belt"] * w, rim_w + 5 * U.MM)  # the mesh's belt edge lies outside the rim flange
    tread = min(max(k["tread"] * w, belt), w)
    base = read_toml(config_path(*TRUCK_TEMPLATE), "tire file")
    bt, bm = base["tire"], base["mass"]
    if size.kind == "truck":
        ref_area = _torus_area(bt["section_width_mm"], bt["section_height_mm"], bt["outer_diameter_mm"])
        tire_kg = bm["tire_kg"] * _torus_area(w / U.MM, h / U.MM, od / U.MM) / ref_area
        belt_kg = tire_kg * bm["belt_kg"] / bm["tire_kg"]
        mass_why = (f"scaled from the {bt['size']} ({bm['tire_kg']:g} kg) by the section's surface", "the same share")
    else:
        ref = S.parse_size(k["ref_size"])
        ref_area = _torus_area(ref.section_width, ref.section_height, ref.outer_diameter)
        tire_kg = k["ref_tire_kg"] * _torus_area(w, h, od) / ref_area
        belt_kg = k["belt_share"] * tire_kg
        mass_why = (f"scaled from a typical {k['ref_size']} ({k['ref_tire_kg']:g} kg) by the section's surface",
                    f"{k['belt_share']:.0%} of the tire: belt, tread and crown")
    rim_kg = bm["rim_kg"] * (rim_d * rim_w) / (bt["rim_diameter_mm"] * bt["rim_width_mm"] * U.MM**2)
    rim_iy = rim_kg * (RIM_GYRATION * rim_d / 2) ** 2
    rim_ixz = rim_iy * bm["rim_Ixz_kgm2"] / bm["rim_Iy_kgm2"]
    template = "tires/xone_xda.toml" if size.kind == "truck" else "tires/passenger_materials.toml"
    lines = [
        f"# {size.text}: written by `jtire new-tire {size.text}` from the size designation. The section follows",
        "# from the designation; widths, crown radius and masses are scaled from the shipped tires; the materials",
        f"# are jtire's {size.kind} defaults ({template}). A STARTING POINT TO CALIBRATE to your measurements",
        "# (`jtire calibrate`), not a model of any one manufacturer's tire.",
        "",
        "[tire]",
        f'size = "{size.text}"',
        f"rim_diameter_mm = {mm(rim_d)}        # {rim_d / U.INCH:g} in",
        f"rim_width_mm = {mm(rim_w)}           # {rim_in:.2f} in measuring rim",
        f"flange_height_mm = {k['flange_mm']}          # where the carcass leaves the rim",
        f"section_width_mm = {mm(w)}",
        f"section_height_mm = {mm(h)}      # aspect ratio {size.aspect_ratio:.0%}",
        f"outer_diameter_mm = {mm(od)}     # rim + 2 section heights (unloaded)",
        f"tread_depth_mm = {k['tread_depth_mm']}            # rubber above the belt mid-surface: tread + undertread",
        f"tread_width_mm = {mm(tread)}         # {tread / w:.0%} of the section width",
        f"belt_width_mm = {mm(belt)}          # {belt / w:.0%} of the section width",
        f"crown_radius_mm = {mm(CROWN_RADIUS_PER_WIDTH * w)}        # transverse crown radius, "
        f"{CROWN_RADIUS_PER_WIDTH:.2f} section widths as the shipped tire (calibratable)",
        "widest_point_ratio = 0.5       # widest point at half the section height (calibratable)",
        'mid_surface = "section_width"',
        "",
        "[mass]                         # the mesh reproduces these by construction",
        f"tire_kg = {tire_kg:.2f}                # {mass_why[0]}",
        f"belt_kg = {belt_kg:.2f}                # m_b, {mass_why[1]}",
        f"rim_kg = {rim_kg:.2f}                 # scaled from the study's 22.5 x 14.00 rim ({bm['rim_kg']:g} kg) "
        "by diameter x width",
        f"rim_Iy_kgm2 = {rim_iy:.4g}            # radius of gyration {RIM_GYRATION:.3f} of the rim radius, as the "
        "study's rim",
        f"rim_Ixz_kgm2 = {rim_ixz:.4g}",
        "",
        "[mesh]",
        "n_theta = 64                   # segments around the tire",
        "n_side = 5                     # elements per sidewall (multiple of 5)",
        "n_crown = 6                    # elements across the crown",
        "contact_subpoints = 2          # contact points per segment",
        "",
        "[rated]                        # the load index's load at the reference pressure (not used by the physics)",
        f"load_index = {rated.load_index}",
        f"load_kg = {rated.load_kg:g}",
        f"pressure_kPa = {rated.pressure_kPa:g}",
        "",
        _template_materials(size.kind),
    ]
    return "\n".join(lines)


def _scaled(rated: Rated, factor: float, ndigits=2) -> float:
    return round(factor * rated.load_N / U.KN, ndigits)


def run_text(size: S.Size, rated: Rated) -> str:
    """E01, E02, E09 and E12 at the rated condition; E02's ramp and E09's force scaled with the rated load as
    in the shipped default config (60 kN and 5 kN at the study's 45.4 kN)."""
    speed = "speed_mph = 15.0             # the study's" if size.kind == "truck" else \
        "speed_mph = 49.7             # 80 km/h, ISO 28580's passenger speed"
    return "\n".join([
        f"# {size.text} at its rated condition: E01 footprint, E02 vertical stiffness, E09 lateral stiffness, E12",
        "# rolling resistance. Written by `jtire new-tire`; run: jtire run THIS_FILE",
        'experiments = ["footprint", "vertical_stiffness", "lateral_stiffness", "rolling_resistance"]',
        'tire_file = "tire.toml"',
        "",
        "[condition]",
        f"load_kg = {rated.load_kg:g}               # load index {rated.load_index}",
        f"pressure_kPa = {rated.pressure_kPa:g}",
        "",
        "[vertical_stiffness]",
        f"max_load_kN = {_scaled(rated, 1.32)}",
        "stated_load_kN = 0.0           # 0: the secant at the rated load",
        f"fit_range_kN = [{_scaled(rated, 0.22)}, {_scaled(rated, 1.32)}]",
        "",
        "[lateral_stiffness]",
        f"force_kN = {_scaled(rated, 0.11, 3)}",
        "decay_s = 0.0                  # the static part only",
        "",
        "[rolling_resistance]",
        speed,
        "",
    ])


def characterize_text(size: S.Size, rated: Rated) -> str:
    """The shipped characterization (configs/characterize.toml) on this tire: loads 0.5, 1 and 1.5 times the
    rated load, pressures 70/120, 1 and 150/120 times the rated pressure, the study's ratios."""
    text = config_path("characterize.toml").read_text()
    psi = rated.pressure_kPa * 1e3 / U.PSI
    loads = [round(f * rated.load_kg, 1) for f in (0.5, 1.0, 1.5)]
    pressures = [round(f * psi, 1) for f in (70.0 / 120.0, 1.0, 150.0 / 120.0)]
    subs = {
        r'^tire_file = ".*"$': 'tire_file = "tire.toml"',
        r"^description = .*$": f'description = "rigid-ring characterization of the {size.text} (jtire new-tire)"',
        r"^loads_kg = .*$": f"loads_kg = {loads}",
        r"^pressures_psi = .*$": f"pressures_psi = {pressures}",
        r"^rated_load_kg = .*$": f"rated_load_kg = {loads[1]}",
        r"^rated_pressure_psi = .*$": f"rated_pressure_psi = {pressures[1]}",
        r"^max_load_kN = [0-9.]+": f"max_load_kN = {_scaled(rated, 1.65)}\n"
                                   f"fit_range_kN = [{_scaled(rated, 0.22)}, {_scaled(rated, 1.32)}]",
        r"^force_kN = [0-9.]+": f"force_kN = {_scaled(rated, 0.11, 3)}",
    }
    for pattern, repl in subs.items():
        text, n = re.subn(pattern, repl, text, count=1, flags=re.MULTILINE)
        if n != 1:
            raise RuntimeError(f"configs/characterize.toml: no line matches {pattern!r}; update jtire.new_tire")
    # the rigid-belt tests' forces: their defaults, set for the study's tire at 45.4 kN, scaled to the rated load
    from .experiments import REGISTRY

    ratio = rated.load_N / (4625.0 * U.G0)
    text += ("\n# rigid-belt and standstill test forces: each test's default (for the study's 45.4 kN) scaled to the "
             "rated load\n")
    for name in (*RIGID_BELT_TESTS, "longitudinal_stiffness"):
        default_kN = REGISTRY[name].schema["force_kN"].default
        text += f"\n[{name}]\nforce_kN = {round(default_kN * ratio, 3)}\n"
    head = (f"# The study's virtual test programme on the {size.text}, written by `jtire new-tire`: the shipped\n"
            "# characterization with its grid and load-like fields scaled to this tire's rated condition.\n"
            "# Run:  jtire characterize THIS_FILE --out runs/characterize_mytire\n")
    return head + text


def files_for(size_text: str, rim_width_in=None, load_index=None, pressure_kPa=None, measured=None) -> tuple:
    """(Size, Rated, {file name: text}) for a designation; the tire text is validated as `jtire run` would.
    measured: a measurements CSV (path) for a calibrate.toml too."""
    size = S.parse_size(size_text)
    rated = rated_condition(size, load_index, pressure_kPa)
    tire = tire_text(size, rated, rim_width_in)
    import tomllib

    tire_from_dict(tomllib.loads(tire))  # a section the mesh cannot build is refused here, naming the field
    files = {"tire.toml": tire, "run.toml": run_text(size, rated), "characterize.toml": characterize_text(size, rated)}
    if measured is not None:
        from pathlib import Path

        files["calibrate.toml"] = calibrate_text(size, rated, read_measured(measured), Path(measured).name)
    return size, rated, files


# ---- a calibration config from the user's measurements (CSV) ----------------------------------------
# CSV quantity -> (short name, experiment, response, {unit in the CSV: measured_<unit> key of the target})
MEASURED = {
    # stiffnesses become the deflection at the row's load (k_sv) or at 11 % of it sideways (k_l), the study's
    # target form (DZ, DY): F / k, written in mm
    "k_sv": ("DZ", "vertical_stiffness", "deflection_m", {"N/m": 1.0, "kN/m": 1e3}),
    "k_l": ("DY", "lateral_stiffness", "lateral_deflection_m", {"N/m": 1.0, "kN/m": 1e3}),
    "footprint_length": ("FL", "footprint", "contact_length_m", {"mm": "measured_mm", "m": "measured_m"}),
    "footprint_width": ("FW", "footprint", "contact_width_m", {"mm": "measured_mm", "m": "measured_m"}),
    "rolling_resistance": ("FX", "rolling_resistance", "rolling_resistance_N", {"N": "measured_N", "kN": "measured_kN"}),
}
CSV_COLUMNS = ("quantity", "value", "unit", "load_kg", "pressure_kPa")  # and optionally speed_kmh


def read_measured(path) -> list:
    """Rows of a measurements CSV, checked: one line naming the file, line and field for anything wrong."""
    import csv

    from .config import read_text

    text = read_text(path, "measurements CSV")
    lines = [ln for ln in text.splitlines() if not ln.lstrip().startswith("#")]  # '#' lines are comments
    rows = list(csv.DictReader(lines))
    header = next(csv.reader(lines), [])
    missing = [c for c in CSV_COLUMNS if c not in header]
    if missing:
        raise ConfigError(f"{path}: needs the columns {', '.join(CSV_COLUMNS)} (and optionally speed_kmh); "
                          f"missing {', '.join(missing)}")
    if not rows:
        raise ConfigError(f"{path}: no measurements (one row per measured quantity: {', '.join(MEASURED)})")
    out = []
    data_lines = [i + 1 for i, ln in enumerate(text.splitlines()) if not ln.lstrip().startswith("#")][1:]
    for line, row in zip(data_lines, rows):
        where = f"{path} line {line}"
        q = (row["quantity"] or "").strip()
        if q not in MEASURED:
            raise ConfigError(f"{where}: quantity {q!r}: must be one of {', '.join(MEASURED)}")
        units = MEASURED[q][3]
        unit = (row["unit"] or "").strip()
        if unit not in units:
            raise ConfigError(f"{where}: unit {unit!r} for {q}: must be one of {', '.join(units)}")
        vals = {}
        for col, lo, hi in (("value", 0.0, math.inf), ("load_kg", 50.0, 50000.0), ("pressure_kPa", 70.0, 1700.0),
                            ("speed_kmh", 1.0, 150.0)):
            raw = (row.get(col) or "").strip()
            if col == "speed_kmh" and not raw:
                continue
            try:
                v = float(raw)
            except ValueError:
                raise ConfigError(f"{where}: {col} = {raw!r}: must be a number") from None
            if not (lo < v <= hi if col == "value" else lo <= v <= hi) or math.isnan(v):
                raise ConfigError(f"{where}: {col} = {raw}: must be in {'(0, inf)' if col == 'value' else f'[{lo:g}, {hi:g}]'}")
            vals[col] = v
        out.append({"quantity": q, "unit": unit, **vals})
    return out


def calibrate_text(size: S.Size, rated: Rated, measured: list, source: str) -> str:
    """A calibration config: one target per measured row at its own condition, the free parameters of the
    shipped study calibration (geometry bounds made relative to this tire's values), a non-tire drag bias on
    the rolling-resistance targets, ARSM with the study's budget."""
    study = read_toml(config_path("calibration", "study.toml"))
    base = read_toml(config_path(*TRUCK_TEMPLATE), "tire file")["tire"]
    speed_kmh = 80.0 if size.kind == "passenger" else 15.0 * U.MPH / U.KMH
    lines = [f"# Calibration of the {size.text} to the measurements in {source}, written by `jtire new-tire`.",
             "# Run:  jtire calibrate THIS_FILE --out runs/calibrate_mytire",
             f'description = "{size.text} to {len(measured)} measurement(s) from {source}"',
             'tire_file = "tire.toml"', 'method = "arsm"', ""]
    count, rr_names = {}, []
    for row in measured:
        short, exp, response, units = MEASURED[row["quantity"]]
        count[short] = count.get(short, 0) + 1
        name = f"{short}{count[short]}"
        load_kN = row["load_kg"] * U.G0 / U.KN
        lines += [f"[targets.{name}]", f'experiment = "{exp}"', f'quantity = "{response}"',
                  f"condition = {{ load_kg = {row['load_kg']:g}, pressure_kPa = {row['pressure_kPa']:g} }}"]
        if exp in ("vertical_stiffness", "lateral_stiffness"):
            k = row["value"] * units[row["unit"]]  # N/m
            if exp == "vertical_stiffness":  # the deflection at the row's load; the ramp 1.32 times past it
                force_kN = round(load_kN, 3)
                lines.append(f"table = {{ stated_load_kN = {force_kN}, max_load_kN = {round(1.32 * load_kN, 2)}, "
                             f"fit_range_kN = [{round(0.22 * load_kN, 2)}, {round(1.32 * load_kN, 2)}] }}")
            else:  # 11 % of the load sideways, static (as the study's 5 kN at 45.4 kN)
                force_kN = round(0.11 * load_kN, 3)
                lines.append(f"table = {{ force_kN = {force_kN}, decay_s = 0.0 }}")
            lines += [f"measured_mm = {force_kN * U.KN / k / U.MM:.5g}   # {row['quantity']} = {row['value']:g} "
                      f"{row['unit']}: {force_kN:g} kN / k", ""]
            continue
        if exp == "rolling_resistance":
            v = row.get("speed_kmh", speed_kmh)
            lines.append(f"table = {{ speed_mph = {round(v * U.KMH / U.MPH, 3)} }}")
            rr_names.append((name, row["value"] * (1e3 if row["unit"] == "kN" else 1.0)))
        lines += [f"{units[row['unit']]} = {row['value']:g}", ""]
    lines += ["# ---- free parameters (those of configs/calibration/study.toml; theta = ln(value)) ----",
              "# factor = [lo, hi] times the tire file's value, or bounds = [lo, hi] in the tire file's unit."]
    for f in study["free"]:
        if f["name"].startswith("bias."):
            continue
        lines += ["[[free]]", f'name = "{f["name"]}"']
        if f["name"].startswith("geometry.") and "bounds" in f:  # the study's bounds relative to its tire
            ref = base[f["name"].split(".", 1)[1] + "_mm"]
            lines.append(f"factor = [{f['bounds'][0] / ref:g}, {f['bounds'][1] / ref:g}]")
        else:
            lines.append(f"{'factor' if 'factor' in f else 'bounds'} = {list(f.get('factor', f.get('bounds')))}")
        lines += [f"why = {_toml_str(f.get('why', ''))}", ""]
    if rr_names:
        hi = 2.0 * max(v for _, v in rr_names)
        lines += ["# FX_measured = FX_tire + b: drag of the rig or vehicle that is not the tire's, and measurement bias",
                  "[[free]]", 'name = "bias.non_tire_drag"', f"bounds = [0.0, {hi:g}]",
                  f"targets = [{', '.join(repr(n).replace(chr(39), chr(34)) for n, _ in rr_names)}]",
                  'why = "non-tire drag and measurement bias on the rolling-resistance targets (N)"', ""]
    lines += ["[arsm]", "budget = 45            # the study's 45 iterations", "seed = 0", "batch_size = 4", ""]
    return "\n".join(lines)


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'
