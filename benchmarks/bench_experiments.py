"""Benchmark every experiment config at the default mesh: wall time with and without compile.

Runs each `configs/experiments/*.toml` (or the ones named) through the same path as `jtire run`,
twice in one process: the first run includes compiling its programs (the shared inflation/load
phase program is compiled once per process and shape, so later experiments reuse it), the second
is the cost a user pays for a further condition. Prints a table: wall times, time steps (as the
experiment reports them in info["steps"]), simulated seconds, microseconds per step and wall
seconds per simulated second. Timing on shared machines varies +-40 % (physics notes).

    python benchmarks/bench_experiments.py                       # all 12 experiments, ~30-40 min
    python benchmarks/bench_experiments.py drum_cleat rolling_resistance --once
"""

import argparse
import time
from pathlib import Path

import jtire  # noqa: F401  (float64)
from jtire import batch
from jtire.config import load_run_config
from jtire.tire import make_tire

REPO = Path(__file__).resolve().parents[1]
CONFIGS = REPO / "configs" / "experiments"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="config stems (default: every file in configs/experiments)")
    ap.add_argument("--once", action="store_true", help="one run each (wall includes compile)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="config override for every config, e.g. tire.mesh.n_theta=32")
    args = ap.parse_args(argv)
    names = args.names or sorted(p.stem for p in CONFIGS.glob("*.toml"))
    head = ("config", "experiment", "1st wall [s]", "2nd wall [s]", "steps", "sim [s]", "us/step", "wall/sim s")
    print(" | ".join(f"{h:>20}" if i < 2 else f"{h:>12}" for i, h in enumerate(head)), flush=True)
    def run_config(path):
        rc = load_run_config(path, args.overrides)
        tire = make_tire(rc.tire)
        out = []
        for exp in rc.experiments:
            (res,) = batch.run(exp, tire, [rc.condition])
            if isinstance(res, batch.CaseFailure):
                raise SystemExit(f"{path.name}: {res.error}")
            out.append(res)
        return out

    for name in names:
        path = CONFIGS / f"{name}.toml"
        t0 = time.perf_counter()
        results = run_config(path)
        first = time.perf_counter() - t0
        second = float("nan")
        if not args.once:
            t0 = time.perf_counter()
            results = run_config(path)
            second = time.perf_counter() - t0
        wall = first if args.once else second
        for res in results:
            steps = int(res.info.get("steps", 0))  # 0 for a static solve (E01, E02: Newton levels)
            sim = float(res.info.get("simulated_s", float("nan")))
            us = 1e6 * wall / steps if steps else float("nan")
            row = (name, res.experiment, f"{first:.1f}", f"{second:.1f}", str(steps), f"{sim:.3f}",
                   f"{us:.0f}", f"{wall / sim:.1f}" if sim == sim and sim > 0 else "-")
            print(" | ".join(f"{c:>20}" if i < 2 else f"{c:>12}" for i, c in enumerate(row)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
