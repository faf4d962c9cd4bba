"""`jtire calibrate CONFIG`: tune the tire's free parameters to the calibration targets (the work
is `jtire.calibration.tire.run`).

Outputs in --out: fingerprint.json, history.jsonl (every evaluation; rerun the same command to
resume a killed run), table_4_4.csv/.md, figure_4_6.png, calibrated_tire.toml, summary.json.
"""

from pathlib import Path


def add_arguments(parser):
    parser.add_argument("config", metavar="CONFIG",
                        help="calibration TOML, e.g. configs/calibration/study.toml")
    parser.add_argument("--out", default=None,
                        help="output folder (default runs/calibrate/<config name>); resumes from it")
    parser.add_argument("--method", choices=("arsm", "gradient", "lm"), default=None,
                        help="arsm (response surfaces, batches) or gradient (= lm: Levenberg-Marquardt with "
                        "the simulator's Jacobian); default: the config's")
    parser.add_argument("--budget", type=float, default=None,
                        help="ARSM evaluations or LM forward-run equivalents (default: the config's)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config field, e.g. --set arsm.seed=3 or "
                        "--set tire.mesh.n_theta=48 (repeatable)")
    parser.add_argument("--check-tire", default=None, metavar="TIRE",
                        help="no calibration: evaluate the config's targets on this tire TOML (e.g. "
                        "DIR/calibrated_tire.toml) at the config's mesh and print measured, simulated, error")
    parser.add_argument("--standin", action="store_true",
                        help="use the closed-form STAND-IN simulator (a dry run of the machinery, "
                        "not physics)")


def simulator_for(spec, standin: bool, say):
    """The shell simulator (calibration.tire.shell.make_simulator) or the stand-in; a missing
    shell simulator is reported as one line (returns None)."""
    from ..calibration.tire.shell import make_simulator
    from ..calibration.tire.standin import StandinSimulator

    if standin:
        say("simulator: closed-form STAND-IN (not physics)")
        return StandinSimulator(spec.space, spec.base_params, spec.targets)
    try:
        sim = make_simulator(spec, spec.tire)
    except NotImplementedError as e:
        say(f"jtire calibrate: error: {e} (not available yet; --standin runs the machinery on a stand-in)",
            err=True)
        return None
    sim.on_case = _case_bar()
    return sim


def _case_bar(unit=None):
    """on_case for the shell simulator: one tqdm bar per evaluation batch (cases of every target);
    any (label, done, total) progress with `unit` (e.g. the posterior check's draws)."""
    from tqdm import tqdm

    state = {"bar": None}

    def on_case(label, done, total):
        if state["bar"] is None or state["bar"].total != total or state["bar"].n >= total:
            if state["bar"] is not None:
                state["bar"].close()
            state["bar"] = tqdm(total=total, desc=f"simulate {label}", leave=False, mininterval=0,
                                unit=unit or ("experiment" if label.startswith("Jacobian") else "case"))
        if done > state["bar"].n:  # (a bar prints when made: an update by 0 printed it twice)
            state["bar"].update(done - state["bar"].n)
        if done >= total:
            state["bar"].close()

    return on_case


def run_cli(args, say) -> int:
    from ..calibration.tire.spec import load_calibration
    from ..calibration.tire.run import run_calibration
    from ..errors import ConfigError

    from ..io import check_writable

    if args.check_tire is not None:
        return _check_tire(args, say)
    spec = load_calibration(args.config, args.set)
    if args.budget is not None and not args.budget >= 1:
        raise ConfigError(f"--budget = {args.budget:g}: must be >= 1")
    budget = spec.arsm["budget"] if args.budget is None else args.budget
    n0 = spec.space.d + 2
    if (args.method or spec.method) == "arsm" and not spec.arsm["n_initial"] and budget < n0:
        raise ConfigError(f"budget = {budget:g}: ARSM's initial design alone is d + 2 = {n0} evaluations for "
                          f"{spec.space.d} free parameters; give a budget >= {n0} (--budget) or a smaller "
                          "arsm.n_initial (>= 2)")
    out = Path(args.out) if args.out else Path("runs") / "calibrate" / (
        Path(args.config).stem + ("_standin" if args.standin else ""))
    check_writable(out)
    sim = simulator_for(spec, args.standin, say)
    if sim is None:
        return 2

    def progress(res):
        say(f"  {res.n_evaluations} evaluations, best total error {res.total_error_pct:.4g} %",
            err=True)

    method = "lm" if args.method == "gradient" else args.method
    res, paths = run_calibration(spec, sim, out, method, args.budget, progress)
    say(paths["table_md"].read_text().rstrip())
    say(f"{res.method}: {res.n_evaluations} evaluations and {res.n_jacobians} Jacobian calls in "
        f"{res.n_batches} batches, "
        f"{res.cost_forward:.0f} forward-run equivalents, simulator wall {res.wall_s:.1f} s; "
        f"stop: {res.stop_reason}")
    say("wrote " + ", ".join(str(p) for p in paths.values()))
    return 0


