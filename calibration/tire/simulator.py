"""The interface between the calibration machinery and whatever computes the responses.

Everything in calibration/ (ARSM, the gradient route, sensitivities, the posterior's emulator
and its simulator check) sees the tire only through a `Simulator`: a batch of log-parameter
vectors in, the target responses out. The shell-model implementation lives with the batched
runner (`calibration.tire.shell.make_simulator`); the tests use cheap stand-ins (`calibration.tire.standin`).

Contract (what an implementation must provide):

    space: ParamSpace                       the free parameters; theta = ln(SI value), shape (d,)
    response_names: tuple[str, ...]         the m responses, in the order of the targets
    cost_forward_equivalents: dict          {"evaluate": cost of one point, "jacobian": cost of
                                            one jacobian call}, in forward runs of one point;
                                            for reporting and the LM budget; may be updated by
                                            each call (a measured price is read after it)
    evaluate(thetas (n, d)) -> (n, m)       SI responses of one batch (a calibration iteration's
                                            design points run together); a point whose run
                                            failed is a row of nan (the batch goes on)
    points_per_call: int                    how many points one evaluate call should hold for
                                            full speed (0: any number). Long jobs (ARSM's history,
                                            the posterior check) call evaluate in pieces of this
                                            size and save each piece as it returns, so a kill
                                            loses at most one piece
    last_failures: dict                     optional: after evaluate, {row: {target: message}} of
                                            the points whose run failed (recorded in the history)
    jacobian(theta (d,), quantities=None) -> (values (q,), J (q, d))
                                            d(quantity)/d(theta) by autodiff at one point;
                                            quantities=None means response_names; any other name
                                            the simulator knows is allowed (sensitivity tables);
                                            may raise NotImplementedError
    for_targets(targets) -> Simulator|None  the same model over other targets (optional; None:
                                            not available), for the config's [checks]
    fingerprint() -> dict                   JSON-able description of everything besides the
                                            calibration config that fixes the numbers (mesh,
                                            solver settings, model version); stored with a
                                            run's outputs so that a rerun on another model
                                            refuses instead of mixing results

Batch semantics: evaluate must return the same row for the same theta whatever else is in the
batch (a resumed calibration re-evaluates only the points it had not recorded).
"""

import abc

import numpy as np

from .space import ParamSpace

__all__ = ["Simulator", "check_batch", "pieces"]


class Simulator(abc.ABC):
    """Abstract simulator (see the module docstring for the contract)."""

    space: ParamSpace
    response_names: tuple
    cost_forward_equivalents: dict = {"evaluate": 1.0, "jacobian": float("nan")}
    points_per_call: int = 0

    @abc.abstractmethod
    def evaluate(self, thetas) -> np.ndarray:
        """thetas (n, d) log-parameters -> responses (n, m), SI; a failed point is a nan row."""

    def jacobian(self, theta, quantities=None):
        """theta (d,) -> (values (q,), J (q, d) = d value / d theta); autodiff."""
        raise NotImplementedError(f"{type(self).__name__}: no Jacobian")

    def fingerprint(self) -> dict:
        return {"simulator": type(self).__name__}

    def for_targets(self, targets):
        """A simulator of the same model and free parameters over other targets (the config's
        [checks]), or None where this simulator cannot simulate them."""
        return None


def check_batch(sim: Simulator, thetas, values) -> np.ndarray:
    """A simulator's batch answer as a float array (n, m), or a clear error if malformed."""
    values = np.asarray(values, dtype=float)
    n, m = np.shape(thetas)[0], len(sim.response_names)
    if values.shape != (n, m):
        raise RuntimeError(f"{type(sim).__name__}.evaluate returned shape {values.shape} for "
                           f"{n} points; must be ({n}, {m})")
    return values


def pieces(sim: Simulator, n: int) -> list:
    """Index ranges [(start, stop), ...] covering n points in evaluate calls of the simulator's
    points_per_call (one range when it is 0)."""
    per = int(getattr(sim, "points_per_call", 0) or 0)
    per = n if per <= 0 else per
    return [(s, min(s + per, n)) for s in range(0, n, max(per, 1))]
