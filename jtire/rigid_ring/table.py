"""The characterization: what `jtire characterize` writes and every rigid-ring tool reads.

A characterization is the tire's reference data plus one row per condition (load x pressure) holding the SI
quantities of E01-E14 and E10's and E06's curves. A quantity may be missing (not run, or failed): absent or None.

`characterization.json` layout (SI; the writer adds "quantities" for the reader's eye, the reader ignores it):

    {
      "format": "jtire.characterization", "version": 1,
      "tire": {"name": str, "m_b_kg", "m_tot_kg", "tire_mass_kg", "rim_mass_kg", "I_by_kgm2",
               "I_bx_kgm2", "I_ay_kgm2", "I_ax_kgm2", "unloaded_radius_m", "width_m",
               "rim_radius_m", "rim_width_m", "aspect_ratio", "rated_load_N", "rated_pressure_Pa",
               "tire_Iy_kgm2", "tire_Ix_kgm2", "relaxation_time_s"},   # the last three optional
      "quantities": {"k_sv_N_per_m": {"symbol": "k_sv", "unit": "N/m", "experiment": "E02",
                                      "meaning": "..."}, ...},
      "rows": [{"load_N": 45371.25, "pressure_Pa": 827371.0,
                "k_sv_N_per_m": 1.28e6, "C_tot_2p_Ns_per_m": 1190.0, ...,   # any of QUANTITIES
                "E10_curves": {"slip_angle_deg": [...], "lateral_force_N": [...],  # SAE, road axes
                               "M_z_SAE_Nm": [...], "F_z_N": [...],
                               "F_y_SAE_N": [...], "F_x_N": [...]},   # the last two optional
                "E06_curves": {"slip": [...], "force_x_N": [...],   # ISO, > 0 driving
                               "force_z_N": [...], "surface": "drum"}}, ...]   # the last two optional
    }

`read_characterization(path)` takes that file or a folder holding it. `row_from_results` merges
the `quantities` of experiments' result.json dicts into one row (for the characterize runner).
"""

import dataclasses
import json
import math
import tomllib
from pathlib import Path

import numpy as np

from .. import units as U
from ..errors import ConfigError
from ..io import atomic_write_json
from ..resources import config_path

FORMAT = "jtire.characterization"
VERSION = 1
FILENAME = "characterization.json"


@dataclasses.dataclass(frozen=True)
class Quantity:
    key: str  # SI name as in the experiments' result.json
    symbol: str
    unit: str  # SI unit
    experiment: str
    meaning: str
    plane: str  # "in" or "out" (which table)
    damping: bool = False  # carries _2p_ and _fit_ variants
    display: tuple = ("", 1.0)  # (unit, factor) for the markdown tables


def _q(key, symbol, unit, exp, meaning, plane, damping=False, display=None):
    return Quantity(key, symbol, unit, exp, meaning, plane, damping, display or (unit, 1.0))


