"""`jtire sample CONFIG`: the posterior of a calibration's free parameters (emcee through an
emulator trained on the calibration's simulator runs; the work is `jtire.calibration.posterior.run`).

Rerun the same command to resume a killed chain or check. --check runs posterior draws through the
simulator (in pieces that fill the cores once, each saved as it returns: OUT/check_runs.jsonl) and
reports the emulator's interval coverage; where it is off, a refined round (those runs added to
the emulator's training) runs in OUT/refined, and while it is still off, up to [check] rounds in
all (OUT/refined_2, ...).
"""

from pathlib import Path

import numpy as np


def add_arguments(parser):
    parser.add_argument("config", metavar="CONFIG", help="posterior TOML, e.g. "
                        "configs/calibration/posterior.toml")
    parser.add_argument("--out", default=None, help="output folder (default runs/sample/<config>)")
    parser.add_argument("--history", default=None,
                        help="the calibration's output folder (default: the config's history)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                        help="override a field, e.g. --set sampler.max_steps=5000 (repeatable)")
    parser.add_argument("--check", action="store_true",
                        help="run [check] draws posterior samples through the simulator")
    parser.add_argument("--standin", action="store_true",
                        help="the closed-form STAND-IN simulator for --check (not physics)")


def run_cli(args, say) -> int:
    import dataclasses

    from ..calibration.posterior.spec import load_posterior
    from ..calibration.posterior.conformal import COVERAGE_OK, band_chance
    from ..calibration.posterior.run import run_posterior
    from .calibrate import _case_bar, simulator_for

    spec = load_posterior(args.config, args.set)
    if args.history:
        spec = dataclasses.replace(spec, history=Path(args.history))
    sim = None
    if args.check:
        sim = simulator_for(spec.calibration, args.standin, say)
        if sim is None:
            return 2
        sim.on_case = None  # the check draws its own bar, one step per posterior draw
    out = Path(args.out) if args.out else Path("runs") / "sample" / Path(args.config).stem
    from ..io import check_writable

    check_writable(out)

    def progress(steps, tau):
        t = f"{np.max(tau):.1f}" if np.all(np.isfinite(tau)) else "n/a"
        say(f"  {steps} steps, max tau {t}", err=True)

    bar = _case_bar(unit="draw")  # draws reused from a killed check are counted at the start
    r = run_posterior(spec, out, sim, progress, lambda done, total, reused: bar("posterior draws (check)", done, total))
    _report(r, spec, say)
    for k, ref in enumerate(r["rounds"][1:], start=1):
        say(f"coverage outside {COVERAGE_OK[0]:.0%}-{COVERAGE_OK[1]:.0%}: refined round {k} of at most "
            f"{spec.check['rounds']} (every check run so far, {ref['n_check_runs']}, joins the training set; "
            f"predictive variance in ln ({spec.check['variance']}): " + ref["emulator"].calibration_text()
            + f" by {spec.check['folds']}-fold cross-validation over them; fresh draws check it):")
        _report(ref, spec, say)
    final = r["rounds"][-1]
    if "check" in final and len(r["rounds"]) > 1:
        cov = final["check"]["coverage"]
        low = [n for n, v in cov.items() if v < COVERAGE_OK[0]]
        high = [n for n, v in cov.items() if v > COVERAGE_OK[1]]
        if low or high:
            say(f"coverage still outside {COVERAGE_OK[0]:.0%}-{COVERAGE_OK[1]:.0%} after {len(r['rounds']) - 1} "
                "refined round(s) (check.rounds):")
        if low:
            say(f"  {', '.join(low)}: below {COVERAGE_OK[0]:.0%}: the intervals are too narrow, not "
                "trustworthy at the stated level")
        if high:
            say(f"  {', '.join(high)}: above {COVERAGE_OK[1]:.0%}: the intervals are wider than the stated "
                "level needs (conservative)")
        if low or high:
            n_cal, n = final["n_check_runs"], final["check"]["n"]
            say(f"  (an interval made exactly valid on {n_cal} held-out runs shows a coverage inside "
                f"{COVERAGE_OK[0]:.0%}-{COVERAGE_OK[1]:.0%} on {n} draws with chance "
                f"{band_chance(n_cal, n):.2f} per response: calibration.posterior.conformal.band_chance)")
    return 0 if final["result"].converged else 1


def _report(r, spec, say) -> None:
    res, diag = r["result"], r["diagnostics"]
    emu = r["emulator"]
    say(f"emulator ({emu.n_points} simulator runs), leave-one-out RMSE of ln(response):")
    for name, kind in zip(emu.names, emu.kinds):
        scores = ", ".join(f"{k} {v:.3g}" for k, v in emu.loo[name].items())
        say(f"  {name}: chose {kind}  ({scores})")
    for name, src, d in zip(emu.names, r["sigma_sources"], r["discrepancy"]):
        extra = f"; model discrepancy sd {d:.3g} in ln ({spec.discrepancy})" if d > 0 else ""
        say(f"  measurement sd {name}: {src}{extra}")
    verdict = ("converged" if res.converged else
               f"NOT CONVERGED: stopped at the budget of {res.steps} steps, which is not longer "
               f"than {res.n_tau:g} x max tau")
    say(f"chain: {res.steps} steps x {res.chain.shape[1]} walkers ({res.n_new_steps} new; "
        f"{spec.sampler['moves']} moves in {spec.sampler['coordinates']} coordinates), "
        f"max tau {np.nanmax(res.tau):.1f}: {verdict}")
    say(f"acceptance fraction {diag['acceptance_mean']:.3f} (min {diag['acceptance_min']:.3f}); "
        f"R-hat max {np.nanmax(diag['rhat']):.4f}; bulk ESS min {np.nanmin(diag['ess_bulk']):.0f}")
    say("posterior predictive of the tire model (median [90 % interval]) beside the targets:")
    for row in r["predictive"]:
        meas = f"measured {row['measured']:.5g} {row['unit']:<5}" if np.isfinite(row["measured"]) else \
            f"{'(not measured)':<{len(row['unit']) + 20}}"  # the tire alone and the bias: no measurement
        say(f"  {row['target']:<5} {row['what']:<22} {meas} median {row['median']:.5g} [{row['lower']:.5g}, "
            f"{row['upper']:.5g}]")
    say("posterior / prior 90 % width in ln p (smallest first):")
    for row in sorted(r["widths"], key=lambda w: w["ratio"])[:8]:
        say(f"  {row['parameter']:<40} {row['ratio']:.3f}")
    if "check" in r:
        c = r["check"]
        k = int(c.get("reused", 0))
        how = ("stored runs reused" if k >= c["n_requested"] else
               f"{k} stored runs reused, {c['n_requested'] - k} simulated" if k else "simulated")
        say(f"simulator check ({c['n']} of {c['n_requested']} draws, {how}): coverage of the "
            f"emulator's {c['level']:.0%} intervals (inside / draws; the true coverage's exact 90 % "
            "confidence interval): " + ", ".join(
                f"{k} {v:.2f} ({c['inside'][k]}/{c['n']}; {c['coverage_interval'][k][0]:.2f}-"
                f"{c['coverage_interval'][k][1]:.2f})" for k, v in c["coverage"].items()))
    w = r["wall"]
    say("wall time: emulator {:.1f} s, chain {:.1f} s ({} new steps){}".format(
        w["emulator_s"], w["chain_s"], res.n_new_steps,
        f", simulator check {w['check_s']:.1f} s" if "check_s" in w else ""))
    say(f"wrote {r['out']}/ (chain.h5, diagnostics.json, predictive.csv, widths.csv, corner.png, "
        "emulator.json" + (", check.json)" if "check" in r else ")"))
