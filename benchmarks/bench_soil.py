"""Time the soil plate test and scan its error surface over (density, Young's modulus).

    python benchmarks/bench_soil.py                 # timing table, default and finer mesh
    python benchmarks/bench_soil.py --scan 11       # plus an 11 x 11 error scan over the bounds

Prints: mesh size, compile time (first call, includes tracing and XLA), wall time per run after
compilation (median and best of --repeats calls at distinct parameters, so nothing is cached
but the compiled function), Newton iterations, and the sinkage at a reference point.
Wall times on a shared machine vary with its load; the best-of figure is the least disturbed.
"""

import argparse
import dataclasses
import time

import numpy as np

from jtire.calibration.soil.block import SoilSpec, simulate_sinkage, sinkage_objective, suggested_bounds


def time_layout(name: str, spec: SoilSpec, repeats: int) -> dict:
    from jtire.calibration.soil.block import _layout, _solver

    t0 = time.perf_counter()
    run, mesh = _solver(_layout(spec))
    t_mesh = time.perf_counter() - t0
    t0 = time.perf_counter()
    res = simulate_sinkage(1700.0, 2e6, spec)
    t_first = time.perf_counter() - t0
    walls, cpus = [], []
    for k in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        simulate_sinkage(1200.0 + 1000.0 * k / max(repeats - 1, 1), 2e6 + 1e4 * k, spec)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    its = res.newton_iterations
    return dict(
        layout=name,
        elements=mesh.n_elements,
        nodes=mesh.nodes.shape[0],
        unknowns=f"{mesh.n_free} ({mesh.n_blocks}x{mesh.block_size})",
        mesh_s=t_mesh,
        compile_s=t_first - np.median(walls),
        run_median_ms=1e3 * np.median(walls),
        run_best_ms=1e3 * np.min(walls),
        run_cpu_ms=1e3 * np.median(cpus),  # all threads of this process
        newton=f"{its.sum()} ({its.min()}-{its.max()}/step)",
        sinkage_mm=1e3 * res.sinkage_m,
        recompiles=run._cache_size() - 1,
    )


def print_table(rows: list) -> None:
    keys = list(rows[0])
    def fmt(v):
        return f"{v:.3g}" if isinstance(v, float) else str(v)

    cells = [[k] + [fmt(r[k]) for r in rows] for k in keys]
    width = [max(len(c[i]) for c in cells) for i in range(len(rows) + 1)]
    for c in cells:
        print("  ".join(s.rjust(w) for s, w in zip(c, width)))


def scan(spec: SoilSpec, n: int) -> None:
    """Brute-force error grid over the suggested bounds, then the valley E*(rho)."""
    (r_lo, r_hi), (e_lo, e_hi) = suggested_bounds()
    rhos = np.linspace(r_lo, r_hi, n)
    es = np.linspace(e_lo, e_hi, n)
    f = sinkage_objective(spec)
    err = np.array([[f(np.array([r, e])) for e in es] for r in rhos])
    print(f"\nerror (%) on a {n} x {n} grid; rows density kg/m^3, columns E MPa")
    print("rho\\E  " + " ".join(f"{e / 1e6:7.2f}" for e in es))
    for r, row in zip(rhos, err):
        print(f"{r:6.0f} " + " ".join(f"{v:7.2f}" for v in row))
    i, j = np.unravel_index(np.argmin(err), err.shape)
    print(f"grid minimum {err[i, j]:.3f} % at rho = {rhos[i]:.0f}, E = {es[j] / 1e6:.3f} MPa")
    # Sinkage is exactly S(rho)/E, so the zero-error valley is E*(rho) = S(rho) / target.
    target = spec.target_sinkage_m
    print(f"\nvalley E*(rho) for target {1e3 * target:.4f} mm (error checked by a direct run)")
    for r in rhos:
        e_star = simulate_sinkage(r, 2e6, spec).sinkage_m * 2e6 / target
        err_star = f(np.array([r, e_star]))
        print(f"  rho {r:6.0f}  E* = {e_star / 1e6:.4f} MPa  error {err_star:.2e} %")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--scan", type=int, default=0, help="grid points per axis (0: no scan)")
    ap.add_argument("--no-fine", action="store_true", help="skip the finer mesh")
    args = ap.parse_args()
    spec = SoilSpec()
    rows = [time_layout("default", spec, args.repeats)]
    if not args.no_fine:
        fine = dataclasses.replace(spec, n_r_plate=10, n_r_outer=14, n_z=20)
        rows.append(time_layout("fine", fine, max(args.repeats // 4, 3)))
    print_table(rows)
    if args.scan:
        scan(spec, args.scan)


if __name__ == "__main__":
    main()