# Measured quantities, in table order. Damping keys name the value the experiment chose (two-peak
# when it had two clear peaks, else the fit); `<stem>_2p_<unit>` and `<stem>_fit_<unit>` carry both.
QUANTITIES = (
    _q("contact_length_m", "2a", "m", "E01", "contact patch length (full)", "in", display=("mm", 1e3)),
    _q("contact_width_m", "w", "m", "E01", "contact patch width", "in", display=("mm", 1e3)),
    _q("k_sv_N_per_m", "k_sv", "N/m", "E02", "total static vertical stiffness", "in", display=("kN/m", 1e-3)),
    _q("k_sv_tangent_N_per_m", "k_vt", "N/m", "E02", "tangent vertical stiffness at the load (the ring's dynamic springs)",
       "in", display=("kN/m", 1e-3)),
    _q("first_mode_Hz", "f", "Hz", "E03", "first in-plane mode, drum-cleat (FFT peak)", "in"),
    _q("k_dv_N_per_m", "k_dv", "N/m", "E03", "total dynamic vertical stiffness (2 pi f)^2 m_b", "in",
       display=("kN/m", 1e-3)),
    _q("C_tot_Ns_per_m", "C_tot", "N s/m", "E04", "total vertical damping (drop test)", "in", True),
    _q("k_btheta_Nm_per_rad", "k_btheta", "N m/rad", "E05", "in-plane rotational sidewall stiffness", "in",
       display=("kN m/rad", 1e-3)),
    _q("C_btheta_Nms_per_rad", "C_btheta", "N m s/rad", "E05", "in-plane rotational sidewall damping", "in", True),
    _q("k_bx_N_per_m", "k_bx", "N/m", "E13", "longitudinal sidewall stiffness (rigid belt, fore-aft)", "in",
       display=("kN/m", 1e-3)),
    _q("C_bx_Ns_per_m", "C_bx", "N s/m", "E13", "longitudinal sidewall damping (rigid belt, fore-aft)", "in", True),
    _q("k_k_N_per_slip", "k_k", "N", "E06", "longitudinal slip stiffness", "in", display=("kN", 1e-3)),
    _q("k_cx_N_per_m", "k_cx", "N/m", "E06", "tread longitudinal stiffness k_k / a", "in", display=("kN/m", 1e-3)),
    _q("C_x_N_per_m", "C_x", "N/m", "E14", "longitudinal stiffness at standstill (fore-aft at the rim)", "in",
       display=("kN/m", 1e-3)),
    _q("rolling_resistance_N", "F_r", "N", "E12", "rolling resistance (free-rolling hub drag)", "in"),
    _q("k_by_N_per_m", "k_by", "N/m", "E07", "lateral sidewall stiffness", "out", display=("kN/m", 1e-3)),
    _q("C_by_Ns_per_m", "C_by", "N s/m", "E07", "lateral sidewall damping", "out", True),
    _q("k_bgamma_Nm_per_rad", "k_bgamma", "N m/rad", "E08", "camber-wise sidewall stiffness", "out",
       display=("kN m/rad", 1e-3)),
    _q("C_bgamma_Nms_per_rad", "C_bgamma", "N m s/rad", "E08", "camber-wise sidewall damping", "out", True),
    _q("k_l_N_per_m", "k_l", "N/m", "E09", "total lateral stiffness (loaded, at the rim)", "out",
       display=("kN/m", 1e-3)),
    _q("C_l_Ns_per_m", "C_l", "N s/m", "E09", "total lateral damping", "out", True),
    _q("k_l_storage_N_per_m", "k_l'", "N/m", "E09'", "k_l on the storage moduli at E09's release frequency", "out",
       display=("kN/m", 1e-3)),
    _q("k_f_N_per_rad", "k_f", "N/rad", "E10", "cornering stiffness (SAE sign, > 0)", "out", display=("kN/rad", 1e-3)),
    _q("k_m_Nm_per_rad", "k_m", "N m/rad", "E10", "aligning-moment stiffness", "out", display=("kN m/rad", 1e-3)),
    _q("sigma_m", "sigma", "m", "E11", "lateral relaxation length k_f / k_l", "out", display=("mm", 1e3)),
)
BY_KEY = {q.key: q for q in QUANTITIES}  # and below, accepted but not tabulated: extra outputs tests and reports use
EXTRA_KEYS = ("deflection_m", "first_mode_fit_fn_Hz", "first_mode_xi", "k_dv_fit_N_per_m", "xi_in_contact_fit",
              "omega_n_in_contact_fit_rad_per_s",
              # E03's tandem cam (jtire.enveloping), fitted to its quasi-static crossing
              "ellips_shift_m", "ellips_length_m", "ellips_height_m", "ellips_order", "enveloping_fit_rms_height_m",
              "enveloping_max_height_m", "f_l_storage_Hz",  # f_l_storage: where k_l_storage's moduli are taken
              "xi_l_fit", "max_load_N", "settled_deflection_at_max_load_m")  # E09's release zeta, E02's top (derive)
CURVE_KEYS = ("slip_angle_deg", "lateral_force_N", "M_z_SAE_Nm", "F_z_N", "F_y_SAE_N", "F_x_N")
CURVE_REQUIRED = ("slip_angle_deg", "lateral_force_N")
SLIP_CURVE_KEYS = ("slip", "force_x_N", "force_z_N")
SLIP_CURVE_REQUIRED = ("slip", "force_x_N")


def variant_keys(q: Quantity) -> tuple:
    """(two-peak key, fit key) of a damping quantity, e.g. C_by_2p_Ns_per_m, C_by_fit_Ns_per_m."""
    symbol, stem, unit = q.key.split("_", 2)  # "C", "by", "Ns_per_m"
    return f"{symbol}_{stem}_2p_{unit}", f"{symbol}_{stem}_fit_{unit}"


def all_keys() -> tuple:
    return tuple(k for q in QUANTITIES for k in (q.key, *(variant_keys(q) if q.damping else ()))) + EXTRA_KEYS


