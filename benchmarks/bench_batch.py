"""Benchmark: one experiment over a 9-case grid, run one case at a time, vmapped on one device, and
sharded over the host devices; compile time and peak memory of each.

Every variant runs in a fresh process with the persistent compilation cache OFF (so compile time is
measured, not loaded): the process runs the grid twice, the first pass includes compiling, the second
is the per-case cost after compile. Peak memory is the process's maximum resident set size.

    python benchmarks/bench_batch.py                          # E01, E09, E12 on the default mesh
    python benchmarks/bench_batch.py --experiments footprint --mesh 32x5x4 --cases 4
    python benchmarks/bench_batch.py --experiments footprint lateral_stiffness --method transient
    python benchmarks/bench_batch.py --experiments rolling_resistance --one-core   # where the time goes
Take figures on a quiet machine (nothing else running) and repeat: timings here vary +-40 %.
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
CONFIGS = {"footprint": "footprint.toml", "lateral_stiffness": "lateral_stiffness.toml",
           "rolling_resistance": "rolling_resistance.toml", "vertical_stiffness": "vertical_stiffness.toml"}
EXTRA = {"lateral_stiffness": ["lateral_stiffness.decay_s=0"]}


def child(args):
    """Run inside a fresh process: the grid twice in one mode; prints one JSON line."""
    import resource

    import jtire  # noqa: F401  (devices)
    from jtire import batch
    from jtire import units as U
    from jtire.config import load_run_config
    from jtire.tire import make_tire

    nt, ns, nc = (int(v) for v in args.mesh.split("x"))
    over = [f"tire.mesh.n_theta={nt}", f"tire.mesh.n_side={ns}", f"tire.mesh.n_crown={nc}"] + EXTRA.get(args.experiment, [])
    if args.method and args.experiment in ("footprint", "vertical_stiffness", "lateral_stiffness"):
        over.append(f'{args.experiment}.method="{args.method}"')
    rc = load_run_config(REPO / "configs" / "experiments" / CONFIGS[args.experiment], over)
    tire = make_tire(rc.tire)
    exp = rc.experiments[0]
    loads = [2312.5, 4625.0, 6937.5] if args.experiment != "rolling_resistance" else [3945.0, 4220.0, 4625.0]
    conds = [{"pressure_Pa": p * U.PSI, "load_N": w * U.G0} for p in (70.0, 120.0, 150.0) for w in loads][: args.cases]
    walls = []
    for _ in range(2):
        r0 = resource.getrusage(resource.RUSAGE_SELF)
        t0 = time.perf_counter()
        if args.mode == "single":
            res = [batch.run(exp, tire, [c], devices=1)[0] for c in conds]
        elif args.mode == "sharded-1":  # one case per device at a time: batches of the device count
            import jax

            res = batch.run(exp, tire, conds, batch=len(jax.devices()))
        else:
            res = batch.run(exp, tire, conds, devices=1 if args.mode == "vmap" else None)
        walls.append(time.perf_counter() - t0)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        # cores busy on average during the pass: CPU time (user + system, all threads) / wall time
        cores = (r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime) / walls[-1]
    bad = [r for r in res if isinstance(r, batch.CaseFailure)]
    steps = [r.info.get("steps", r.info.get("newton_iterations", 0)) for r in res if not isinstance(r, batch.CaseFailure)]
    peak_gib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    print(json.dumps({"first_s": walls[0], "second_s": walls[1], "n": len(conds), "failed": len(bad),
                      "steps_mean": sum(steps) / max(len(steps), 1), "peak_GiB": peak_gib, "cores_busy": cores}))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--experiments", nargs="+", default=["footprint", "lateral_stiffness", "rolling_resistance"])
    ap.add_argument("--mesh", default="64x5x6", help="n_theta x n_side x n_crown (default: the default mesh)")
    ap.add_argument("--cases", type=int, default=9)
    ap.add_argument("--modes", nargs="+", default=["single", "vmap", "sharded", "sharded-1"],
                    help="single: one case at a time; vmap: all cases vmapped on one device; sharded: all cases "
                         "vmapped and split over the devices; sharded-1: batches of one case per device")
    ap.add_argument("--method", default="", help="static or transient for E01/E02/E09 (default: the config's; "
                    "static solves run case by case in every mode, so only the transient shows vmap and sharding)")
    ap.add_argument("--one-core", action="store_true",
                    help="also run each mode pinned to one core (Linux `taskset -c 0`): how much of the second core a "
                         "single case already uses, and what vmap gains on one core")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--experiment", help=argparse.SUPPRESS)
    ap.add_argument("--mode", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        return child(args)
    env = dict(os.environ, JTIRE_CACHE_DIR="off")
    print(f"{args.cases}-case grid, mesh {args.mesh}; per case after compile, compile = first pass - second pass")
    print("| experiment | mode | per case after compile [s] | vs single | compile [s] | peak memory [GiB] | "
          "steps/case (static: Newton iterations) | cores busy after compile |")
    print("|---|---|---|---|---|---|---|---|")
    runs = [(e, m, pin) for e in args.experiments for pin in ([False, True] if args.one_core else [False])
            for m in args.modes if not (pin and m.startswith("sharded"))]  # sharded over 2 devices on 1 core: nothing to learn
    base = {}
    for e, m, pin in runs:
        cmd = (["taskset", "-c", "0"] if pin else []) + [
            sys.executable, __file__, "--child", "--experiment", e, "--mode", m, "--mesh", args.mesh,
            "--cases", str(args.cases), "--method", args.method]
        # the jtire command line turns the cache on; this script never does (JTIRE_CACHE_DIR=off for clarity)
        out = subprocess.run(cmd, capture_output=True, text=True, env=env)
        line = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
        m_name = m + (" (1 core)" if pin else "")
        if out.returncode or not line:
            print(f"| {e} | {m_name} | failed: {out.stderr.strip().splitlines()[-1] if out.stderr.strip() else out.returncode} |")
            continue
        r = json.loads(line[-1])
        per = r["second_s"] / r["n"]
        if m == "single" and not pin:
            base[e] = per
        ratio = f"{per / base[e]:.2f}" if e in base else "-"
        print(f"| {e} | {m_name} | {per:.2f} | {ratio} | {r['first_s'] - r['second_s']:.0f} | {r['peak_GiB']:.2f} | "
              f"{r['steps_mean']:.0f} | {r.get('cores_busy', float('nan')):.2f} |", flush=True)


if __name__ == "__main__":
    main()
