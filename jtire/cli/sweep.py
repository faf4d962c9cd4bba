"""`jtire sweep CONFIG [--out DIR] [--batch N]`: one experiment over a load x pressure grid.

The grid comes from the config's [sweep] table (loads in kg, pressures in psi) or defaults to the
study's 3 x 3 grid (experiments where the load does not enter, E05/E07/E08, run once per pressure).
All cases run through the batch runner (`jtire.batch`) in batches of --batch cases: by default one,
each case on its own and the cases side by side, one per device, so each is saved (and counted by the
progress bar) the moment it finishes and a kill loses at most the cases in flight; a larger batch is
vmapped and sharded over the devices (0: the whole grid). Every finished case is written to
DIR/cases/<case>/result.json at once; DIR/settings.json holds everything that determines the numbers,
so a rerun into DIR resumes (finished cases are not recomputed) only with the same settings and
refuses otherwise. DIR/summary.csv gathers every case's quantities.
"""

import json
from pathlib import Path

from .. import units as U
from ..config import validate_table
from ..errors import ConfigError, SimulationError
from ..io import atomic_write_csv, atomic_write_text, check_writable
from ..schema import Field

GRID_SCHEMA = {
    "loads_kg": Field(list, U.G0, 50, 50000, [2312.5, 4625.0, 6937.5], "kg"),
    "pressures_psi": Field(list, U.PSI, 10, 250, [70.0, 120.0, 150.0], "psi"),
}


def grid_conditions(raw_sweep: dict, per_pressure: bool = False):
    g = validate_table(raw_sweep or {}, GRID_SCHEMA, "sweep")
    for key in ("loads_kg", "pressures_psi"):
        vals = g[key]
        if len(set(vals)) != len(vals):
            raise ConfigError(f"sweep.{key}: lists a value twice")
    if per_pressure:
        return [{"pressure_Pa": p} for p in g["pressures_psi"]]
    return [{"pressure_Pa": p, "load_N": w} for p in g["pressures_psi"] for w in g["loads_kg"]]


def case_name(i: int, c: dict) -> str:
    """Unique (the index comes first) and readable: 003_p120psi_l4625kg."""
    name = f"{i:03d}_p{c['pressure_Pa'] / U.PSI:.4g}psi"
    if "load_N" in c:
        name += f"_l{c['load_N'] / U.G0:.6g}kg"
    return name


def add_arguments(p):
    p.add_argument("config", help="experiment config TOML (its [sweep] table sets the grid)")
    p.add_argument("--out", default="runs/sweep", help="output folder (resumes if it holds finished cases of the same settings)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--batch", type=int, default=1, help="cases per batch (default 1: case by case, side by side over "
                                                        "the devices, each saved as it finishes; 0: the whole grid at once)")


def settings(rc, exp, conditions) -> dict:
    from ..fingerprint import code_version

    return {"experiment": exp.name, "table": exp, "tire": rc.tire, "solver": rc.solver, "conditions": conditions,
            "jtire": code_version()}


def run_cli(args, say) -> int:
    from tqdm import tqdm

    from .. import batch
    from ..config import load_run_config
    from ..fingerprint import claim_folder
    from ..tire import make_tire

    rc = load_run_config(args.config, args.overrides)
    if len(rc.experiments) != 1:
        raise ConfigError("sweep: the config must name exactly one experiment")
    exp = rc.experiments[0]
    if args.batch < 0:
        raise ConfigError(f"--batch {args.batch}: must be >= 0 (1: case by case, 0: the whole grid in one batch)")
    conditions = grid_conditions(rc.sweep, exp.per_pressure)
    for c in conditions:
        if hasattr(exp, "check_condition"):
            exp.check_condition(c)
    out = Path(args.out)
    check_writable(out)
    resumed = claim_folder(out, settings(rc, exp, conditions))
    names = [case_name(i, c) for i, c in enumerate(conditions)]
    todo = [i for i, n in enumerate(names) if not (out / "cases" / n / "result.json").exists()]
    if resumed:
        say(f"resuming: {len(conditions) - len(todo)} of {len(conditions)} cases already done in {out}", err=True)
    failures = []
    if todo:
        tire = make_tire(rc.tire)
        bar = tqdm(total=len(todo), desc=f"sweep {exp.name}", unit="case")

        def save(k, res):
            i = todo[k]
            folder = out / "cases" / names[i]
            if isinstance(res, batch.CaseFailure):
                failures.append(f"{names[i]}: {res.error}")
                atomic_write_text(folder / "error.txt", f"{res.error}\n")
            else:
                res.write(folder)
                (folder / "error.txt").unlink(missing_ok=True)
            bar.update(1)

        batch.run(exp, tire, [conditions[i] for i in todo], batch=args.batch, on_result=save)
        bar.close()
    rows, keys = [], []
    for i, c in enumerate(conditions):
        f = out / "cases" / names[i] / "result.json"
        if not f.exists():
            continue
        d = json.loads(f.read_text())
        q = {k: v for k, v in d["quantities"].items() if isinstance(v, (int, float)) or v is None}
        keys += [k for k in q if k not in keys]
        rows.append((names[i], c, q))
    cols = ["case", "pressure_Pa"] + (["load_N"] if not exp.per_pressure else [])
    atomic_write_csv(out / "summary.csv", cols + keys,
                     [[n] + [c[k] for k in cols[1:]] + [q.get(k) for k in keys] for n, c, q in rows])
    for n, c, q in rows:
        say(f"{n}: " + ", ".join(f"{k}={v:.6g}" for k, v in q.items() if isinstance(v, (int, float))))
    say(f"summary written to {out / 'summary.csv'}")
    if failures:
        raise SimulationError(f"{len(failures)} of {len(conditions)} cases failed (rerun to retry them): "
                              + "; ".join(failures))
    return 0