@dataclasses.dataclass(frozen=True)
class TireInfo:
    """Reference masses, inertias and dimensions (SI). I_ay, I_ax: the ring's rim body's spin and
    camber inertias: from a characterization, the rim's (tire config) plus the tire's non-belt part
    (sidewalls and beads, from the mesh), as its mass m_tot - m_b carries them; from_reference,
    the rim's alone (the study gives neither)."""

    name: str
    m_b_kg: float
    m_tot_kg: float
    tire_mass_kg: float
    rim_mass_kg: float
    I_by_kgm2: float
    I_bx_kgm2: float
    I_ay_kgm2: float
    I_ax_kgm2: float
    unloaded_radius_m: float
    width_m: float
    rim_radius_m: float
    rim_width_m: float
    aspect_ratio: float
    rated_load_N: float
    rated_pressure_Pa: float
    # the whole tire's (no rim) inertias about the axle and a diameter: belt + sidewalls and beads;
    # None where not known (the study gives neither; folders written before they were recorded)
    tire_Iy_kgm2: float | None = None
    tire_Ix_kgm2: float | None = None
    relaxation_time_s: float | None = None  # the rubber's longest Prony time (s): the ring's lateral branches

    @classmethod
    def from_reference(cls, reference=None, tire_toml=None) -> "TireInfo":
        """The study's tire (configs/reference_xone_xda.toml [tire], rim inertias and width from
        configs/tires/xone_xda.toml)."""
        ref = tomllib.loads(Path(reference or config_path("reference_xone_xda.toml")).read_text())["tire"]
        tt = tomllib.loads(Path(tire_toml or config_path("tires", "xone_xda.toml")).read_text())
        r0 = ref["outer_diameter_mm"] * U.MM / 2
        return cls(name=ref["size"], m_b_kg=ref["belt_mass_kg"], m_tot_kg=ref["total_mass_kg"],
                   tire_mass_kg=ref["tire_mass_kg"], rim_mass_kg=ref["rim_mass_kg"],
                   I_by_kgm2=ref["belt_Iy_kgm2"], I_bx_kgm2=ref["belt_Ix_kgm2"],
                   I_ay_kgm2=tt["mass"]["rim_Iy_kgm2"], I_ax_kgm2=tt["mass"]["rim_Ixz_kgm2"],
                   unloaded_radius_m=r0, width_m=ref["section_width_mm"] * U.MM,
                   rim_radius_m=ref["rim_diameter_mm"] * U.MM / 2, rim_width_m=tt["tire"]["rim_width_mm"] * U.MM,
                   aspect_ratio=ref["section_height_mm"] / ref["section_width_mm"],
                   rated_load_N=ref["rated_load_kg"] * U.G0, rated_pressure_Pa=ref["rated_inflation_psi"] * U.PSI)

    @classmethod
    def from_dict(cls, d: dict) -> "TireInfo":
        fields = dataclasses.fields(cls)
        missing = [f.name for f in fields if f.name not in d and f.default is dataclasses.MISSING]
        if missing:
            raise ConfigError(f"characterization tire: missing {missing}")
        return cls(**{f.name: d[f.name] for f in fields if f.name in d})


def _curve_arrays(d: dict, keys, required, where) -> dict:
    """{key: 1-D float array or None} of a curve dict; the required keys present, every array as long
    as the first key's."""
    for k in required:
        if k not in d or d[k] is None:
            raise ConfigError(f"{where}.{k}: missing (needed: {list(required)})")
    arrs = {k: None if d.get(k) is None else np.asarray(d[k], float) for k in keys}
    n = arrs[keys[0]].shape
    for k, v in arrs.items():
        if v is not None and (v.ndim != 1 or v.shape != n):
            raise ConfigError(f"{where}.{k}: must be a list of {n[0]} numbers like {keys[0]}")
    return arrs


@dataclasses.dataclass(frozen=True)
class E10Curves:
    """Steady cornering curves of one condition, SAE signs: slip_angle_deg (n,), lateral_force_N
    (n,) in road axes, M_z_SAE_Nm (n,), F_z_N (n,); F_y_SAE_N and F_x_N (wheel axes) optional."""

    slip_angle_deg: np.ndarray
    lateral_force_N: np.ndarray
    M_z_SAE_Nm: np.ndarray | None = None
    F_z_N: np.ndarray | None = None
    F_y_SAE_N: np.ndarray | None = None
    F_x_N: np.ndarray | None = None

    @classmethod
    def from_dict(cls, d: dict, where: str = "E10_curves") -> "E10Curves":
        return cls(**_curve_arrays(d, CURVE_KEYS, CURVE_REQUIRED, where))

    def wheel_lateral_force(self) -> tuple:
        """(F_y in wheel axes, SAE sign (n,), source): F_y_SAE_N when given; else from the road-axis
        force and F_x: (lat + F_x sin a) / cos a; else the road-axis force itself (a free-rolling
        tire's F_x sin a is ~1 % of F_y below 10 deg)."""
        if self.F_y_SAE_N is not None:
            return self.F_y_SAE_N, "F_y_SAE_N (wheel axes)"
        a = np.radians(self.slip_angle_deg)
        if self.F_x_N is not None:
            return (self.lateral_force_N + self.F_x_N * np.sin(a)) / np.cos(a), "from lateral_force_N and F_x_N"
        return self.lateral_force_N, "lateral_force_N (road axes; F_x not given)"

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in CURVE_KEYS if getattr(self, k) is not None}


