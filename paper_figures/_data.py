"""Data for the chapter 5-6 figures: the cases of one experiment, read from a results folder or run.

Folder layouts read (what `jtire characterize` and `jtire sweep` write):
    DIR/<experiment>/cases/<NNN>_p<psi>psi[_l<kg>kg]/result.json, signals.csv   (characterization)
    DIR/cases/<NNN>_p<psi>psi[_l<kg>kg]/...                                       (a plain sweep)
result.json holds {experiment, condition {pressure_Pa, load_N}, quantities, checks, info}; signals.csv
the recorded series (header = names). Any other *.csv in a case folder (e.g. E01's
contact_pressure.csv) is read into `Case.tables`.

Without a folder, `run_cases` runs the experiment through the public API (`load_run_config` on the
shipped experiment config, `jtire.batch.run` over the conditions) and can write the same layout
(`out_root`), so one run serves several figures. No physics here: only loading, selecting, running.
"""

import csv
import dataclasses
from pathlib import Path

import numpy as np

from jtire import results
from jtire import units as U
from jtire.errors import ConfigError, SimulationError

RATED_PSI, RATED_KG = 120.0, 4625.0
LOADS_KG = (2312.5, 4625.0, 6937.5)
PRESSURES_PSI = (70.0, 120.0, 150.0)
QUICK_LOADS_KG = (2312.5, 6937.5)
QUICK_PRESSURES_PSI = (70.0, 150.0)

# --quick: the coarse ring and short durations through the experiments' own config fields
QUICK_MESH = ("tire.mesh.n_theta=32", "tire.mesh.n_crown=4", "solver.load_ramp_s=0.05", "solver.settle_max_s=0.3")
QUICK_SETTINGS = {
    "footprint": (),
    "vertical_stiffness": ("vertical_stiffness.ramp_s=0.15",),
    "drum_cleat": ("drum_cleat.roll_settle_s=0.01", "drum_cleat.record_s=0.06",
                   "drum_cleat.enveloping_range_mm=0"),  # the axle-force figure has no use for the crossing
    "drop_test": ("drop_test.duration_s=0.12",),
    "inplane_rotation": ("inplane_rotation.decay_s=0.06",),
    "traction": (),
    "sidewall_translation": ("sidewall_translation.decay_s=0.06",),
    "sidewall_camber": ("sidewall_camber.decay_s=0.06",),
    "lateral_stiffness": ("lateral_stiffness.decay_s=0.08",),
    "cornering": ("cornering.slip_angles_deg=[0,1,2,4]", "cornering.settle_s=0.03", "cornering.ramp_s=0.01",
                  "cornering.release_s=0.005", "cornering.measure_s=0.01"),
}
# settings every run of a figure needs, quick or not
FIGURE_SETTINGS = {"lateral_stiffness": ("lateral_stiffness.decay_s=0.3",)}


@dataclasses.dataclass
class Case:
    """One condition's result. condition: SI (pressure_Pa, load_N when the load enters)."""

    name: str
    experiment: str
    condition: dict
    quantities: dict
    checks: dict = dataclasses.field(default_factory=dict)
    info: dict = dataclasses.field(default_factory=dict)
    signals: dict = dataclasses.field(default_factory=dict)
    tables: dict = dataclasses.field(default_factory=dict)

    @property
    def pressure_psi(self) -> float:
        return self.condition["pressure_Pa"] / U.PSI

    @property
    def load_kg(self):
        return self.condition["load_N"] / U.G0 if "load_N" in self.condition else None


