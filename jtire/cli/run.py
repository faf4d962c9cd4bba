"""`jtire run [CONFIG] [--set key=value ...] [--out DIR]`: run virtual experiments from a config.

An experiment config names one experiment (`experiment = "..."`) or several
(`experiments = [...]`), the tire file, the condition and optional solver and per-experiment
tables. Without CONFIG the default config runs: the static experiments at the rated condition.
`--set` overrides any field before validation: `condition.pressure_psi=70` for the experiment
file, `tire.<section>.<key>=...` for the tire file (e.g. `tire.mesh.n_theta=48`).
"""

import math
from pathlib import Path

from ..config import apply_overrides, load_toml, parse_condition, parse_solver, tire_from_dict, validate_table
from ..errors import ConfigError
from ..io import atomic_write_csv

TOP_KEYS = {"experiment", "experiments", "tire_file", "condition", "solver", "description", "sweep"}


def load_run_config(path, overrides=()):
    """Parse an experiment config (+ overrides) -> (tire spec, [(Experiment, table)], condition, protocol dict)."""
    from ..experiments.registry import REGISTRY

    path = Path(path)
    raw = load_toml(path)
    tire_over = [o[len("tire."):] for o in overrides if o.startswith("tire.")]
    apply_overrides(raw, [o for o in overrides if not o.startswith("tire.")])
    names = raw.get("experiments", [raw["experiment"]] if "experiment" in raw else None)
    if not names or not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise ConfigError(f"{path.name}: needs experiment = NAME or experiments = [NAMES] (known: {', '.join(REGISTRY)})")
    for n in names:
        if n not in REGISTRY:
            raise ConfigError(f"experiment = {n!r}: unknown (known: {', '.join(REGISTRY)})")
    for key in raw:
        if key not in TOP_KEYS and key not in REGISTRY:
            raise ConfigError(f"{key}: unknown field (allowed: {', '.join(sorted(TOP_KEYS))} and experiment tables)")
    if "tire_file" not in raw or not isinstance(raw["tire_file"], str):
        raise ConfigError("tire_file: missing (path of the tire TOML, relative to this config)")
    tire_raw = load_toml((path.parent / raw["tire_file"]).resolve())
    tire = tire_from_dict(apply_overrides(tire_raw, tire_over))
    exps = [(REGISTRY[n], validate_table(raw.get(n, {}), REGISTRY[n].schema, n)) for n in names]
    condition = parse_condition(raw.get("condition", {}), need_load=any(e.needs_load for e, _ in exps))
    proto = parse_solver(raw.get("solver", {}))
    return tire, exps, condition, proto


def run_config(path, overrides=(), progress=None):
    """Run every experiment of a config; returns the list of ExperimentResults."""
    from ..experiments.phases import Protocol
    from ..tire import make_tire

    spec, exps, condition, proto = load_run_config(path, overrides)
    tire = make_tire(spec)
    protocol = Protocol.from_dict(proto)
    results = []
    for exp, table in exps:
        if progress:
            progress(exp.name)
        res = exp.runner(tire, dict(condition), protocol, **table)
        res.info["config"] = str(path)
        results.append(res)
    return results


def _fmt(v):
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (int, float)):
        return "nan" if (isinstance(v, float) and math.isnan(v)) else f"{v:.6g}"
    return str(v)


def table_lines(res) -> list:
    c = res.condition
    head = f"{res.experiment}: pressure {c.get('pressure_Pa', float('nan')) / 1e3:.1f} kPa"
    if "load_N" in c:
        head += f", load {c['load_N'] / 1e3:.3f} kN"
    lines = [head]
    w = max(len(k) for k in res.quantities) if res.quantities else 10
    for k, v in res.quantities.items():
        lines.append(f"  {k:<{w}}  {_fmt(v)}")
    settled = all(v for k, v in res.checks.items() if k.endswith("_settled"))
    lines.append(f"  {'settled':<{w}}  {settled}   (dt {res.info.get('dt_s', float('nan')):.3g} s, "
                 f"{res.info.get('steps', 0)} steps, {res.info.get('wall_s_including_compile', 0):.1f} s wall incl. compile)")
    return lines


def add_arguments(p):
    p.add_argument("config", nargs="?", default=None,
                   help="experiment config TOML (default: configs/default.toml, the static experiments at rated load and pressure)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config field, e.g. condition.pressure_psi=70 or tire.mesh.n_theta=48")
    p.add_argument("--out", default=None, help="write DIR/result.json and DIR/signals.csv (DIR/<experiment>/ for several)")


def run_cli(args, say) -> int:

    from ..resources import config_path

    results = run_config(args.config or config_path("default.toml"), args.overrides, progress=lambda n: say(f"running {n} ...", err=True))
    for res in results:
        say("\n".join(table_lines(res)))
    if args.out:
        out = Path(args.out)
        if len(results) == 1:
            results[0].write(out)
        else:
            rows = []
            for res in results:
                res.write(out / res.experiment)
                rows += [(res.experiment, k, v) for k, v in res.quantities.items()]
            atomic_write_csv(out / "summary.csv", ["experiment", "quantity", "value"], rows)
        say(f"results written to {out}/")
    return 0
