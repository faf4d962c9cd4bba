"""Baseline optimizers a user would compare ARSM with, under the same rules.

Each has the signature of `calibration.arsm.minimize`:

    f(fun, lower, upper, budget, seed, history_path=None, **options) -> OptimizeResult

and goes through the same `Evaluator`: same bounds, same call budget, same history file
format, same resume by replay.

- `genetic_algorithm`: pymoo's single-objective GA (tournament selection, SBX crossover,
  polynomial mutation, duplicate elimination) on the unit box. The wrapped black box counts
  every evaluation pymoo asks for against the budget; the run ends when the budget is used.
- `monte_carlo`: uniform random search; `latin_hypercube_search`: a Latin hypercube of
  `budget` points evaluated in order (space-filling Monte Carlo).
"""

import numpy as np
from pymoo.algorithms.soo.nonconvex.ga import GA
from pymoo.core.problem import ElementwiseProblem
from pymoo.optimize import minimize as _pymoo_minimize

from ..history import BudgetExhausted, Evaluator, OptimizeResult
from ...errors import ConfigError
from ...surrogates import as_bounds, latin_hypercube, to_bounds

__all__ = ["genetic_algorithm", "monte_carlo", "latin_hypercube_search"]

# pymoo needs a number; a failed simulation must rank below every successful one.
_FAILED_VALUE = 1e300


class _UnitProblem(ElementwiseProblem):
    """pymoo view of the black box on [0, 1]^d; each evaluation goes through the Evaluator."""

    def __init__(self, evaluator: Evaluator, lower, upper):
        super().__init__(n_var=lower.size, n_obj=1, xl=0.0, xu=1.0)
        self._ev, self._lo, self._hi = evaluator, lower, upper

    def _evaluate(self, x, out, *args, **kwargs):
        f = self._ev(to_bounds(x, self._lo, self._hi), phase="ga")
        out["F"] = f if np.isfinite(f) else _FAILED_VALUE


def genetic_algorithm(
    fun, lower, upper, budget: int, seed: int, history_path=None, pop_size: int = 10
) -> OptimizeResult:
    """pymoo GA with population `pop_size` (offspring per generation = pop_size).

    The study does not give its GA settings; 10 individuals make 5 generations in 50 calls,
    a common choice for small budgets (pymoo's default of 100 would not finish one).
    """
    lower, upper = as_bounds(lower, upper)
    if not 2 <= int(pop_size) <= int(budget):
        raise ConfigError(f"ga pop_size = {pop_size}: must be in [2, budget = {budget}]")
    ev = Evaluator(fun, lower, upper, "ga", seed, budget, history_path)
    problem = _UnitProblem(ev, lower, upper)
    try:
        # n_eval termination is checked between generations; the Evaluator enforces the budget
        # exactly, so ask pymoo for more and stop on BudgetExhausted.
        _pymoo_minimize(problem, GA(pop_size=int(pop_size)), ("n_eval", 10 * int(budget)),
                        seed=int(seed), verbose=False)
        reason = "ga_converged"  # pymoo stopped on its own (e.g. no new non-duplicate offspring)
    except BudgetExhausted:
        reason = "budget"
    return ev.result(reason)


def _sample_search(method, design, fun, lower, upper, budget, seed, history_path):
    ev = Evaluator(fun, lower, upper, method, seed, budget, history_path)
    try:
        for u in design:
            ev(to_bounds(u, lower, upper), phase="sample")
    except BudgetExhausted:  # pragma: no cover (the design has exactly `budget` points)
        pass
    return ev.result("budget")


def monte_carlo(fun, lower, upper, budget: int, seed: int, history_path=None) -> OptimizeResult:
    """Uniform random search: `budget` independent uniform points in the box."""
    lower, upper = as_bounds(lower, upper)
    design = np.random.default_rng(int(seed)).uniform(size=(int(budget), lower.size))
    return _sample_search("mc", design, fun, lower, upper, budget, seed, history_path)


def latin_hypercube_search(
    fun, lower, upper, budget: int, seed: int, history_path=None
) -> OptimizeResult:
    """Latin hypercube search: one LHS of `budget` points, evaluated in order."""
    lower, upper = as_bounds(lower, upper)
    design = latin_hypercube(int(budget), lower.size, int(seed))
    return _sample_search("mc_lhs", design, fun, lower, upper, budget, seed, history_path)
