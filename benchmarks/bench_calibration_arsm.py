"""Which ARSM variant for the tire calibration: measured on the STAND-IN simulator (not physics).

The problem: configs/calibration/study.toml (20 free parameters in log space, the study's four
targets, equal weights), budget 45 evaluations. The responses come from
calibration.tire.standin (closed-form, smooth monotone power laws and series springs of the moduli,
rolling resistance ~ losses x deflection x load). Variants: the surface kind per response
(linear, reduced, ridge, subspace), the region rule (arsm, trust), the batch fill (local,
region), and the study's way for comparison: ONE quadratic of the total |%| error
(calibration.arsm.minimize, one point per iteration, the same box).

Prints, per variant, the final best total error (%) over seeds: median [q25, q75], and the
seconds per run (the stand-in costs nothing; this is the optimizer's own overhead).

    python benchmarks/bench_calibration_arsm.py --seeds 10
"""

import argparse
import itertools
import time

import numpy as np

import jtire  # noqa: F401  (float64)
from jtire.calibration import arsm
from jtire.calibration.tire.arsm_multi import calibrate_arsm
from jtire.calibration.tire.runlog import RunLog
from jtire.calibration.tire.spec import load_calibration
from jtire.calibration.tire.standin import StandinSimulator
from jtire.calibration.tire.targets import total_error
from jtire.resources import config_path


def scalar_arsm(sim, spec, budget, seed):
    """The study's way: one quadratic surface of the total error (calibration.arsm)."""
    space = sim.space

    def fun(u):
        return float(total_error(sim.evaluate(space.from_unit(u)[None])[0], spec.targets))

    return arsm.minimize(fun, np.zeros(space.d), np.ones(space.d), budget, seed).f_best


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("--budget", type=int, default=45)
    ap.add_argument("--batch", type=int, default=4)
    ap.add_argument("--config", default=str(config_path("calibration", "study.toml")))
    ap.add_argument("--surfaces", default="linear,reduced,ridge,subspace")
    ap.add_argument("--rules", default="arsm,trust")
    ap.add_argument("--fills", default="local,region")
    ap.add_argument("--weightings", default="distance,nearest")
    ap.add_argument("--no-scalar", action="store_true")
    args = ap.parse_args(argv)
    spec = load_calibration(args.config)
    sim = StandinSimulator(spec.space, spec.base_params, spec.targets)
    sim.evaluate(spec.space.default[None])  # compile
    print(f"stand-in, d = {spec.space.d}, budget {args.budget}, batch {args.batch}, "
          f"{args.seeds} seeds; base tire total error "
          f"{total_error(sim.evaluate(spec.space.default[None])[0], spec.targets)[()]:.1f} %")
    print(f"{'surface':<9} {'rule':<6} {'fill':<7} {'fit':<9} {'final total error % median [q25, q75]':<40} s/run")
    variants = itertools.product(args.surfaces.split(","), args.rules.split(","),
                                 args.fills.split(","), args.weightings.split(","))
    for surf, rule, fill, wt in variants:
        t0, res = time.perf_counter(), []
        for seed in range(args.seeds):
            log = RunLog(sim, spec.targets, None, "arsm", seed, args.budget)
            res.append(calibrate_arsm(sim, spec.targets, log, seed=seed, batch_size=args.batch,
                                      surface=surf, region_rule=rule, fill=fill,
                                      weighting=wt).total_error_pct)
        q = np.percentile(res, [50, 25, 75])
        print(f"{surf:<9} {rule:<6} {fill:<7} {wt:<9} {q[0]:8.3f} [{q[1]:.3f}, {q[2]:.3f}]"
              f"{'':<18} {(time.perf_counter() - t0) / args.seeds:.2f}")
    if not args.no_scalar:
        t0 = time.perf_counter()
        res = [scalar_arsm(sim, spec, args.budget, s) for s in range(args.seeds)]
        q = np.percentile(res, [50, 25, 75])
        print(f"{'one quadratic of the |%| sum (calibration.arsm, the study way)':<33} "
              f"{q[0]:8.3f} [{q[1]:.3f}, {q[2]:.3f}]   {(time.perf_counter() - t0) / args.seeds:.2f}")


if __name__ == "__main__":
    main()
