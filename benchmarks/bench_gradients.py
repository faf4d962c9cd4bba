"""Benchmark: the price of a gradient with respect to every material leaf, as a multiple of one forward
run of the same program (after compile), for E02's deflection at 50 kN and E12's mean drag.

Forward mode: `jax.jacfwd` through the experiment (one vmapped tangent per leaf: d = 42 scalar leaves of
MaterialParams, every one a calibratable modulus, thickness, loss or friction). Reverse mode: `jax.jacrev`
with every transient phase checkpointed (diffrax RecursiveCheckpointAdjoint, 1024 stored states; the
static solves differentiate implicitly either way). The steps are held at their values (a numerical
setting, not physics). Every figure is the best of --repeat runs (compile excluded: each program runs
once before it is timed). The persistent compilation cache is on, as for the command line: the first
run in a fresh cache compiles (slower, more memory), later runs load the programs.

    python benchmarks/bench_gradients.py                      # default mesh
    python benchmarks/bench_gradients.py --mesh 32x5x4 --short
    python benchmarks/bench_gradients.py --calibration configs/calibration/study.toml --repeat 1
        # the calibration's target Jacobian (ShellSimulator.jacobian: forward mode through the static
        # solves, reverse mode through E12) against one evaluation of the same targets
"""

import argparse
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="64x5x6")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--short", action="store_true", help="short E12 stages (a quick check, not the reported figure)")
    ap.add_argument("--experiments", nargs="+", default=["vertical_stiffness", "rolling_resistance"])
    ap.add_argument("--calibration", default="", help="price this calibration config's target Jacobian instead")
    ap.add_argument("--save-dir", default="", help="save each Jacobian as grad_<experiment>_<mode>.npy here")
    ap.add_argument("--modes", nargs="+", default=["forward", "reverse"], choices=["forward", "reverse"])
    args = ap.parse_args(argv)

    import jax
    import jax.numpy as jnp
    import numpy as np

    import jtire  # noqa: F401
    from jtire import batch, cache
    from jtire.calibration.tire.shell import traced_jacobian
    from jtire.config import load_run_config
    from jtire.tire import make_tire

    cache.enable()
    nt, ns, nc = (int(v) for v in args.mesh.split("x"))
    mesh = [f"tire.mesh.n_theta={nt}", f"tire.mesh.n_side={ns}", f"tire.mesh.n_crown={nc}"]
    if args.calibration:
        return calibration_jacobian(args, mesh)
    extra = {"vertical_stiffness": ["vertical_stiffness.stated_load_kN=50"],
             "rolling_resistance": ["rolling_resistance.settle_s=0.02", "rolling_resistance.ramp_s=0.02",
                                    "rolling_resistance.release_s=0.01", "rolling_resistance.measure_s=0.03"]
             if args.short else []}
    qty = {"vertical_stiffness": "deflection_m", "rolling_resistance": "rolling_resistance_N"}
    print(f"gradient of one quantity w.r.t. all MaterialParams leaves, mesh {args.mesh}, best of {args.repeat}")
    print("| experiment | quantity | leaves | mode | forward run [s] | gradient [s] | cost / forward | value |")
    print("|---|---|---|---|---|---|---|---|")
    for name in args.experiments:
        rc = load_run_config(REPO / "configs" / "experiments" / f"{name}.toml", mesh + extra.get(name, []))
        tire = make_tire(rc.tire)
        exp = rc.experiments[0]
        flat, unravel = jax.flatten_util.ravel_pytree(tire.params)
        theta0 = jnp.log(flat)
        params_of = lambda th: unravel(jnp.exp(th))  # noqa: E731  (every leaf positive: log space)

        def forward():
            return batch.run(exp, tire, [rc.condition])[0]

        res = forward()
        tf = []
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            forward()
            tf.append(time.perf_counter() - t0)
        f = min(tf)
        for mode in args.modes:
            def gradient():
                return traced_jacobian(exp, tire, params_of, theta0, [rc.condition], [qty[name]], mode=mode)

            gradient()
            tg = []
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                v, J = gradient()
                tg.append(time.perf_counter() - t0)
            gg = min(tg)
            print(f"| {name} | {qty[name]} | {flat.size} | {mode} | {f:.1f} | {gg:.1f} | {gg / f:.1f} | "
                  f"{float(v[0]):.6g} (host {res.quantities[qty[name]]:.6g}) |", flush=True)
            if args.save_dir:
                np.save(Path(args.save_dir) / f"grad_{name}_{mode}.npy", J)


def calibration_jacobian(args, mesh):
    """The m x d Jacobian of a calibration's targets at the base tire, first call (compiles) and
    after, against one evaluation of the targets (after compile)."""
    import resource

    import numpy as np

    import jtire  # noqa: F401
    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration

    spec = load_calibration(args.calibration, mesh)
    sim = ShellSimulator(spec, spec.tire)
    theta = np.asarray(spec.space.from_params(spec.base_params))
    peak = lambda: resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6  # noqa: E731  (Linux: KB)
    t0 = time.perf_counter()
    sim.evaluate(theta[None])
    first_eval = time.perf_counter() - t0
    peaks = [peak()]
    te = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        y = sim.evaluate(theta[None])[0]
        te.append(time.perf_counter() - t0)
    peaks.append(peak())
    tj = []
    for k in range(args.repeat + 1):
        t0 = time.perf_counter()
        v, J = sim.jacobian(theta)
        tj.append(time.perf_counter() - t0)
        split = dict(sim.last_wall)
        if k == 0:
            peaks.append(peak())
    peaks.append(peak())
    e, j = min(te), min(tj[1:])
    print(f"target Jacobian of {args.calibration}, mesh {args.mesh}: {J.shape[0]} targets x {J.shape[1]} parameters")
    print("| what | wall [s] | forward-run equivalents | peak RSS so far [GB] |")
    print("|---|---|---|---|")
    print(f"| one evaluation of the targets (first call, compiles) | {first_eval:.1f} | | {peaks[0]:.2f} |")
    print(f"| one evaluation of the targets | {e:.1f} | 1 | {peaks[1]:.2f} |")
    print(f"| Jacobian, first call (compiles) | {tj[0]:.1f} | {tj[0] / e:.1f} | {peaks[2]:.2f} |")
    print(f"| Jacobian | {j:.1f} | {j / e:.1f} | {peaks[3]:.2f} |")
    print("values by the Jacobian's programs vs the evaluation: "
          + ", ".join(f"{n} {a:.6g} / {b:.6g}" for n, a, b in zip(sim.response_names, v, y)))
    print("wall split of the last Jacobian [s]: " + ", ".join(f"{k} {w:.1f}" for k, w in split.items()))
    if args.save_dir:
        np.save(Path(args.save_dir) / "jacobian_targets.npy", J)


if __name__ == "__main__":
    import jax.flatten_util  # noqa: F401

    main()
