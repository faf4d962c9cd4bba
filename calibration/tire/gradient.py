"""The gradient route: Levenberg-Marquardt on log parameters with the simulator's Jacobian.

Residuals are the weighted log-ratios r_i = sqrt(w_i) ln(y_i / t_i): relative errors to first
order, and nearly linear in ln(parameters) for responses that behave like power laws of the
moduli, which is what Gauss-Newton needs. The Jacobian comes from `Simulator.jacobian` (autodiff,
dy/dtheta, (m, d)); in unit coordinates u of the log box, J_u = sqrt(w) (dy/dtheta / y) width.

With m = 4 targets and d >= 15 parameters the problem is under-determined: the step is the
minimum-norm LM step delta = -J^T (J J^T + lambda I)^-1 r (an m x m solve), so among the many
parameter sets that meet the targets it walks to the one nearest the start. Bounds: the box is
enforced by projection, and a parameter at a bound whose gradient pushes outwards is frozen for
the step (a projected LM).

Why numpy and not optimistix.LevenbergMarquardt: the simulator is a host call that returns
values and Jacobian together at a stated cost (the batched shell runner), not a jax function;
optimistix would need it wrapped in pure_callback with a custom jvp, hide how many runs each
step costs, and it has no bounds. Forty lines of LM keep every call visible and counted.

Cost: a trial point is first evaluated alone (one forward run); the Jacobian, which costs many
forward runs on the shell model, is computed only where a trial is accepted. A rejected trial so
costs one run, and a budget that cannot pay for the next Jacobian still takes the step it has
paid for (with a Jacobian at every trial, a small budget can end at the base tire without trying
a step: docs/design-notes.md). Each call is recorded with its forward-run
equivalents (`Simulator.cost_forward_equivalents`; the shell model measures a Jacobian's: the
call's wall time, less its compiling, over a timed forward evaluation of the same targets, its first
call charged the two reference evaluations) and wall time, in the same history format as ARSM,
so a killed run resumes by replay.
"""

import numpy as np

from .arsm_multi import CalibrationResult, result_from_log
from .runlog import BudgetExhausted, RunLog

__all__ = ["calibrate_lm"]

_LAMBDA_DOWN, _LAMBDA_UP = 1.0 / 3.0, 4.0


def _residuals(vals, jac, targets, weights, width):
    sw = np.sqrt(weights)
    meas = np.array([t.measured for t in targets])
    r = sw * np.log(vals / meas)
    ju = sw[:, None] * jac / vals[:, None] * width[None, :]
    return r, ju


def calibrate_lm(sim, targets, log: RunLog, weights=None, max_iterations: int = 30,
                 lambda0: float = 1e-2, tol_percent: float = 0.01, min_step: float = 1e-8,
                 theta0=None, progress=None) -> CalibrationResult:
    """Projected minimum-norm Levenberg-Marquardt from theta0 (default: the base tire).

    Stops: "target" (total error <= tol_percent), "step" (the step fell below min_step in unit
    coordinates), "iterations", "budget" (the log's forward budget), "failed" (the simulator
    returned non-finite values or Jacobian at the start or at an accepted point).
    """
    space = sim.space
    w = np.ones(len(targets)) if weights is None else np.asarray(weights, float)
    width = space.width
    u = space.to_unit(space.default if theta0 is None else theta0)
    lam = float(lambda0)
    reason = "iterations"
    try:
        vals, jac = log.jacobian(space.from_unit(u), phase="lm_start")
        if not (np.all(np.isfinite(vals)) and np.all(vals > 0) and np.all(np.isfinite(jac))):
            return result_from_log(log, "failed")
        r, ju = _residuals(vals, jac, targets, w, width)
        meas = np.array([t.measured for t in targets])
        for _ in range(int(max_iterations)):
            err = np.sum(w * 100.0 * np.abs(vals / meas - 1.0))
            if err <= tol_percent:
                reason = "target"
                break
            g = ju.T @ r
            free = ~(((u <= 0.0) & (g > 0)) | ((u >= 1.0) & (g < 0)))
            jf = ju[:, free]
            delta = np.zeros_like(u)
            delta[free] = -jf.T @ np.linalg.solve(jf @ jf.T + lam * np.eye(len(r)), r)
            u_new = np.clip(u + delta, 0.0, 1.0)
            if np.max(np.abs(u_new - u)) < min_step:
                reason = "step"
                break
            theta_new = space.from_unit(u_new)
            v_new = log.evaluate(theta_new[None], phase="lm_trial", extras=[{"lambda": lam}])[0]
            ok = np.all(np.isfinite(v_new)) and np.all(v_new > 0)
            r_new = np.sqrt(w) * np.log(v_new / meas) if ok else None
            if ok and r_new @ r_new < r @ r:
                # accepted: the Jacobian there (its values are the trial's, recomputed with it)
                v_j, j_new = log.jacobian(theta_new, phase="lm", extra={"lambda": lam})
                if not (np.all(np.isfinite(v_j)) and np.all(v_j > 0) and np.all(np.isfinite(j_new))):
                    reason = "failed"
                    break
                u, vals = u_new, v_j
                r, ju = _residuals(vals, j_new, targets, w, width)
                lam = max(lam * _LAMBDA_DOWN, 1e-12)
            else:
                lam *= _LAMBDA_UP
            if progress is not None:
                progress(result_from_log(log, "running"))
    except BudgetExhausted:
        reason = "budget"
    return result_from_log(log, reason)

