"""Benchmark: how well each variance correction of the posterior check holds the next round's draws.

`jtire sample ... --check` refines its emulator round by round: round k trains on the calibration's
history plus the check runs of rounds < k, corrects its predictive variance by k-fold cross-validation
over those runs (`calibrate_variance`, check.variance = scale | floor | wider), and is checked on
round k's fresh draws. This script replays that on a finished sample folder for every form (and
without correction), scoring each refined emulator on the draws of the round it never saw, so the
forms are compared on the same simulator runs. No simulator runs: only emulator fits, the k-fold ones
once for every form (GP: 59 s for two rounds on 2 cores; 2 min 26 s when each form refitted the folds).

    jtire sample configs/calibration/posterior.toml --out runs/sample/study --check   # >= 2 rounds
    python benchmarks/bench_variance_forms.py --sample runs/sample/study --history runs/calibrate/study

Prints coverage of the 90 % intervals per response, with the previous figures beside it.
"""

import argparse
import dataclasses
import json
from pathlib import Path

import numpy as np

import jtire  # noqa: F401  (float64)
from jtire.calibration.posterior.conformal import held_out_residuals, variance_correction
from jtire.calibration.posterior.emulator import fit_emulator, usable
from jtire.calibration.posterior.report import coverage
from jtire.calibration.posterior.spec import load_posterior
from jtire.calibration.posterior.run import refined_dir, training_data
from jtire.resources import config_path

# Previous figures (2-core machine, default-mesh study calibration, 45 runs; the check draws of a
# `jtire sample` run with check.variance = "floor", commit eb8c960): coverage DZ / DY / FX1 / FX2.
PREVIOUS = {
    (1, "none"): "0.34 / 0.50 / 0.72 / 0.81", (1, "scale"): "0.84 / 0.66 / 0.94 / 0.97",
    (1, "floor"): "0.97 / 0.94 / 1.00 / 1.00", (1, "wider"): "0.97 / 0.94 / 1.00 / 1.00",
    (2, "none"): "0.62 / 0.78 / 0.59 / 0.59", (2, "scale"): "0.91 / 1.00 / 1.00 / 0.84",
    (2, "floor"): "0.91 / 1.00 / 1.00 / 0.75", (2, "wider"): "0.91 / 1.00 / 1.00 / 0.84",
}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sample", required=True, help="a `jtire sample --check` output folder")
    ap.add_argument("--history", required=True, help="the calibration's output folder it was run on")
    ap.add_argument("--config", default=str(config_path("calibration", "posterior.toml")))
    args = ap.parse_args(argv)
    spec = dataclasses.replace(load_posterior(args.config), history=Path(args.history))
    names = [t.name for t in spec.calibration.targets]
    th, y = training_data(spec)
    checks = []
    for k in range(0, 11):
        p = (Path(args.sample) if k == 0 else refined_dir(args.sample, k)) / "check.json"
        if not p.is_file():
            break
        c = json.loads(p.read_text())
        checks.append((np.asarray(c["thetas"], float), np.asarray(c["simulated"], float)))
    if len(checks) < 2:
        raise SystemExit(f"{args.sample}: needs the checks of at least two rounds (found {len(checks)})")
    print("| scored on round | trained on runs | form | " + " | ".join(names) + " | before |")
    print("|---|---|---|" + "---|" * len(names) + "---|")
    for k in range(1, len(checks)):
        ex_t = np.vstack([c[0] for c in checks[:k]])
        ex_y = np.vstack([c[1] for c in checks[:k]])
        good = usable(ex_y)
        ex_t, ex_y = ex_t[good], ex_y[good]
        emu = fit_emulator(spec.calibration.space, names, np.vstack([th, ex_t]), np.vstack([y, ex_y]),
                           spec.candidates, spec.emulator_seed)
        r, v = held_out_residuals(spec, th, y, ex_t, ex_y)  # the fold fits once, for every form
        for form in ("none", "scale", "floor", "wider"):
            emu.var_scale = emu.var_floor = None
            if form != "none":
                emu.var_scale, emu.var_floor = variance_correction(r, v, form=form)
            cov = coverage(emu, *checks[k])["coverage"]
            print(f"| {k} | {len(th) + len(ex_t)} | {form} | " + " | ".join(f"{cov[n]:.2f}" for n in names)
                  + f" | {PREVIOUS.get((k, form), '')} |", flush=True)


if __name__ == "__main__":
    main()
