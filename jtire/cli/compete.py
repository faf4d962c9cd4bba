"""`jtire compete`: ARSM vs GA vs Monte Carlo on the soil-block simulation (the work is
`jtire.calibration.soil.competition`)."""

from pathlib import Path

from ..calibration.soil.competition import (QUICK_BUDGET, QUICK_SEEDS, CompetitionSpec, fingerprint, load_config,
                                       run_competition, soil_objective, standin_objective)
from ..calibration.soil.report import format_table, write_outputs


def add_arguments(parser):
    parser.add_argument("config", metavar="CONFIG", help="competition TOML, e.g. "
                        "configs/calibration/soil_competition.toml")
    parser.add_argument("--out", default="runs/compete", help="output folder (resumes from it)")
    parser.add_argument("--seeds", type=int, default=None, help="seeds per method (config: 20)")
    parser.add_argument("--budget", type=int, default=None, help="calls per run (config: 50)")
    parser.add_argument("--quick", action="store_true",
                        help=f"{QUICK_SEEDS} seeds, {QUICK_BUDGET} calls (a smoke run)")
    parser.add_argument("--methods", default=None,
                        help="comma-separated subset, e.g. arsm,ga (config: all it lists)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config field, e.g. --set soil.pressure_Pa=80000 (repeatable)")
    parser.add_argument("--objective", choices=("soil", "standin"), default="soil",
                        help="soil: the finite-element plate test (default); standin: a "
                        "closed-form stand-in for quick checks, not physics")


def run_cli(args, say) -> int:
    from ..config import apply_overrides
    from ..errors import ConfigError
    from ..io import check_writable

    cfg = apply_overrides(load_config(args.config), args.set)
    comp = cfg.get("competition", {})
    if not isinstance(comp, dict):
        raise ConfigError("competition: must be a table")
    comp = dict(comp)
    if args.quick:
        comp.update(seeds=QUICK_SEEDS, budget=QUICK_BUDGET)
    for flag, value, lo, hi in (("--seeds", args.seeds, 1, 10000), ("--budget", args.budget, 5, 100000)):
        if value is not None and not lo <= value <= hi:
            raise ConfigError(f"{flag} {value}: must be in [{lo}, {hi}]")
    if args.seeds is not None:
        comp["seeds"] = args.seeds
    if args.budget is not None:
        comp["budget"] = args.budget
    if args.methods is not None:
        comp["methods"] = [m.strip() for m in args.methods.split(",") if m.strip()]
        if not comp["methods"]:
            raise ConfigError(f"--methods {args.methods!r}: name at least one method, e.g. arsm,ga")
    spec = CompetitionSpec.from_config({**cfg, "competition": comp})
    objective = (soil_objective if args.objective == "soil" else standin_objective)(cfg)
    out = Path(args.out) / args.objective
    check_writable(out)
    results = run_competition(objective, spec, out, fingerprint=fingerprint(cfg, args.objective))
    what = ("soil plate test (FE)" if args.objective == "soil"
            else "CLOSED-FORM STAND-IN objective, not the soil FE model")
    title = (f"Optimizer competition, sinkage error: {what}\n{spec.seeds} seeds x "
             f"{spec.budget} calls; median and quartiles; stars: the study's single runs")
    paths = write_outputs(results, spec, out, title)
    say(format_table(paths["summary"], spec))
    say(f"wrote {paths['runs_csv']}, {paths['summary_csv']}, {paths['figure']}")
    return 0
