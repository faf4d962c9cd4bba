"""Benchmark: the static experiments as equilibrium solves (jtire.equilibrium), default mesh.

Prints, for inflation, E01 (inflate + load to the rated 45.37 kN), E02 (inflate + 0..60 kN in load
levels), E09 static (E01 + 5 kN lateral) and the forward-mode gradient of E02's deflection at 50 kN
with respect to every MaterialParams leaf: compile time (first call minus the median of the later
ones), the median wall time of `--repeat` compiled runs, Newton iterations, factorizations and
GMRES iterations, and the quantities (k_sv secant and fit, deflection, footprint, k_l) beside
today's transient results. Run it alone on the machine:
`python benchmarks/bench_equilibrium.py` (timings vary by +-40 % on a shared 2-core machine).

    python benchmarks/bench_equilibrium.py --repeat 3
    python benchmarks/bench_equilibrium.py --mesh 32x5x4 --repeat 1     # the coarse ring
"""

import argparse
import dataclasses
import os
import time
from pathlib import Path

# LAPACK (the block factorization's small LU calls) comes from scipy's OpenBLAS, whose worker
# threads spin against XLA's on 2 cores: a 180 x 180 LU took 64 ms instead of 1 ms (measured)
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

REPO = Path(__file__).resolve().parents[1]
TRANSIENT = {"k_sv_45": 1.40475e6, "defl_e01": 0.0326, "k_l": 718341.0}  # today's transient runs, default mesh
E01_LEVELS = (15e3, 30e3, 45.37e3)
E02_LEVELS = tuple(float(v) for v in [5e3, 10e3, 15e3, 20e3, 25e3, 30e3, 35e3, 40e3, 45e3, 45.37e3, 50e3, 55e3, 60e3])
E09_LATERAL = (2.5e3, 5e3)


def default_tire(mesh: str):
    """(model, params) of the default tire on the mesh "n_theta x n_side x n_crown"."""
    from jtire.config import load_tire
    from jtire.tire import make_tire

    nt, ns, nc = (int(v) for v in mesh.split("x"))
    spec = dataclasses.replace(load_tire(REPO / "configs" / "tires" / "xone_xda.toml"), n_theta=nt, n_side=ns,
                               n_crown=nc)
    tire = make_tire(spec)
    return tire.model, tire.params


