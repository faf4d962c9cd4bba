"""`jtire sweep CONFIG [--out DIR] [--batch N]`: one experiment over the load x pressure grid.

The grid comes from the config's [sweep] table (loads in kg, pressures in psi) or defaults to the
study's 3 x 3 grid. Static experiments run vmapped (`jtire.sweep`), in batches of --batch cases;
others run case by case (each phase compiled once and reused). Every finished case is written to
DIR/cases/<case>/result.json at once, and a rerun with the same DIR skips finished cases, so a
killed sweep resumes without losing work. DIR/summary.csv gathers every case's quantities.
"""

import json
import sys
from pathlib import Path

from tqdm import tqdm

from .. import units as U
from ..config import F, validate_table
from ..errors import ConfigError
from ..io import atomic_write_csv

GRID_SCHEMA = {
    "loads_kg": F(list, U.G0, 1, 50000, [2312.5, 4625.0, 6937.5], "kg"),
    "pressures_psi": F(list, U.PSI, 10, 250, [70.0, 120.0, 150.0], "psi"),
}


def grid_conditions(raw_sweep: dict):
    g = validate_table(raw_sweep or {}, GRID_SCHEMA, "sweep")
    return [{"pressure_Pa": p, "load_N": w} for p in g["pressures_psi"] for w in g["loads_kg"]]


def case_name(c):
    return f"p{c['pressure_Pa'] / U.PSI:.0f}psi_l{c['load_N'] / U.G0:.0f}kg"


def add_arguments(p):
    p.add_argument("config", help="experiment config TOML (its [sweep] table sets the grid)")
    p.add_argument("--out", default="runs/sweep", help="output folder (resumes if it holds finished cases)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    p.add_argument("--batch", type=int, default=9, help="cases per vmapped batch (default 9: the whole grid)")


def run_cli(args, say) -> int:
    from ..config import load_toml
    from ..experiments.phases import Protocol
    from .run import load_run_config, table_lines
    from ..sweep import VMAPPED, run_static_batch
    from ..tire import make_tire

    from ..config import apply_overrides

    raw = apply_overrides(load_toml(args.config), [o for o in args.overrides if o.startswith("sweep.")])
    conditions = grid_conditions(raw.pop("sweep", {}))
    spec, exps, base_condition, proto = load_run_config(args.config, [o for o in args.overrides if not o.startswith("sweep.")])
    if len(exps) != 1:
        raise ConfigError("sweep: the config must name exactly one experiment")
    exp, table = exps[0]
    if args.batch < 1:
        raise ConfigError(f"--batch {args.batch}: must be >= 1")
    tire = make_tire(spec)
    protocol = Protocol.from_dict(proto)
    out = Path(args.out)
    todo = [c for c in conditions if not (out / "cases" / case_name(c) / "result.json").exists()]
    if len(todo) < len(conditions):
        say(f"resuming: {len(conditions) - len(todo)} of {len(conditions)} cases already done in {out}", err=True)
    bar = tqdm(total=len(todo), desc=f"sweep {exp.name}", unit="case", err=True)
    while todo:
        chunk = todo[: args.batch] if exp.name in VMAPPED else todo[:1]
        todo = todo[len(chunk):]
        if exp.name in VMAPPED:
            results = run_static_batch(tire, chunk, protocol, exp.name, table)
        else:
            results = [exp.runner(tire, dict(c), protocol, **table) for c in chunk]
        for c, res in zip(chunk, results):
            res.write(out / "cases" / case_name(c))
            bar.update(1)
    bar.close()
    rows, keys = [], []
    for c in conditions:
        d = json.loads((out / "cases" / case_name(c) / "result.json").read_text())
        q = {k: v for k, v in d["quantities"].items() if isinstance(v, (int, float)) or v is None}
        keys += [k for k in q if k not in keys]
        rows.append((c, q))
    header = ["pressure_Pa", "load_N"] + keys
    atomic_write_csv(out / "summary.csv", header, [[c["pressure_Pa"], c["load_N"]] + [q.get(k) for k in keys] for c, q in rows])
    for c, q in rows:
        say(f"{case_name(c)}: " + ", ".join(f"{k}={v:.6g}" for k, v in q.items() if isinstance(v, (int, float))))
    say(f"summary written to {out / 'summary.csv'}")
    return 0
