"""Adaptive response surface method (ARSM) for bounded black-box minimization.

The loop (Wang, Dong & Aitchison 2001, with the inherited designs of Wang 2003):

1. Initial design in the unit box: a small Latin hypercube (2d + 1 points by default, the
   fewest that fix a reduced quadratic), improved for centred discrepancy, seeded.
2. Fit a quadratic response surface to the points inside the current region (inherited), topped
   up with the nearest outside points when the region holds too few (already paid for, so they
   cost no calls). The richest basis the points determine is used.
3. Move the region: ARSM keeps the bounding box of the part of the region where the surface is
   at or below the second-best value seen; SRSM (Stander & Craig 2002) pans and zooms around the
   best point. Safeguards (region.py): the best point stays inside; a width never drops below
   `min_width` nor below `min_shrink` times its old value in one step; after a proposal that
   failed to improve, the region zooms on the best point (the data are trusted over the
   surface); when the best point sits on an inner face, the region pans across it and grows.
4. Evaluate ONE new point: the surface's minimizer in the region, or a space-filling point when
   that minimizer repeats a point already evaluated (the surface has nothing new to say there)
   or, optionally, when the region holds fewer than `n_fill` points.
5. Stop on the budget, on the region reaching its minimum width, or when surface and truth
   agree on two proposals in a row (`_agrees`: at the new interior minimizer, and
   leave-one-out at the fitted points).

Variables keep their physical units outside; inside, everything is in unit coordinates of
[lower, upper], so the method treats a density in kg/m^3 and a modulus in Pa alike.
Every call goes through `calibration.history.Evaluator`: it is appended to the history file as
it returns, and a killed run resumes by replaying the file (the loop is deterministic given seed).
"""

import numpy as np

from .history import BudgetExhausted, Evaluator, OptimizeResult
from ..errors import ConfigError
from ..surrogates import (
    Region,
    arsm_update,
    as_bounds,
    fit_quadratic,
    inherit,
    latin_hypercube,
    maximin_fill,
    n_terms,
    second_best,
    srsm_update,
    to_bounds,
)

__all__ = ["minimize"]

_RULES = ("arsm", "srsm")
# A proposed point closer than this (in widths of the current region, max-norm) to one already
# evaluated brings no new information; a space-filling point is evaluated instead.
_MIN_SEPARATION = 1e-3
# Monotone maps of the values the surfaces are fitted to, and their inverses (for the records).
_TRANSFORMS = {"none": lambda f: f, "square": lambda f: f * np.abs(f)}
_UNTRANSFORMS = {"none": lambda h: h, "square": lambda h: np.sign(h) * np.sqrt(np.abs(h))}
# Agreement must hold on this many consecutive proposals: a fit with one spare point can show
# small residuals by chance; twice in a row is a real sign of convergence.
_N_AGREE = 2


def _sub_seed(seed, it, salt):
    """Deterministic per-iteration seed for the dense samples (no clock, no global state)."""
    return int(np.random.SeedSequence([int(seed), int(it), int(salt)]).generate_state(1)[0])


def _fit_set(u, f, region, n_want):
    """Indices of the points to fit: all finite ones inside the region, then the nearest
    outside ones (distance to the box, in region widths) until there are n_want."""
    ok = np.isfinite(f)
    inside = inherit(u, region) & ok
    idx = list(np.flatnonzero(inside))
    if len(idx) < n_want:
        gap = np.maximum(region.lower - u, 0) + np.maximum(u - region.upper, 0)
        dist = np.linalg.norm(gap / region.width, axis=1)
        outside = np.flatnonzero(~inside & ok)
        idx += list(outside[np.argsort(dist[outside], kind="stable")][: n_want - len(idx)])
    return np.array(sorted(idx), dtype=int)


def _on_face(u, region, rel=1e-2):
    """u lies within rel region widths of a face of the region."""
    return bool(np.any((u - region.lower <= rel * region.width)
                       | (region.upper - u <= rel * region.width)))