# ---- reading ---------------------------------------------------------------------------------
def read_columns(path) -> dict:
    """A CSV with a header row -> {name: float array}."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    head, body = rows[0], rows[1:]

    def num(v):
        try:
            return float(v)
        except ValueError:
            return np.nan

    return {h: np.array([num(r[k]) for r in body if len(r) > k]) for k, h in enumerate(head)}


def _experiment_of(case_dir: Path):
    d = results.read_result(case_dir)
    return None if d is None else d.get("experiment")


def experiment_dir(root, experiment: str) -> Path:
    """The folder holding `cases/` for `experiment` under root (either layout)."""
    root = Path(root)
    if not root.is_dir():
        raise ConfigError(f"--from {root}: no such folder")
    if results.cases_dir(root, experiment).is_dir():
        return root / experiment
    if results.cases_dir(root).is_dir() and any(_experiment_of(d) == experiment for d in results.cases_dir(root).iterdir()):
        return root
    have = sorted(d.name for d in root.iterdir() if results.cases_dir(d).is_dir())
    raise ConfigError(f"--from {root}: no results of {experiment} (expected {results.cases_dir(root, experiment)}"
                      + (f"; found {', '.join(have)}" if have else "") + ")")


def load_case(folder: Path) -> Case:
    d = results.read_result(folder)
    tables = {p.stem: read_columns(p) for p in sorted(folder.glob("*.csv")) if p.name != results.SIGNALS}
    sig = read_columns(folder / results.SIGNALS) if (folder / results.SIGNALS).is_file() else {}
    return Case(folder.name, d["experiment"], d["condition"], d["quantities"], d.get("checks", {}), d.get("info", {}),
                sig, tables)


def load_cases(root, experiment: str) -> list:
    """Every finished case of `experiment` under root (cases with only error.txt are skipped)."""
    base = results.cases_dir(experiment_dir(root, experiment))
    cases = [load_case(d) for d in sorted(base.iterdir()) if results.is_done(d)]
    cases = [c for c in cases if c.experiment == experiment]
    if not cases:
        raise ConfigError(f"{base}: no finished cases of {experiment}")
    return cases


# ---- choosing conditions ------------------------------------------------------------------------
def conditions(kind: str, quick: bool) -> list:
    """The conditions a figure plots (SI): "loads" (three loads at 120 psi), "pressures" (three
    pressures at 4625 kg), "per_pressure" (pressures only: the load does not enter), "grid" (3 x 3).
    quick: two of them (the extremes; the grid: the two loads at 120 psi)."""
    loads = QUICK_LOADS_KG if quick else LOADS_KG
    pressures = QUICK_PRESSURES_PSI if quick else PRESSURES_PSI
    if kind == "loads" or (kind == "grid" and quick):
        return [{"pressure_Pa": RATED_PSI * U.PSI, "load_N": w * U.G0} for w in loads]
    if kind == "pressures":
        return [{"pressure_Pa": p * U.PSI, "load_N": RATED_KG * U.G0} for p in pressures]
    if kind == "per_pressure":
        return [{"pressure_Pa": p * U.PSI} for p in pressures]
    if kind == "grid":
        return [{"pressure_Pa": p * U.PSI, "load_N": w * U.G0} for p in pressures for w in loads]
    raise ValueError(f"unknown condition kind {kind!r}")


def select(cases: list, kind: str) -> list:
    """The cases of a results folder that a figure of this kind plots: "loads": every load at the
    pressure nearest 120 psi; "pressures": every pressure at the load nearest 4625 kg (all cases
    when the load does not enter); "per_pressure": one case per pressure; "grid": all. Sorted."""
    if kind == "loads":
        p = min({c.pressure_psi for c in cases}, key=lambda v: abs(v - RATED_PSI))
        out = [c for c in cases if abs(c.pressure_psi - p) < 1e-6]
        return sorted(out, key=lambda c: c.load_kg or 0.0)
    if kind in ("pressures", "per_pressure"):
        loads = {c.load_kg for c in cases if c.load_kg is not None}
        if loads:
            w = min(loads, key=lambda v: abs(v - RATED_KG))
            cases = [c for c in cases if c.load_kg is not None and abs(c.load_kg - w) < 1e-6]
        one = {}
        for c in cases:
            one.setdefault(round(c.pressure_psi, 6), c)
        return [one[k] for k in sorted(one)]
    if kind == "grid":
        return sorted(cases, key=lambda c: (c.pressure_psi, c.load_kg or 0.0))
    raise ValueError(f"unknown condition kind {kind!r}")


# ---- running -----------------------------------------------------------------------------------
def config_file(experiment: str) -> Path:
    from jtire.resources import config_path

    return config_path("experiments", f"{experiment}.toml")


def overrides_for(experiment: str, quick: bool, extra=()) -> list:
    return list(FIGURE_SETTINGS.get(experiment, ())) + (list(QUICK_MESH) + list(QUICK_SETTINGS.get(experiment, ()))
                                                         if quick else []) + list(extra)


def run_cases(experiment: str, conds: list, quick: bool = False, extra=(), out_root=None) -> list:
    """Run `experiment` at `conds` (SI dicts) through `jtire.batch.run`; returns Cases. With
    out_root, also writes out_root/<experiment>/cases/... (the characterization layout) and a
    summary.csv. E01 keeps its loaded states and adds the contact-pressure table of each case."""
    from jtire import batch
    from jtire.config import load_run_config
    from jtire.tire import make_tire

    rc = load_run_config(config_file(experiment), overrides_for(experiment, quick, extra))
    exp = rc.experiments[0]
    if exp.per_pressure:
        conds = [{"pressure_Pa": c["pressure_Pa"]} for c in conds]
    tire = make_tire(rc.tire)
    footprint = experiment == "footprint"
    ran = batch.run(exp, tire, conds, keep_outputs=footprint)
    failed = [f"{c}: {r.error}" for c, r in zip(conds, ran) if isinstance(r, batch.CaseFailure)]
    if failed:
        raise SimulationError(f"{experiment}: {len(failed)} of {len(conds)} cases failed: " + "; ".join(failed))
    cases = []
    for i, (c, r) in enumerate(zip(conds, ran)):
        tables = {}
        if footprint:
            from jtire.contact_pressure import footprint_table

            out = r.outputs[0]
            tables["contact_pressure"] = footprint_table(tire.model, tire.params, out["y"], float(out["z_road"]))
        case = Case(results.case_name(i, c), r.experiment, dict(r.condition), dict(r.quantities), dict(r.checks),
                    dict(r.info), {k: np.asarray(v) for k, v in r.signals.items()}, tables)
        if out_root is not None:
            results.save(results.cases_dir(out_root, experiment) / case.name, r, tables)
        cases.append(case)
    if out_root is not None:
        results.write_summary(Path(out_root) / experiment, [c.name for c in cases], [c.condition for c in cases],
                              [{"quantities": c.quantities} for c in cases], exp.per_pressure)
    return cases


def obtain(experiment: str, kind: str, args, extra=()):
    """(cases, source text) for a figure: from args.from_dir if given, else simulated now."""
    if args.from_dir:
        return select(load_cases(args.from_dir, experiment), kind), f"results read from {args.from_dir}"
    from jtire import cache

    cache.enable()
    cases = run_cases(experiment, conditions(kind, args.quick), args.quick, extra)
    what = "QUICK CHECK: coarse ring (32 x 4), short runs" if args.quick else "default mesh and config"
    return cases, f"simulated now with jtire.batch.run ({experiment}, {what})"