@dataclasses.dataclass(frozen=True)
class E06Curves:
    """Steady force-slip curve of one condition (E06), ISO signs: slip kappa (n,) (> 0 driving),
    force_x_N (n,) (> 0 forward), force_z_N (n,) or None; surface: "drum" or "flat" (None: not said)."""

    slip: np.ndarray
    force_x_N: np.ndarray
    force_z_N: np.ndarray | None = None
    surface: str | None = None

    @classmethod
    def from_dict(cls, d: dict, where: str = "E06_curves") -> "E06Curves":
        arrs = _curve_arrays(d, SLIP_CURVE_KEYS, SLIP_CURVE_REQUIRED, where)
        surface = d.get("surface")
        if surface is not None and surface not in ("drum", "flat"):
            raise ConfigError(f"{where}.surface = {surface!r}: must be \"drum\" or \"flat\"")
        return cls(**arrs, surface=surface)

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in SLIP_CURVE_KEYS if getattr(self, k) is not None}
        return d | ({} if self.surface is None else {"surface": self.surface})


@dataclasses.dataclass(frozen=True)
class ConditionRow:
    load_N: float
    pressure_Pa: float
    q: dict  # quantity key -> float (missing keys: not measured)
    curves: E10Curves | None = None
    slip_curves: E06Curves | None = None

    def get(self, key):
        v = self.q.get(key)
        return None if v is None or (isinstance(v, float) and not math.isfinite(v)) else float(v)

    @property
    def load_kg(self) -> float:
        return self.load_N / U.G0

    @property
    def pressure_psi(self) -> float:
        return self.pressure_Pa / U.PSI


@dataclasses.dataclass(frozen=True)
class Characterization:
    tire: TireInfo
    rows: tuple  # ConditionRow, any order

    def loads(self) -> list:
        return sorted({r.load_N for r in self.rows})

    def pressures(self) -> list:
        return sorted({r.pressure_Pa for r in self.rows})

    def row(self, load_N, pressure_Pa, rtol=1e-6):
        """The row at (load, pressure) or None."""
        for r in self.rows:
            if math.isclose(r.load_N, load_N, rel_tol=rtol) and math.isclose(r.pressure_Pa, pressure_Pa, rel_tol=rtol):
                return r
        return None

    def rated_row(self):
        """The row nearest the rated condition (relative distance in load and pressure)."""
        t = self.tire
        return min(self.rows, key=lambda r: abs(r.load_N / t.rated_load_N - 1) + abs(r.pressure_Pa / t.rated_pressure_Pa - 1))

    def to_dict(self) -> dict:
        rows = []
        for r in self.rows:
            d = {"load_N": r.load_N, "pressure_Pa": r.pressure_Pa}
            d |= {k: v for k, v in r.q.items() if v is not None}
            if r.curves is not None:
                d["E10_curves"] = r.curves.to_dict()
            if r.slip_curves is not None:
                d["E06_curves"] = r.slip_curves.to_dict()
            rows.append(d)
        quantities = {q.key: {"symbol": q.symbol, "unit": q.unit, "experiment": q.experiment, "meaning": q.meaning}
                      for q in QUANTITIES}
        for q in QUANTITIES:
            if q.damping:
                k2, kf = variant_keys(q)
                quantities[k2] = {"symbol": q.symbol + "_2p", "unit": q.unit, "experiment": q.experiment,
                                  "meaning": q.meaning + ", two-peak log decrement"}
                quantities[kf] = {"symbol": q.symbol + "_fit", "unit": q.unit, "experiment": q.experiment,
                                  "meaning": q.meaning + ", damped-sine fit"}
        return {"format": FORMAT, "version": VERSION, "tire": dataclasses.asdict(self.tire),
                "quantities": quantities, "rows": rows}


