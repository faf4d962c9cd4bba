"""The results folder, defined once: the load x pressure grid, the rated condition, the name and the
files of a case, and how a case is saved and read back.

    DIR/cases/<case>/                 a sweep (`jtire sweep`), the validation's slip steps
    DIR/<experiment>/cases/<case>/    a characterization (`jtire characterize`), the figures' data

A case folder holds signals.csv and any extra tables (e.g. contact_pressure.csv), then result.json,
written last: result.json marks the case done, so a kill between them redoes the case on resume. A
failed case holds error.txt instead. Every writer and reader of these folders goes through here.
"""

import csv
import json
from pathlib import Path

import numpy as np

from . import units as U
from .errors import ConfigError
from .io import atomic_write_csv, atomic_write_text
from .schema import Field

RESULT, SIGNALS, ERROR, SUMMARY = "result.json", "signals.csv", "error.txt", "summary.csv"

# the study's rated condition (4625 kg, 120 psi): the default of a characterization's rated point and
# where the calibration's sensitivities are taken
RATED = {"load_N": 4625.0 * U.G0, "pressure_Pa": 120.0 * U.PSI}

# the study's 3 x 3 grid by default
GRID_SCHEMA = {
    "loads_kg": Field(list, U.G0, 50, 50000, [2312.5, 4625.0, 6937.5], "kg"),
    "pressures_psi": Field(list, U.PSI, 10, 250, [70.0, 120.0, 150.0], "psi"),
}
RATED_SCHEMA = {
    "rated_load_kg": Field(float, U.G0, 50, 50000, RATED["load_N"] / U.G0, "kg"),
    "rated_pressure_psi": Field(float, U.PSI, 10, 250, RATED["pressure_Pa"] / U.PSI, "psi"),
}


def grid_conditions(g: dict, where: str, per_pressure: bool = False) -> list:
    """The conditions (SI dicts) of a validated grid table `g` (GRID_SCHEMA): every pressure x every
    load, pressure major; per_pressure: one per pressure (experiments where the load does not enter)."""
    for key in GRID_SCHEMA:
        if len(set(g[key])) != len(g[key]):
            raise ConfigError(f"{where}.{key}: lists a value twice")
    if per_pressure:
        return [{"pressure_Pa": p} for p in g["pressures_psi"]]
    return [{"pressure_Pa": p, "load_N": w} for p in g["pressures_psi"] for w in g["loads_kg"]]


def case_name(i: int, c: dict) -> str:
    """Unique (the index comes first) and readable: 003_p120psi_l4625kg."""
    name = f"{i:03d}_p{c['pressure_Pa'] / U.PSI:.4g}psi"
    if "load_N" in c:
        name += f"_l{c['load_N'] / U.G0:.6g}kg"
    return name


def steady_reference_folder(speed) -> str:
    """DIR/validation/<this>: the validation's steady references at a slip step's speed (m/s), one
    subfolder load_levels_<n> per try (`validate.steady_references`)."""
    return f"steady_{speed:g}_m_s"


# DIR/<this>/<case> of a characterization: E09's push on the rubber's storage moduli at E09's release
# frequency (`validate.storage_pushes`), one folder per condition: the ring's lateral springs
LATERAL_STORAGE = "lateral_storage"


def cases_dir(root, experiment: str | None = None) -> Path:
    """DIR/cases (a sweep) or DIR/<experiment>/cases (a characterization)."""
    return Path(root) / "cases" if experiment is None else Path(root) / experiment / "cases"


def is_done(case) -> bool:
    return (Path(case) / RESULT).exists()


def save(case, result, tables: dict | None = None) -> None:
    """A finished case: its extra tables ({name: {column: array}}, as name.csv), then signals.csv and
    result.json (`ExperimentResult.write`); a stale error.txt of an earlier try goes."""
    case = Path(case)
    for name, cols in (tables or {}).items():
        atomic_write_csv(case / f"{name}.csv", None, {k: np.asarray(v) for k, v in cols.items()})
    result.write(case)
    (case / ERROR).unlink(missing_ok=True)


def save_failure(case, error) -> None:
    atomic_write_text(Path(case) / ERROR, f"{error}\n")


def read_result(case) -> dict | None:
    """result.json of a case as a dict, or None when the case is not done."""
    f = Path(case) / RESULT
    return json.loads(f.read_text()) if f.exists() else None


def read_error(case) -> str | None:
    f = Path(case) / ERROR
    return f.read_text().strip() if f.exists() else None


def read_signals(case) -> dict | None:
    """signals.csv of a case as {column: array} (empty cells: nan), or None when it has none."""
    p = Path(case) / SIGNALS
    if not p.exists():
        return None
    with p.open() as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        return None
    return {k: np.array([float(r[k]) if r[k] not in ("", "None") else np.nan for r in rows]) for k in rows[0]}


def find_case(cases_root, load_N, pressure_Pa) -> Path | None:
    """The finished case folder under cases_root at a condition (a per-pressure case matches any
    load), or None."""
    for d in sorted(Path(cases_root).glob("*")):
        res = read_result(d)
        if res is None:
            continue
        c = res.get("condition", {})
        if abs(c.get("pressure_Pa", -1) - pressure_Pa) < 1e-3 and ("load_N" not in c or abs(c["load_N"] - load_N) < 1e-6):
            return d
    return None


def write_summary(folder, names, conds, found, per_pressure: bool) -> Path:
    """DIR/summary.csv: one row per case (result dicts, None for a failed one), its condition and its
    numeric quantities."""
    keys, rows = [], []
    for n, c, r in zip(names, conds, found):
        q = {} if r is None else {k: v for k, v in r["quantities"].items() if isinstance(v, (int, float)) or v is None}
        keys += [k for k in q if k not in keys]
        rows.append((n, c, q))
    cols = ["case", "pressure_Pa"] + ([] if per_pressure else ["load_N"])
    return atomic_write_csv(Path(folder) / SUMMARY, cols + keys,
                            [[n] + [c.get(k) for k in cols[1:]] + [q.get(k) for k in keys] for n, c, q in rows])
