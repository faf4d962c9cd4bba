"""`jtire sensitivity CONFIG`: d(quantity)/d(ln parameter) for a calibration config's free
parameters, at the base tire or at a calibrated point (the work is
`jtire.calibration.tire.sensitivity`): a table (CSV, JSON), a heat map of the elasticities and the
singular values of the targets' Jacobian (how many parameter directions the targets identify).
"""

import json
from pathlib import Path

import numpy as np


def add_arguments(parser):
    parser.add_argument("config", metavar="CONFIG", help="calibration TOML (its [[free]] and targets)")
    parser.add_argument("--at", default="base",
                        help="base (the config's tire) or a calibration folder: its summary.json's "
                        "best point")
    parser.add_argument("--quantities", default=None,
                        help="comma-separated quantities (default: the config's [sensitivity] "
                        "list, else the targets)")
    parser.add_argument("--out", default=None, help="output folder (default runs/sensitivity/<config>)")
    parser.add_argument("--rel-tol", type=float, default=1e-2,
                        help="singular values below this fraction of the largest count as "
                        "unidentified (default 0.01)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a config field (repeatable)")
    parser.add_argument("--standin", action="store_true",
                        help="the closed-form STAND-IN simulator (not physics)")


def run_cli(args, say) -> int:
    from ..calibration.tire.sensitivity import compute, identifiability, write_sensitivity
    from ..calibration.tire.spec import load_calibration
    from ..errors import ConfigError
    from .calibrate import simulator_for

    spec = load_calibration(args.config, args.set)
    if not 0 < args.rel_tol < 1:
        raise ConfigError(f"--rel-tol = {args.rel_tol:g}: must be in (0, 1)")
    if args.at == "base":
        theta = spec.space.default
    else:
        path = Path(args.at) / "summary.json"
        if not path.is_file():
            raise ConfigError(f"--at {args.at}: no summary.json there (a `jtire calibrate` output "
                              "folder, or base)")
        from ..config import read_text

        text = read_text(path, "calibration summary")
        try:
            theta = np.array(json.loads(text)["theta"], float)
        except (ValueError, KeyError, TypeError):  # not JSON, no theta, not numbers
            raise ConfigError(f"--at {args.at}: {path.name} holds no best point (theta: a list of "
                              "numbers); is it a `jtire calibrate` output folder?") from None
        if theta.shape != (spec.space.d,) or not np.all(np.isfinite(theta)):
            raise ConfigError(f"--at {args.at}: its best point does not fit this config's "
                              f"{spec.space.d} free parameters")
    quantities = (tuple(q.strip() for q in args.quantities.split(",") if q.strip())
                  if args.quantities else spec.sensitivity_quantities)
    if not quantities:
        raise ConfigError(f"--quantities {args.quantities!r}: name at least one quantity")
    from ..io import check_writable

    out = Path(args.out) if args.out else Path("runs") / "sensitivity" / Path(args.config).stem
    check_writable(out)
    sim = simulator_for(spec, args.standin, say)
    if sim is None:
        return 2
    try:
        sens = compute(sim, theta, quantities)
        targets = compute(sim, theta) if tuple(quantities) != spec.response_names else sens
    except NotImplementedError as e:
        say(f"jtire sensitivity: error: the simulator has no Jacobian ({e})", err=True)
        return 2
    except KeyError as e:
        raise ConfigError(f"--quantities: {e.args[0]}") from None
    ident = identifiability(targets.elasticity, spec.weights, args.rel_tol)
    paths = write_sensitivity(sens, out, ident, f"{spec.path.name}: elasticities at {args.at}")
    w = max(len(n) for n in spec.space.names)
    say(f"{'parameter':<{w}}  " + "  ".join(f"{q:>12}" for q in sens.quantities)
        + "   (d ln q / d ln p)")
    for j, n in enumerate(spec.space.names):
        say(f"{n:<{w}}  " + "  ".join(f"{sens.elasticity[i, j]:>12.4f}"
                                     for i in range(len(sens.quantities))))
    s = ident["singular_values"]
    say("singular values of the targets' elasticity matrix: "
        + ", ".join(f"{v:.4g}" for v in s) + f"  -> {ident['n_identified']} of {spec.space.d} "
        f"parameter directions identified (s_k / s_1 >= {args.rel_tol:g}); the other "
        f"{spec.space.d - ident['n_identified']} are not seen by the targets")
    say("wrote " + ", ".join(str(p) for p in paths.values()))
    return 0
