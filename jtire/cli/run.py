"""`jtire run [CONFIG] [--set key=value ...] [--out DIR]`: run virtual experiments from a config.

An experiment config names one experiment (`experiment = "..."`) or several (`experiments = [...]`),
the tire file, the condition and optional solver and per-experiment tables. Without CONFIG the
default config runs: the static experiments at the rated condition. `--set` overrides any field
before validation: `condition.pressure_psi=70` for the experiment file, `tire.<section>.<key>=...`
for the tire file (e.g. `tire.mesh.n_theta=48`). Everything is validated, and the output folder
checked writable, before anything is simulated; with several experiments each one's results are
printed and saved as soon as it finishes.
"""

import math
from pathlib import Path

from ..errors import SimulationError
from ..io import atomic_write_csv, check_writable


def _fmt(v):
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (int, float)):
        return "nan" if (isinstance(v, float) and math.isnan(v)) else f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
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
    method = res.info.get("method")
    if "refined_from_n_theta" in res.info:  # batch.run reran an under-resolved case on a finer ring
        lines.append(f"  {'ring':<{w}}  {res.info['n_theta']} segments (refined from {res.info['refined_from_n_theta']}: "
                     f"{res.info['refined_because']})")
    if "unsolved_slip_angles_deg" in res.info:  # a sweep that stopped beyond its fit ranges
        lines.append(f"  {'not solved':<{w}}  slip angles {_fmt(res.info['unsolved_slip_angles_deg'])} deg "
                     f"({res.info['sweep_stopped']})")
    if method in ("static", "steady"):
        then = (f", then {res.info['steps']} explicit steps at dt {res.info.get('dt_s', float('nan')):.3g} s"
                if "steps" in res.info else "")  # a transient started from the static state (a release)
        lines.append(f"  {'converged':<{w}}  {res.checks.get(method + '_converged')}   ({method}: "
                     f"{res.info.get('levels')} levels, {res.info.get('newton_iterations')} Newton iterations{then}, "
                     f"{res.info.get('wall_s', 0):.1f} s wall incl. compile)")
        return lines
    settled = all(v for k, v in res.checks.items() if k.endswith("_settled"))
    lines.append(f"  {'settled':<{w}}  {settled}   (dt {res.info.get('dt_s', float('nan')):.3g} s, "
                 f"{res.info.get('steps', 0)} steps, {res.info.get('wall_s', 0):.1f} s wall incl. compile)")
    return lines


def add_arguments(p):
    p.add_argument("config", nargs="?", default=None,
                   help="experiment config TOML (default: the shipped configs/default.toml, the static experiments at "
                        "rated load and pressure)")
    p.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                   help="override a config field, e.g. condition.pressure_psi=70 or tire.mesh.n_theta=48")
    p.add_argument("--out", default=None, help="write DIR/result.json and DIR/signals.csv (DIR/<experiment>/ for several)")
    p.add_argument("--frames", type=int, default=0, metavar="N",
                   help="also record frames (deformed shape, contact pressure, strain energy) to DIR/frames.npz for "
                        "`jtire export-vtk DIR`: N uniform in time over each phase's longest span (a phase that "
                        "settles early reaches fewer) and its end (needs --out; 2 to 200)")


def run_cli(args, say) -> int:
    import time

    from .. import batch
    from ..config import load_run_config
    from ..resources import config_path
    from ..tire import make_tire

    from ..errors import ConfigError

    if args.frames and not 2 <= args.frames <= 200:
        raise ConfigError(f"--frames: {args.frames} is out of range (frames per phase, 2 to 200; 0 records none)")
    if args.frames and not args.out:
        raise ConfigError("--frames: needs --out DIR (the frames are written to DIR/frames.npz)")
    rc = load_run_config(args.config or config_path("default.toml"), args.overrides)
    out = Path(args.out) if args.out else None
    if out is not None:
        check_writable(out)
    tire = make_tire(rc.tire)
    several = len(rc.experiments) > 1
    rows = []
    for exp in rc.experiments:
        say(f"running {exp.name} ...", err=True)
        t0 = time.perf_counter()
        if args.frames:
            from ..experiments.program import recording_frames

            with recording_frames(args.frames):
                (res,) = batch.run(exp, tire, [rc.condition], keep_outputs=True)
        else:
            (res,) = batch.run(exp, tire, [rc.condition])
        if isinstance(res, batch.CaseFailure):
            raise SimulationError(f"{exp.name}: {res.error}")
        res.info |= {"wall_s": time.perf_counter() - t0, "config": str(rc.path)}
        say("\n".join(table_lines(res)))
        if out is not None:
            res.write(out / exp.name if several else out)
            if args.frames:
                _write_frames(tire, res, out / exp.name if several else out, say)
            rows += [(res.experiment, k, v) for k, v in res.quantities.items()]
            if several:
                atomic_write_csv(out / "summary.csv", ["experiment", "quantity", "value"], rows)
    if out is not None:
        say(f"results written to {out}/")
    return 0


def _write_frames(tire, res, folder, say):
    from ..frames import frames_from_outputs, save_frames

    outputs = getattr(res, "outputs", None)
    if not outputs:  # a composite (E11) keeps its components' results, not their signals
        say(f"  {res.experiment}: no frames (a composite of other experiments' runs)", err=True)
        return
    try:
        fr = frames_from_outputs(tire.model, outputs)
    except ValueError:  # static solves (E01, E02 by default) have no time history
        say(f"  {res.experiment}: no frames (solved as static equilibria, no time history)", err=True)
        return
    path = save_frames(Path(folder) / "frames.npz", fr)
    say(f"  {len(fr['t'])} frames -> {path}")
