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

from pathlib import Path

from .. import results
from ..config import validate_table
from ..errors import ConfigError, SimulationError
from ..io import check_writable


def grid_conditions(raw_sweep: dict, per_pressure: bool = False):
    g = validate_table(raw_sweep or {}, results.GRID_SCHEMA, "sweep")
    return results.grid_conditions(g, "sweep", per_pressure)


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
    names = [results.case_name(i, c) for i, c in enumerate(conditions)]
    cases = results.cases_dir(out)
    todo = [i for i, n in enumerate(names) if not results.is_done(cases / n)]
    if resumed:
        say(f"resuming: {len(conditions) - len(todo)} of {len(conditions)} cases already done in {out}", err=True)
    failures = []
    if todo:
        from ..executor import CaseTask, current

        bar = tqdm(total=len(todo), desc=f"sweep {exp.name}", unit="case")
        tasks = [CaseTask(exp.name, rc.tables[exp.name], rc.solver, rc.tire, conditions[i]) for i in todo]

        def save(k, outcome):
            i = todo[k]
            if isinstance(outcome.result, batch.CaseFailure):
                failures.append(f"{names[i]}: {outcome.result.error}")
                results.save_failure(cases / names[i], outcome.result.error)
            else:
                results.save(cases / names[i], outcome.result)
            bar.update(1)

        current().run(tasks, save, batch_size=args.batch)
        bar.close()
    done = [(n, c, results.read_result(cases / n)) for n, c in zip(names, conditions) if results.is_done(cases / n)]
    results.write_summary(out, [n for n, _, _ in done], [c for _, c, _ in done], [r for _, _, r in done],
                          exp.per_pressure)
    for n, _, r in done:
        say(f"{n}: " + ", ".join(f"{k}={v:.6g}" for k, v in r["quantities"].items() if isinstance(v, (int, float))))
    say(f"summary written to {out / results.SUMMARY}")
    if failures:
        raise SimulationError(f"{len(failures)} of {len(conditions)} cases failed (rerun to retry them): "
                              + "; ".join(failures))
    return 0
