"""Benchmark the free decays started from a static equilibrium (method = "static", the default of
E03, E04, E05, E07, E08, E09 and E13) against the same experiments run as transients throughout
(method = "transient": explicit inflation, loading and settling).

Each experiment runs its shipped config through the same path as `jtire run`, twice per method in
one process (the first run includes tracing and compiling, the second is what a further condition
costs). The table gives the second run's wall, the explicit steps, and the quantities both methods
report, with the static-start value's difference from the transient's.

    python benchmarks/bench_static_start.py                         # default mesh (~10 min)
    python benchmarks/bench_static_start.py --set tire.mesh.n_theta=32
    python benchmarks/bench_static_start.py --experiments drop_test lateral_stiffness
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

# the quantities compared, per experiment (the stiffness of the held state, the decay's damping)
COMPARE = {
    "drum_cleat": ("first_mode_Hz", "k_dv_N_per_m", "first_mode_xi", "deflection_m", "peak_axle_force_N"),
    "drop_test": ("k_sv_N_per_m", "C_tot_Ns_per_m", "C_tot_fit_Ns_per_m", "omega_n_fit_rad_per_s"),
    "inplane_rotation": ("k_btheta_Nm_per_rad", "C_btheta_Nms_per_rad", "C_btheta_fit_Nms_per_rad"),
    "sidewall_translation": ("k_by_N_per_m", "C_by_Ns_per_m", "C_by_fit_Ns_per_m"),
    "sidewall_camber": ("k_bgamma_Nm_per_rad", "C_bgamma_Nms_per_rad", "C_bgamma_fit_Nms_per_rad"),
    "sidewall_longitudinal": ("k_bx_N_per_m", "C_bx_Ns_per_m", "C_bx_fit_Ns_per_m"),
    "lateral_stiffness": ("k_l_N_per_m", "C_l_Ns_per_m", "C_l_fit_Ns_per_m"),
}
# main before this change (2026-11-28, quiet, default mesh, `jtire run` of the shipped config, warm
# compilation cache, whole process): wall incl. compile as the run line printed it, and the steps
BEFORE = {"drop_test": "26.8 s, 28,378 steps", "sidewall_translation": "26.4 s, 22,219 steps",
          "lateral_stiffness": "31.5 s, 39,015 steps (decay_s 0.3)"}


def run(name, overrides, method, repeat=2):
    """(result, [wall of each run]) of the named experiment's shipped config with the overrides."""
    rc = load_run_config(CONFIGS / f"{name}.toml", overrides + [f"{name}.method={method}"])
    tire, exp = make_tire(rc.tire), rc.experiments[0]

    def once():
        t0 = time.perf_counter()
        res = batch.run(exp, tire, [rc.condition])[0]
        if isinstance(res, batch.CaseFailure):
            raise SystemExit(f"{name} ({method}): {res.error}")
        return res, time.perf_counter() - t0

    runs = [once() for _ in range(repeat)]
    return runs[-1][0], [w for _, w in runs]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--experiments", nargs="+", default=list(COMPARE), choices=list(COMPARE))
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE")
    args = ap.parse_args(argv)
    print(f"{'experiment':>22} | {'method':>9} | {'1st wall [s]':>12} | {'2nd wall [s]':>12} | {'steps':>7} | "
          f"{'before (main, jtire run)':>26} | quantities (static vs transient)", flush=True)
    for name in args.experiments:
        res = {}
        for method in ("transient", "static"):
            r, walls = run(name, args.overrides, method)
            res[method] = r
            diffs = ""
            if method == "static":
                t = res["transient"].quantities
                diffs = ", ".join(f"{k} {r.quantities[k]:.5g} ({r.quantities[k] / t[k] - 1:+.2%})" for k in COMPARE[name]
                                  if r.quantities.get(k) is not None and t.get(k))
            else:
                diffs = ", ".join(f"{k} {r.quantities[k]:.5g}" for k in COMPARE[name] if r.quantities.get(k) is not None)
            before = BEFORE.get(name, "-") if method == "transient" else ""
            print(f"{name:>22} | {method:>9} | {walls[0]:>12.1f} | {walls[1]:>12.1f} | {r.info.get('steps', 0):>7} | "
                  f"{before:>26} | {diffs}", flush=True)


if __name__ == "__main__":
    main()