def _agrees(surf, idx, u, f, region, x_new, pred, f_new, tol):
    """Surface and truth agree: the surface predicts the new point to tol and every point it was
    fitted to (leave-one-out, which must be defined everywhere: no point may fix its own
    coefficient) to sqrt(tol), relative to the spread of those values; and the new point lies
    inside the region, not on a face (a constrained minimum of the surface says nothing about
    convergence)."""
    if _on_face(x_new, region) or not np.all(np.isfinite(surf.loo_residuals)):
        return False
    spread = float(np.ptp(np.append(f[idx], f_new)))
    return bool(abs(pred - f_new) <= tol * spread
                and np.all(np.abs(surf.loo_residuals) <= np.sqrt(tol) * spread))


def _fit(u, f, region, n_want):
    """(surface, indices of the fitted points), or None when too few finite values remain."""
    idx = _fit_set(u, f, region, n_want)
    if idx.size < u.shape[1] + 1:
        return None
    return fit_quadratic(u[idx], f[idx], region.lower, region.upper), idx


def minimize(
    fun,
    lower,
    upper,
    budget: int,
    seed: int,
    history_path=None,
    n_initial: int | None = None,
    min_width: float = 1e-4,
    tol: float = 1e-3,
    region_rule: str = "arsm",
    min_shrink: float = 0.5,
    pan_growth: float = 2.0,
    n_fill: int = 0,
    f_target: float | None = None,
    transform: str = "none",
) -> OptimizeResult:
    """Minimize fun over the box [lower, upper] with at most `budget` calls.

    Args:
        fun: x (d,) in physical units -> float. A SimulationError from it is recorded as a
            failed call (f = null) and the point is left out of the fits.
        lower, upper: (d,) bounds, physical units.
        budget: maximum number of calls of fun (replayed calls included).
        seed: seeds the initial design and the dense samples; same seed, same run.
        history_path: JSON-lines file; appended per call, replayed on resume.
        n_initial: size of the initial Latin hypercube (default 2d + 1).
        min_width: smallest region width, unit coordinates; the run stops ("region") when
            every width has reached it.
        tol: agreement stop, on two proposals in a row: the surface predicts the value at its
            (interior) minimizer to tol and its fitted points (leave-one-out) to sqrt(tol),
            relative to the spread of the fitted values; 0 disables.
        region_rule: "arsm" (Wang et al. 2001) or "srsm" (Stander & Craig 2002).
        min_shrink: ARSM: the smallest factor one update may scale a width by; also the zoom
            factor after a proposal that failed to improve.
        pan_growth: ARSM: width factor when the region pans across a face (see region.py).
        n_fill: when the region holds fewer finite points than this, an iteration first
            evaluates one space-filling point in it (0: only when the surface proposes a
            point already evaluated).
        f_target: stop ("target") as soon as a value <= f_target is found (None: never).
        transform: "none", or "square": fit the surfaces to f|f| instead of f. It changes no
            ranking (so neither the best point nor the threshold's sub-level set), and when f
            is an absolute error |g| with g smooth it turns the V-shaped valley of f into the
            smooth g^2, which a quadratic can follow.
    Returns:
        OptimizeResult; stop_reason is "budget", "region", "agreement" or "target".
    """
    lower, upper = as_bounds(lower, upper)
    d = lower.size
    if region_rule not in _RULES:
        raise ConfigError(f"region_rule = {region_rule!r}: must be one of {_RULES}")
    if not tol >= 0:
        raise ConfigError(f"tol = {tol}: must be >= 0")
    n0 = 2 * d + 1 if n_initial is None else int(n_initial)
    if not d + 1 <= n0 <= int(budget):
        raise ConfigError(f"n_initial = {n0}: must be in [{d + 1}, budget = {budget}] (d = {d})")
    if transform not in _TRANSFORMS:
        raise ConfigError(f"transform = {transform!r}: must be one of {sorted(_TRANSFORMS)}")
    if not pan_growth >= 1.0:
        raise ConfigError(f"pan_growth = {pan_growth}: must be >= 1")
    ev = Evaluator(fun, lower, upper, region_rule, seed, budget, history_path)
    # Fit the full quadratic once the budget can afford its points, else the reduced one.
    p_full = n_terms(d, "full")
    n_want = p_full + 1 if p_full + 1 <= budget // 2 else n_terms(d, "reduced")
    u_list, f_list = [], []

    def evaluate(u, **extras):
        f = ev(to_bounds(u, lower, upper), **extras)
        u_list.append(np.asarray(u, dtype=float))
        f_list.append(f)
        if f_target is not None and np.isfinite(f) and f <= f_target:
            raise _Stop("target")
        return f

    def fill(region, it):
        x = maximin_fill(1, np.array(u_list), region.lower, region.upper, _sub_seed(seed, it, 3))
        evaluate(x[0], phase="fill", region=[region.lower.tolist(), region.upper.tolist()])

    def data():
        """Points, fitted values (transformed) and the index of the best point."""
        f = _TRANSFORMS[transform](np.array(f_list, dtype=float))
        return np.array(u_list), f, int(np.argmin(np.where(np.isfinite(f), f, np.inf)))

    region = Region.unit(d)
    failed = False  # did the last proposal fail to improve on the best point?
    agree = 0  # consecutive proposals on which surface and truth agreed
    try:
        for u in latin_hypercube(n0, d, seed, optimization="random-cd"):
            evaluate(u, phase="initial")
        for it in range(10 * int(budget)):  # each pass evaluates at least one point
            u, f, best = data()
            fit = _fit(u, f, region, n_want)
            if region_rule == "arsm" and fit is not None:
                region = arsm_update(region, fit[0], second_best(f), u[best],
                                     _sub_seed(seed, it, 1), min_width, min_shrink,
                                     zoom=failed, pan_growth=pan_growth)
            if np.sum(inherit(u, region) & np.isfinite(f)) < n_fill:
                fill(region, it)
                u, f, best = data()
            fit = _fit(u, f, region, n_want)
            if fit is None:  # failed calls left too few points for even a plane
                fill(region, it)
            else:
                surf, idx = fit
                x_new, pred = surf.argmin(region.lower, region.upper, _sub_seed(seed, it, 2),
                                          starts=u[best])
                near = np.max(np.abs(u - x_new) / region.width, axis=1)
                if near.min() < _MIN_SEPARATION:
                    # the surface points at a known point: explore instead. If that point is the
                    # best one and the surface agrees with the data there, it counts towards
                    # the agreement stop (an exact surface keeps pointing at its minimum).
                    on_best = int(np.argmin(near)) == best
                    agree = (agree + 1 if tol > 0 and on_best and _agrees(
                        surf, idx, u, f, region, u[best], pred, f[best], tol) else 0)
                    if agree >= _N_AGREE:
                        raise _Stop("agreement")
                    fill(region, it)
                    failed = True
                else:
                    f_new = _TRANSFORMS[transform](evaluate(
                        x_new, phase="minimizer", pred=_UNTRANSFORMS[transform](pred),
                        kind=surf.kind, region=[region.lower.tolist(), region.upper.tolist()]))
                    failed = not f_new < f[best]
                    agree = (agree + 1 if tol > 0 and np.isfinite(f_new) and _agrees(
                        surf, idx, u, f, region, x_new, pred, f_new, tol) else 0)
                    if agree >= _N_AGREE:
                        raise _Stop("agreement")
            if region_rule == "srsm":
                u, f, best = data()
                region = srsm_update(region, u[best], min_width=min_width)
            if np.all(region.width <= min_width * (1 + 1e-9)):
                raise _Stop("region")
        reason = "budget"
    except BudgetExhausted:
        reason = "budget"
    except _Stop as s:
        reason = str(s)
    return ev.result(reason)


class _Stop(Exception):
    """Internal: a stopping rule fired (the message is the stop reason)."""
