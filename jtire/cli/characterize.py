"""`jtire characterize [CONFIG] [--tire TIRE.toml] [--out DIR]`: every experiment over the load x pressure
grid, into the rigid-ring tables, trend verdicts, a Magic Formula fit and an MF-Swift `.tir` (the work is
`jtire.characterize` and `jtire.rigid_ring`). A killed run resumes from DIR; other settings refuse."""

from pathlib import Path


def add_arguments(p):
    p.add_argument("config", nargs="?", default=None,
                   help="characterization TOML (default: the shipped configs/characterize.toml, the study's grid)")
    p.add_argument("--tire", default=None, help="tire TOML to characterize (default: the config's tire_file), e.g. "
                                                "a calibrated tire from `jtire calibrate`")
    p.add_argument("--out", default="runs/characterize", help="output folder (resumes a run with the same settings)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a field, e.g. grid.pressures_psi=[120] or tire.mesh.n_theta=48")
    p.add_argument("--batch", type=int, default=1, help="cases per batch (default 1: case by case, side by side over "
                                                        "the devices, each saved as it finishes; 0: an experiment's "
                                                        "whole grid at once)")
    p.add_argument("--no-validate", action="store_true",
                   help="skip the rigid-ring validation against the shell model (drop, drum-cleat, lateral release, "
                        "slip step at three grid conditions)")


def run_cli(args, say) -> int:
    import time

    from tqdm import tqdm

    from .. import characterize as ch
    from .. import units as U
    from ..errors import CasesFailed, ConfigError
    from ..resources import config_path
    from ..rigid_ring.export import export
    from ..rigid_ring.table import write_characterization

    if args.batch < 0:
        raise ConfigError(f"--batch {args.batch}: must be >= 0 (1: case by case, 0: an experiment's whole grid in one "
                          f"batch)")
    plan = ch.load_plan(args.config or config_path("characterize.toml"), args.tire, args.overrides)
    out = Path(args.out)
    total, done = ch.total_cases(plan, out if out.exists() else None)
    if done:
        say(f"resuming: {done} of {total} cases already done in {out}", err=True)
    failures, walls = [], {}
    bars = []  # the progress bar starts with the first finished case: an error found before any
    # case (an unwritable or foreign --out) is then the only line on stderr

    def progress(n):
        if not bars:
            bars.append(tqdm(total=total, initial=done, desc="characterize", unit="case"))
        bars[0].update(n)

    def on_case(name, cond, err):
        if err is not None:
            failures.append(f"{name}: {err}")

    t0 = time.perf_counter()
    results = ch.run(plan, out, batch_size=args.batch, progress=progress, on_case=on_case)
    for bar in bars:
        bar.close()
    for line in ch.case_notes(results):  # cases rerun on a finer ring, sweeps that stopped: which and why
        say(line)
    storage_bars = {}
    try:
        on = _stage_bar(storage_bars, "lateral springs (storage moduli)")
        pushes = ch.lateral_springs(plan, out, results, on_case=on)
    finally:
        for bar in storage_bars.values():
            bar.close()
    failures += [f"lateral_storage at {c['load_N'] / U.G0:g} kg, {c['pressure_Pa'] / U.PSI:g} psi: {r}"
                 for c, r in zip(plan.conditions, pushes) if isinstance(r, str)]
    walls["total_s"] = time.perf_counter() - t0
    char = ch.characterization(plan, out, results)
    write_characterization(out, char)
    written, lines = export(char, out, tir_name="tire.tir", source=str(plan.path.name))
    for line in lines:
        say(line)
    if not args.no_validate:
        shown, failed = _validate(plan, out, say)
        written += shown
        failures += failed
    say(f"wrote {out / 'characterization.json'}, {', '.join(p.name for p in written)} in {out} "
        f"({walls['total_s']:.0f} s)")
    if failures:
        raise CasesFailed(failures)
    return 0


def _stage_bar(bars: dict, desc: str):
    """on_case(name, n_done, n_total) of a resumable stage: a progress bar `desc`, kept in `bars` (the caller
    closes them), made at the first call (one step per condition, and speed for the steady references)."""
    from tqdm import tqdm

    def update(name, n_done, n_total):
        if desc not in bars:
            bars[desc] = tqdm(total=n_total, initial=n_done, desc=desc, unit="case")
        else:
            bars[desc].update(n_done - bars[desc].n)
    return update


def _validate(plan, out, say) -> tuple:
    """The rigid ring against the shell model at three grid conditions: table and figure. Returns
    (files written, failed shell runs as "validation/<condition>: error" lines)."""

    from .. import units as U
    from ..io import atomic_write_text
    from ..rigid_ring import validation
    from ..validate import DEFAULT_CONDITIONS, validate

    grid = {(round(c["load_N"] / U.G0, 6), round(c["pressure_Pa"] / U.PSI, 6)) for c in plan.conditions}
    conds = [c for c in DEFAULT_CONDITIONS if c in grid] or [sorted(grid)[0]]
    from ..rigid_ring.diagnosis import diagnose
    from ..rigid_ring.table import read_characterization

    bars = {}
    try:
        res = validate(out, plan, conds, on_case=_stage_bar(bars, "validation slip steps"),
                       on_steady=_stage_bar(bars, "validation steady references"))
    finally:
        for bar in bars.values():
            bar.close()
    char = read_characterization(out)
    text, written, failed = ["## Rigid ring vs shell model\n"], [], []
    for c, rows, s_sig, r_sig, error in res:
        kg, psi = c["load_N"] / U.G0, c["pressure_Pa"] / U.PSI
        text += [f"### {kg:g} kg, {psi:g} psi\n", validation.markdown(rows)]
        if error is not None:
            failed.append(f"validation slip step at {kg:g} kg, {psi:g} psi: {error}")
            text.append(f"The shell model's slip step failed here ({error}); rerun the command to retry it.\n")
        notes = diagnose(char, c["load_N"], c["pressure_Pa"], rows, char_dir=out, shell_signals=s_sig,
                         ring_signals=r_sig)
        if notes:
            text += ["Causes of the disagreements beyond tolerance:\n", "\n".join(notes) + "\n"]
        written.append(validation.validation_figure(s_sig, r_sig, out / f"validation_{kg:g}kg_{psi:g}psi.png",
                                                    title=f"Rigid ring vs shell model, {kg:g} kg, {psi:g} psi"))
    counts = {}
    for _, rows, _, _, _ in res:
        for r in rows:
            counts[r.verdict] = counts.get(r.verdict, 0) + 1
    summary = ", ".join(f"{n} {v}" for v, n in counts.items())
    text.insert(1, f"Metrics over the {len(res)} conditions: {summary}.\n")
    written.append(atomic_write_text(out / "validation.md", "\n".join(text)))
    say("\n".join(text))
    say(f"validation: {summary} (validation.md)")
    return [p for p in written if p is not None], failed
