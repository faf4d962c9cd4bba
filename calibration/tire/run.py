"""Run a tire calibration end to end: output folder, fingerprint, history, method, outputs.

`run_calibration(spec, sim, out_dir)` is what `jtire calibrate` calls; tests call it with a
stand-in simulator. The folder holds fingerprint.json (config, tire, simulator, version: a rerun
with other settings refuses), history.jsonl (every evaluation; a killed run resumes from it with
nothing lost or repeated) and the outputs of calibration.tire.report.
"""

from pathlib import Path

from .arsm_multi import calibrate_arsm
from .gradient import calibrate_lm
from .report import write_outputs
from .runlog import RunLog, check_fingerprint

__all__ = ["run_calibration", "evaluate_checks", "HISTORY"]

HISTORY = "history.jsonl"


def run_calibration(spec, sim, out_dir, method=None, budget=None, progress=None):
    """Calibrate; returns (CalibrationResult, {output: path}).

    method: "arsm" or "lm" (default: the config's); budget: ARSM evaluations or LM forward-run
    equivalents (default: the config's). Budgets may grow on a resumed run; anything else that
    fixes the numbers must match the folder's fingerprint.
    """
    import dataclasses

    method = method or spec.method
    spec = dataclasses.replace(spec, method=method)
    out_dir = Path(out_dir)
    check_fingerprint(out_dir, spec.fingerprint(sim))
    if method == "arsm":
        a = dict(spec.arsm)
        if budget is not None:
            a["budget"] = int(budget)
        log = RunLog(sim, spec.targets, spec.weights, "arsm", a["seed"], a["budget"],
                     out_dir / HISTORY)
        res = calibrate_arsm(sim, spec.targets, log, seed=a["seed"], batch_size=a["batch_size"],
                             n_initial=a["n_initial"], surface=a["surface"],
                             region_rule=a["region_rule"], fill=a["fill"],
                             weighting=a["weighting"], min_width=a["min_width"],
                             min_shrink=a["min_shrink"], initial_width=a["initial_width"],
                             tol_percent=a["tol_percent"], weights=spec.weights,
                             progress=progress)
    else:
        g = dict(spec.gradient)
        if budget is not None:
            g["forward_budget"] = float(budget)
        log = RunLog(sim, spec.targets, spec.weights, "lm", 0, 10**9, out_dir / HISTORY,
                     forward_budget=g["forward_budget"])
        res = calibrate_lm(sim, spec.targets, log, weights=spec.weights,
                           max_iterations=g["max_iterations"], lambda0=g["lambda0"],
                           tol_percent=g["tol_percent"], min_step=g["min_step"],
                           progress=progress)
    checks = evaluate_checks(spec, sim, res.theta)
    title = (f"{spec.path.name}: {method}, {res.n_evaluations} evaluations "
             f"({res.cost_forward:.0f} forward-run equivalents), best total error "
             f"{res.total_error_pct:.3g} %")
    return res, write_outputs(res, spec, out_dir, title, sim, checks)


def evaluate_checks(spec, sim, theta):
    """The config's [checks] simulated once at theta: (values (k,) SI, note) or (None, note) when
    there are none or the simulator cannot run them (the stand-in). Not part of the objective."""
    import numpy as np

    if not spec.checks:
        return None, ""
    if not np.all(np.isfinite(theta)):
        return None, "checks: no calibrated point"
    csim = sim.for_targets(spec.checks)
    if csim is None:
        return None, f"checks: {type(sim).__name__} cannot simulate them (not run)"
    return csim.evaluate(np.asarray(theta, float)[None])[0], ""