def _check_tire(args, say) -> int:
    """`--check-tire TIRE`: the config's targets simulated on TIRE (one evaluation, its own values),
    printed as Table 4-4 and, with --out, written as check_tire.json / check_tire.md."""
    import time
    import types

    import numpy as np

    from ..calibration.tire.report import format_markdown, table_4_4
    from ..calibration.tire.spec import load_calibration
    from ..calibration.tire.targets import percent_errors, total_error
    from ..errors import ConfigError
    from ..io import atomic_write_json, atomic_write_text, check_writable

    tire = Path(args.check_tire)
    if not tire.is_file():
        raise ConfigError(f"--check-tire {tire}: no such tire file")
    spec = load_calibration(args.config, args.set, tire_path=tire)
    if args.out:
        check_writable(Path(args.out))
    sim = simulator_for(spec, args.standin, say)
    if sim is None:
        return 2
    theta = np.array(spec.space.default, float)
    if spec.space.has_bias:  # the bias is not in the tire file: the calibration's summary holds it
        theta, where = _biases_beside(tire, spec.space, theta)
        say(where)
    t0 = time.perf_counter()
    values = sim.evaluate(theta[None])[0]
    wall = time.perf_counter() - t0
    if not np.all(np.isfinite(values)):
        bad = [n for n, v in zip(spec.response_names, values) if not np.isfinite(v)]
        say(f"jtire calibrate: error: --check-tire: the simulation of {', '.join(bad)} failed on {tire}", err=True)
        return 2
    errs = percent_errors(values, spec.targets)
    res = types.SimpleNamespace(values=values, errors_pct=errs, theta=theta,
                                total_error_pct=float(total_error(values[None], spec.targets, spec.weights)[0]))
    from ..calibration.tire.run import evaluate_checks

    rows = table_4_4(res, spec, evaluate_checks(spec, sim, theta))
    text = format_markdown(rows)
    say(f"{tire}: the targets of {Path(args.config).name} simulated in {wall:.1f} s "
        f"(mesh {spec.tire.n_theta} x {spec.tire.n_side} x {spec.tire.n_crown})")
    say(text.rstrip())
    if args.out:
        out = Path(args.out)
        atomic_write_text(out / "check_tire.md", text)
        atomic_write_json(out / "check_tire.json", {"tire": str(tire.resolve()), "config": str(args.config),
                                                    "rows": rows, "simulator_wall_s": wall,
                                                    "simulator": sim.fingerprint()})
        say(f"wrote {out / 'check_tire.md'}, {out / 'check_tire.json'}")
    return 0


def _biases_beside(tire, space, theta):
    """theta with the bias entries read from the calibration's summary.json beside TIRE (the
    folder `jtire calibrate` wrote it to); (theta, one line saying where the biases came from)."""
    import json

    import numpy as np

    from ..errors import ConfigError

    path = tire.parent / "summary.json"
    names = [space.names[j] for j in range(space.d) if space.is_bias(j)]
    if not path.is_file():
        return theta, (f"biases {', '.join(names)}: no {path.name} beside the tire; taken at their "
                       "lower bounds (the simulated values are the tire's own plus those)")
    try:
        got = json.loads(path.read_text()).get("bias_SI", {})
    except (OSError, ValueError) as e:
        raise ConfigError(f"{path}: unreadable ({e})") from None
    theta = np.array(theta, float)
    missing = [n for n in names if n not in got]
    if missing:
        raise ConfigError(f"{path}: bias_SI has no {', '.join(missing)}; it was written by another "
                          "calibration config")
    for j in range(space.d):
        if space.is_bias(j):
            theta[j] = float(got[space.names[j]][0])
    return theta, f"biases from {path}: " + ", ".join(
        f"{n} = {theta[space.names.index(n)]:.6g} {got[n][1]}" for n in names)