def _row_from_dict(d: dict, i: int) -> ConditionRow:
    where = f"characterization rows[{i}]"
    for k in ("load_N", "pressure_Pa"):
        v = d.get(k)
        if not isinstance(v, (int, float)) or not v > 0:
            raise ConfigError(f"{where}.{k} = {v!r}: must be a number > 0")
    known = set(all_keys())
    q = {}
    for k, v in d.items():
        if k in ("load_N", "pressure_Pa", "E10_curves", "E06_curves"):
            continue
        if k not in known:
            continue  # other experiment outputs are carried by result.json, not needed here
        if v is not None and not isinstance(v, (int, float)):
            raise ConfigError(f"{where}.{k} = {v!r}: must be a number or null")
        q[k] = None if v is None else float(v)
    curves = None if d.get("E10_curves") is None else E10Curves.from_dict(d["E10_curves"], f"{where}.E10_curves")
    slip = None if d.get("E06_curves") is None else E06Curves.from_dict(d["E06_curves"], f"{where}.E06_curves")
    return ConditionRow(float(d["load_N"]), float(d["pressure_Pa"]), q, curves, slip)


def characterization_from_dict(d: dict) -> Characterization:
    if d.get("format") != FORMAT:
        raise ConfigError(f"characterization format = {d.get('format')!r}: must be {FORMAT!r}")
    if d.get("version") != VERSION:
        raise ConfigError(f"characterization version = {d.get('version')!r}: this reader knows version {VERSION}")
    rows = d.get("rows")
    if not isinstance(rows, list) or not rows:
        raise ConfigError("characterization rows: must be a non-empty list of condition rows")
    return Characterization(TireInfo.from_dict(d.get("tire") or {}), tuple(_row_from_dict(r, i) for i, r in enumerate(rows)))


def read_characterization(path) -> Characterization:
    """Read characterization.json, or the one inside a folder."""
    p = Path(path)
    if p.is_dir():
        p = p / FILENAME
    if not p.is_file():
        raise ConfigError(f"characterization: no file {p}")
    from ..config import read_text  # the one reader of input files (not UTF-8: one line naming it)

    try:
        d = json.loads(read_text(p, "characterization"))
    except json.JSONDecodeError as e:
        raise ConfigError(f"characterization {p}: not valid JSON ({e.msg}, line {e.lineno})") from None
    return characterization_from_dict(d)


def write_characterization(path, char: Characterization) -> Path:
    p = Path(path)
    if p.suffix != ".json":
        p = p / FILENAME
    return atomic_write_json(p, char.to_dict())


def row_from_results(load_N: float, pressure_Pa: float, results, e10_signals: dict | None = None,
                     e06_signals: dict | None = None, e06_surface: str | None = None) -> ConditionRow:
    """One condition row from experiments' results: `results` is an iterable of result.json dicts
    (or ExperimentResult.to_json_dict()); their "quantities" are merged (known keys only; a later
    result overrides an earlier one, except that a value from the quantity's own experiment, named by
    the result's "study_id" (e.g. k_sv from E02, not E04's rest deflection), is never overridden). e10_signals: the E10 signals dict (its CURVE_KEYS are kept;
    M_z_SAE_Nm may come under aligning_moment_Nm); e06_signals: the E06 signals dict (its
    SLIP_CURVE_KEYS are kept) and e06_surface the surface it ran on."""
    known = set(all_keys())
    source = {k: qq.experiment for qq in QUANTITIES for k in (qq.key, *(variant_keys(qq) if qq.damping else ()))}
    q, from_source = {}, set()
    for res in results:
        mine = res.get("study_id")  # a result of the quantity's own experiment wins over another's
        for k, v in (res.get("quantities") or {}).items():
            if k in known and (v is None or isinstance(v, (int, float))):
                own = mine is not None and source.get(k) == mine
                if k in from_source and not own:
                    continue
                q[k] = None if v is None else float(v)
                if own:
                    from_source.add(k)
    curves = None
    if e10_signals:
        s = dict(e10_signals)
        if "M_z_SAE_Nm" not in s and "aligning_moment_Nm" in s:
            s["M_z_SAE_Nm"] = s["aligning_moment_Nm"]
        curves = E10Curves.from_dict({k: s.get(k) for k in CURVE_KEYS})
    slip = None
    if e06_signals:
        slip = E06Curves.from_dict({k: e06_signals.get(k) for k in SLIP_CURVE_KEYS} | {"surface": e06_surface})
    return ConditionRow(float(load_N), float(pressure_Pa), q, curves, slip)
