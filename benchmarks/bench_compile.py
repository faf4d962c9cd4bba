"""Benchmark: where a static program's compile and run time go (default mesh).

The static path program (`equilibrium.static_path`: inflation, touch and E02's 13 load levels)
compiles in 24-29 s. This splits that time two ways:

- by stage: `jax.jit(...).trace` (Python tracing to a jaxpr), `.lower()` (jaxpr to StableHLO) and
  `.compile()` (XLA's optimization passes and LLVM code generation), each timed alone;
- by piece: the same three stages for each building block the Newton loop instantiates, compiled
  as its own program on the frictional contact setup of a loaded level:
    residual      R(u): the force balance (one evaluation of every force)
    linearize     R(u) and one J v product (jax.linearize: the GMRES matvec)
    assembly      the banded Jacobian from vmapped J v products (colouring) and its block LU
    precond       one solve with that factorization (block-banded forward and back sweeps)
    gmres         one GMRES solve of J d = -r preconditioned by a given factorization
    newton        one whole static solve (`solve_static_full`: every piece above in its loops),
                  E02's last level (55 -> 60 kN, preconditioned by the 55 kN factorization)
    static path   E02's program (the scan over the 15 levels around one solve)

Each row also prints the optimized module's size (HLO instructions and fusions: `fusion(` calls)
and the compiled program's run time (median of --repeat calls after one warm-up), so a static
solve's wall time can be read as its counts (bench_equilibrium.py: Newton iterations,
factorizations, GMRES iterations) times these prices.
jax's in-memory caches are cleared before each program; the persistent compilation cache is off
unless the environment turns it on. Run it alone on the machine:

    python benchmarks/bench_compile.py
    python benchmarks/bench_compile.py --mesh 32x5x4      # the coarse ring
"""

import argparse
import os
import re
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_equilibrium import E02_LEVELS, default_tire  # noqa: E402  (the same tire and load levels)


def split(fn, *args, repeat=5):
    """(trace s, lower s, XLA compile s, HLO instructions, fusions, run s) of jax.jit(fn) at args."""
    import jax
    import numpy as np

    jax.clear_caches()
    jf = jax.jit(fn)
    t0 = time.perf_counter()
    traced = jf.trace(*args)
    t1 = time.perf_counter()
    lowered = traced.lower()
    t2 = time.perf_counter()
    compiled = lowered.compile()
    t3 = time.perf_counter()
    hlo = compiled.as_text()
    instr = sum(1 for ln in hlo.splitlines() if re.match(r"^\s+(ROOT )?%?[\w.\-]+ = ", ln))
    fusions = len(re.findall(r"\sfusion\(", hlo))
    jax.block_until_ready(compiled(*args))
    runs = []
    for _ in range(repeat):
        t4 = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        runs.append(time.perf_counter() - t4)
    return t1 - t0, t2 - t1, t3 - t2, instr, fusions, float(np.median(runs))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="64x5x6", help="n_theta x n_side x n_crown (default mesh 64x5x6)")
    ap.add_argument("--repeat", type=int, default=5, help="timed runs per program (median)")
    args = ap.parse_args(argv)

    import jax
    import jax.numpy as jnp
    import numpy as np

    import jtire.equilibrium as EQ
    from jtire import units as U
    from jtire.equilibrium import linalg as LA
    from jtire.equilibrium import newton as NW
    from jtire.equilibrium import residual as R
    from jtire.equilibrium import sequences as SQ
    from jtire.equilibrium.krylov import gmres
    from jtire.physics.contact import FlatRoad

    m, params = default_tire(args.mesh)
    p = 120 * U.PSI
    levels = SQ.vertical_levels(p, jnp.asarray(E02_LEVELS))
    path = EQ.static_path(m, params, p, levels)  # the states the pieces are compiled at (not timed)
    # E02's last level: from the 55 kN state to 60 kN (the pieces are compiled and timed there)
    y = jax.tree_util.tree_map(lambda a: a[-2], path.ys)
    road = FlatRoad(height=path.road_height[-1], velocity=jnp.zeros(3))
    setup = R.make_setup(p, rim_force=np.array([0, 0, -60e3, 0, 0, 0.0]), rim_free=np.array([0, 0, 1.0, 0, 0, 0]),
                         surface=road, anchors=SQ.anchors_of(m, y, road))
    u = NW.initial_u(m, setup, y)
    st = LA.structure(m, setup.n_border)
    fun = lambda u_: R.residual(m, params, setup, u_)  # noqa: E731

    def linearize(u_, v):
        r, lin = jax.linearize(fun, u_)
        return r, lin(v)

    def assembly(u_):
        _, lin = jax.linearize(fun, u_)
        return LA.factor(LA.jacobian_from_linear(lin, u_, st, True))

    P = jax.jit(assembly)(u)  # the 55 kN factorization: the last level's preconditioner

    def krylov(u_, P_):
        r, lin = jax.linearize(fun, u_)
        return gmres(lin, lambda v: LA.solve_flat(st, P_, v), -r, 1e-4, 40)

    def newton(y_, P_):
        return NW.solve_static_full(m, params, setup, y_, NW.NewtonOptions(), (P_, jnp.asarray(True)))[0].x.x

    pieces = [("residual", fun, (u,)), ("linearize", linearize, (u, jnp.ones_like(u))),
              ("assembly", assembly, (u,)),
              ("precond", lambda P_, v: LA.solve_flat(st, P_, v), (P, jnp.ones_like(u))), ("gmres", krylov, (u, P)), ("newton", newton, (y, P)),
              ("static path (E02)", lambda prm: EQ.static_path(m, prm, p, levels).q, (params,))]
    dof = 3 * m.n_theta * (m.n_s - 2) + 6
    print(f"mesh {args.mesh}: {dof} DOF; jax {jax.__version__}", flush=True)
    print("\n| program | trace [s] | lower [s] | XLA compile [s] | total [s] | HLO instructions | fusions | run [ms] |")
    print("|---|---|---|---|---|---|---|---|")
    for name, fn, a in pieces:
        tr, lo, co, n_ins, n_fus, run = split(fn, *a, repeat=args.repeat if name != "static path (E02)" else 1)
        print(f"| {name} | {tr:.1f} | {lo:.1f} | {co:.1f} | {tr + lo + co:.1f} | {n_ins} | {n_fus} | {1e3 * run:.1f} |",
              flush=True)


if __name__ == "__main__":
    main()
