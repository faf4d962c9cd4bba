"""Benchmark: the full E02 run (inflate, settle, quasi-static ramp to 60 kN, settle) per mesh size.

Prints, per mesh: DOF, stable step, steps, compile time (first call minus second), wall time of
a compiled run, microseconds per step, real-time factor (wall s per simulated s), and the k_sv it
measured. Timing on this shared 2-core machine varies by up to +-40 % between runs (physics
notes): each figure is the best of --repeat compiled runs.

    python benchmarks/bench_static.py                 # meshes 32, 48, 64 (default), 96 segments
    python benchmarks/bench_static.py --meshes 64x5x6 --repeat 3
"""

import argparse
import dataclasses
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["32x5x4", "48x5x6", "64x5x6", "96x10x8"],
                    help="n_theta x n_side x n_crown (default mesh: 64x5x6)")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--pressure-psi", type=float, default=120.0)
    args = ap.parse_args(argv)

    from jtire import units as U
    from jtire.experiments import static
    from jtire.experiments.phases import Protocol
    from jtire.config import load_tire
    from jtire.cli.run import load_run_config
    from jtire.tire import make_tire

    spec0, exps, cond, proto = load_run_config(REPO / "configs" / "experiments" / "vertical_stiffness.toml")
    cond = dict(cond, pressure_Pa=args.pressure_psi * U.PSI)
    table = exps[0][1]
    protocol = Protocol.from_dict(proto)
    rows = []
    head = ("mesh", "DOF", "dt [s]", "steps", "compile [s]", "E02 wall [s]", "us/step", "wall/sim s", "k_sv [kN/m]")
    print("E02 (inflate + settle + ramp 0-60 kN + settle), after compile, best of", max(1, args.repeat), flush=True)
    print(" | ".join(f"{h:>12}" for h in head), flush=True)
    for m in args.meshes:
        nt, ns, nc = (int(v) for v in m.split("x"))
        spec = dataclasses.replace(spec0, n_theta=nt, n_side=ns, n_crown=nc)
        t0 = time.perf_counter()
        tire = make_tire(spec)
        t_build = time.perf_counter() - t0
        run = lambda: static.run_vertical_stiffness(tire, cond, protocol, table["max_load_kN"], table["stated_load_kN"],  # noqa: E731
                                                    table["ramp_s"], table["fit_range_kN"])
        t0 = time.perf_counter()
        first = run()
        t_first = time.perf_counter() - t0
        walls = []
        for _ in range(max(1, args.repeat)):
            t0 = time.perf_counter()
            res = run()
            walls.append(time.perf_counter() - t0)
        wall = min(walls)
        steps = res.info["steps"]
        sim = res.info["simulated_s"]
        dof = 3 * nt * (spec.n_side * 2 + nc - 1) + 6
        rows.append((m, dof, res.info["dt_s"], steps, t_build + t_first - wall, wall, 1e6 * wall / steps, wall / sim,
                     res.quantities["k_sv_N_per_m"]))
        del first
        r = rows[-1]
        print(" | ".join([f"{r[0]:>12}", f"{r[1]:>12d}", f"{r[2]:>12.3g}", f"{r[3]:>12d}", f"{r[4]:>12.1f}", f"{r[5]:>12.2f}",
                          f"{r[6]:>12.0f}", f"{r[7]:>12.1f}", f"{r[8] / 1e3:>12.1f}"]), flush=True)


if __name__ == "__main__":
    main()
