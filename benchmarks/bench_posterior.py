"""Benchmark: the posterior's sampling cost, moves x coordinates, on a calibration's history.

For each sampler variant (emcee's stretch move in ln p, the bounded box; differential-evolution
moves in logit coordinates, the `jtire sample` default) it fits the emulator to the history,
runs the chain from the calibration's best run until it is longer than n_tau integrated
autocorrelation times or hits the budget, and prints: acceptance, max tau, steps, converged, and
the wall time of the emulator fit and of the chain. No simulator runs (the `--check` batch of
`jtire sample` prints its own wall time).

    jtire calibrate configs/calibration/study.toml --out runs/calibrate/study     # the history
    python benchmarks/bench_posterior.py --history runs/calibrate/study
    python benchmarks/bench_posterior.py --history runs/calibrate/study --variants de:logit --max-steps 20000

Chains go to a temporary folder (nothing is resumed). Run it alone on the machine.
"""

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np

import jtire  # noqa: F401  (float64)
from jtire.calibration.posterior.spec import load_posterior
from jtire.calibration.posterior.run import run_posterior
from jtire.resources import config_path

# Previous figures (2-core machine, the default-mesh study calibration's 45 runs, GP emulator,
# 64 walkers, max_steps 20000): `jtire sample` at commit 6d11341 (stretch move in ln p).
# de:logit: `jtire sample` at commit eb8c960, quiet machine (its first round).
PREVIOUS = {"stretch:log": "acceptance 0.079, max tau 2184, 20000 steps, NOT converged, chain ~7 min",
            "de:logit": "acceptance 0.221, max tau 118, 6500 steps, converged, emulator 1.7 s, chain 23.5 s"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--history", required=True, help="a calibration's output folder (history.jsonl)")
    ap.add_argument("--config", default=str(config_path("calibration", "posterior.toml")))
    ap.add_argument("--variants", default="stretch:log,de:logit", help="moves:coordinates, comma-separated")
    ap.add_argument("--max-steps", type=int, default=20000)
    args = ap.parse_args(argv)
    print("| moves | coordinates | acceptance | max tau | steps | converged | emulator s | chain s | before |")
    print("|---|---|---|---|---|---|---|---|---|")
    for v in args.variants.split(","):
        moves, coords = v.split(":")
        spec = load_posterior(args.config, [f"sampler.moves={moves!r}".replace("'", '"'),
                                            f"sampler.coordinates={coords!r}".replace("'", '"'),
                                            f"sampler.max_steps={args.max_steps}"])
        spec = dataclasses.replace(spec, history=Path(args.history))
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            r = run_posterior(spec, Path(tmp) / "post")
            res, diag, w = r["result"], r["diagnostics"], r["wall"]
        print(f"| {moves} | {coords} | {diag['acceptance_mean']:.3f} | {np.nanmax(res.tau):.0f} | "
              f"{res.steps} | {'yes' if res.converged else 'NO'} | {w['emulator_s']:.1f} | "
              f"{w['chain_s']:.0f} | {PREVIOUS.get(v, '')} |", flush=True)


if __name__ == "__main__":
    main()
