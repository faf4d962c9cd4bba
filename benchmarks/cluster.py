"""A 9-case sweep on the default runner against `--cluster local:N`, as whole processes, in turn.

    python benchmarks/cluster.py                      # E01 footprint, 3 x 3 grid, default mesh, 3 rounds
    python benchmarks/cluster.py --config configs/experiments/vertical_stiffness.toml --rounds 5

Each round runs `jtire sweep CONFIG` once per executor (default, local:1, local:2), each into a new
folder, in turn (so a drift of the machine's speed hits them alike), with the compile cache warm from a
first, uncounted round. Prints the median wall time of each, its ratio to the default runner's (per
round, then the median), and whether every summary.csv is byte for byte the default runner's. Run it on a
quiet machine: it runs two processes at once (local:2) and nothing else should.
"""

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXECUTORS = [("default", []), ("local:1", ["--cluster", "local:1"]), ("local:2", ["--cluster", "local:2"])]
# the last run's medians (2026-11-27, quiet 2-core x86, default mesh, E01 3 x 3, OPENBLAS_NUM_THREADS=1, 3 rounds)
PREVIOUS = {"default": "43.5 s", "local:1": "46.6 s (1.087)", "local:2": "37.7 s (0.872)"}


def sweep(args, config, out, sets):
    cmd = [sys.executable, "-c", "import sys; from jtire.cli import main; sys.exit(main(sys.argv[1:]))",
           *args, "sweep", config, "--out", str(out), *[a for s in sets for a in ("--set", s)]]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode:
        raise SystemExit(f"{' '.join(cmd)} failed: {p.stderr[-2000:]}")
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "experiments" / "footprint.toml"))
    ap.add_argument("--set", action="append", default=[], help="override (e.g. tire.mesh.n_theta=32)")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args(argv)
    walls = {name: [] for name, _ in EXECUTORS}
    same = True
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(a.rounds + 1):  # round 0 warms the cache and is not counted
            base = None
            for name, args in EXECUTORS:
                out = Path(tmp) / f"{r}_{name.replace(':', '')}"
                w = sweep(args, a.config, out, a.set)
                summary = (out / "summary.csv").read_bytes()
                base = summary if base is None else base
                same &= summary == base
                if r:
                    walls[name].append(w)
                print(f"round {r} {name}: {w:.1f} s", file=sys.stderr, flush=True)
    ref = walls["default"]
    print("| executor | wall s (median) | min - max | ratio to default (median of rounds) | previous |")
    print("|---|---|---|---|---|")
    for name, _ in EXECUTORS:
        ws = walls[name]
        ratio = statistics.median(w / d for w, d in zip(ws, ref))
        prev = PREVIOUS.get(name)
        print(f"| {name} | {statistics.median(ws):.1f} | {min(ws):.1f} - {max(ws):.1f} | {ratio:.3f} | "
              f"{'-' if prev is None else prev} |")
    print(f"\nsummary.csv byte for byte the default runner's in every round: {same}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