def timed(fn, repeat):
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    walls = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        walls.append(time.perf_counter() - t0)
    import numpy as np

    wall = float(np.median(walls))
    return out, max(first - wall, 0.0), wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="64x5x6", help="n_theta x n_side x n_crown (default mesh 64x5x6)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-grad", action="store_true")
    args = ap.parse_args(argv)

    import jax
    import jax.numpy as jnp
    import numpy as np

    import jtire.equilibrium as EQ
    from jtire import units as U
    from jtire.experiments.patch import extent, flat_gap

    m, params = default_tire(args.mesh)
    p = 120 * U.PSI
    load = 45.37e3

    def path(levels, lateral=None):
        parts = [EQ.vertical_levels(p, jnp.asarray(levels))] if levels else []
        if lateral:
            parts.append(EQ.lateral_levels(p, levels[-1], jnp.asarray(lateral)))
        return jax.jit(lambda prm: EQ.static_path(m, prm, p, *parts))

    rows, res = [], {}

    def report(name, out, comp, wall):
        I = out.infos
        EQ.check_static(I, lambda k: f"{name} level {k}")
        rows.append((name, comp, wall, int(np.sum(I.iterations)), int(np.sum(I.factorizations)),
                     int(np.sum(I.krylov)), len(np.asarray(I.iterations))))
        res[name] = out

    dof = 3 * m.n_theta * (m.n_s - 2) + 6
    print(f"mesh {args.mesh}: {dof} DOF; median of {args.repeat} compiled runs; OPENBLAS_NUM_THREADS="
          f"{os.environ.get('OPENBLAS_NUM_THREADS')}", flush=True)
    for name, fn in (("inflation", path(())), ("E01", path(E01_LEVELS)), ("E02", path(E02_LEVELS)),
                     ("E09 static", path(E01_LEVELS, E09_LATERAL))):
        out, comp, wall = timed(lambda: fn(params), args.repeat)
        report(name, out, comp, wall)
        print(f"  {name}: compile {comp:.1f} s, wall {wall:.2f} s", flush=True)

    if not args.skip_grad:
        upto = tuple(v for v in E02_LEVELS if v <= 50e3)
        fwd = path(upto)
        _, c_f, w_f = timed(lambda: fwd(params), args.repeat)
        lv = EQ.vertical_levels(p, jnp.asarray(upto))
        defl = lambda prm: -EQ.static_path(m, prm, p, lv).q[-1, 2]  # noqa: E731
        jac = jax.jit(jax.jacfwd(defl))
        g, c_g, w_g = timed(lambda: jac(params), args.repeat)
        n_leaves = sum(int(np.size(a)) for a in jax.tree_util.tree_leaves(params))
        print(f"  gradient of the 50 kN deflection w.r.t. {n_leaves} MaterialParams scalars (jacfwd): compile "
              f"{c_g:.1f} s, wall {w_g:.2f} s = {w_g / w_f:.2f} x the forward path to 50 kN ({w_f:.2f} s, "
              f"{len(upto)} levels)", flush=True)
        top = sorted(((abs(float(v)) * abs(float(a)), k, float(v)) for k, (v, a) in enumerate(
            zip(np.concatenate([np.ravel(x) for x in jax.tree_util.tree_leaves(g)]),
                np.concatenate([np.ravel(x) for x in jax.tree_util.tree_leaves(params)])))), reverse=True)[:3]
        print("    largest |d defl / d ln theta| (m):", ", ".join(f"leaf {k}: {s:.3g}" for s, k, _ in top))

    print("\n| run | compile [s] | wall [s] | levels | Newton its | factorizations | GMRES its |")
    print("|---|---|---|---|---|---|---|")
    for name, comp, wall, its, fac, kry, lv in rows:
        print(f"| {name} | {comp:.1f} | {wall:.2f} | {lv} | {its} | {fac} | {kry} |")

    e02 = res["E02"]
    F = -np.asarray(e02.rim_force[:, 2])
    d = -np.asarray(e02.q[:, 2])
    k45 = F[np.isclose(F, load)][0] / d[np.isclose(F, load)][0]
    k50 = 50e3 / d[np.isclose(F, 50e3)][0]
    sel = (F >= 10e3) & (F <= 60e3)
    kfit = np.polyfit(d[sel], F[sel], 1)[0]
    e01 = res["E01"]
    y01 = jax.tree_util.tree_map(lambda a: a[-1], e01.ys)
    length, width, area = extent(m, y01, flat_gap(float(e01.road_height[-1])))
    e09 = res["E09 static"]
    qy = np.asarray(e09.q[:, 1])
    y_lat = qy[-1] - qy[-len(E09_LATERAL) - 1]
    print("\n| quantity | static | transient today |")
    print("|---|---|---|")
    print(f"| E02 k_sv secant at 45.37 kN [N/m] | {k45:.6g} | {TRANSIENT['k_sv_45']:.6g} (ramp lag ~1 %) |")
    print(f"| E02 k_sv secant at 50 kN [N/m] | {k50:.6g} | |")
    print(f"| E02 k_sv fit 10-60 kN [N/m] | {kfit:.6g} | |")
    print(f"| E01 deflection [m] | {-float(e01.q[-1, 2]):.5f} | {TRANSIENT['defl_e01']} |")
    print(f"| E01 contact length / width [m], area [m^2] | {length:.4f} / {width:.4f}, {area:.4f} | |")
    print(f"| E09 k_l [N/m] | {E09_LATERAL[-1] / abs(y_lat):.6g} | {TRANSIENT['k_l']:.6g} |")


if __name__ == "__main__":
    main()
