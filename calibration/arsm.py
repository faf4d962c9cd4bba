"""Adaptive response surface method (ARSM) for bounded black-box minimization.

The loop (Wang, Dong & Aitchison 2001, with the inherited designs of Wang 2003):

1. Initial design in the unit box: a small Latin hypercube (2d + 1 points by default, the
   fewest that fix a reduced quadratic), improved for centred discrepancy, seeded.
2. Fit a quadratic response surface to the points inside the current region (inherited), topped
   up with the nearest outside points when the region holds too few (already paid for, so they
   cost no calls). The richest basis the points determine is used.
3. Move the region: ARSM keeps the bounding box of the part of the region where the surface is
   at or below the second-best value seen; SRSM (Stander & Craig 2002) pans and zooms around the
   best point. Both keep the best point inside and a minimum width.
4. Evaluate ONE new point: the surface's minimizer in the region, or a space-filling point when
   that minimizer repeats a point already evaluated (the surface has nothing new to say there).
5. Stop on the budget, on the region reaching its minimum width, or when the surface predicts
   the value at its minimizer to within `tol` times the initial spread of values (the surface
   agrees with the truth where it matters).

Variables keep their physical units outside; inside, everything is in unit coordinates of
[lower, upper], so the method treats a density in kg/m^3 and a modulus in Pa alike.
Every call goes through `calibration.history.Evaluator`: it is appended to the history file as
it returns, and a killed run resumes by replaying the file (the loop is deterministic given seed).
"""

import numpy as np

from calibration.history import BudgetExhausted, Evaluator, OptimizeResult
from jtire.errors import ConfigError
from surrogates import (
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


def _on_inner_face(u, region, rel=1e-2):
    """u sits on a face of the region that is not a face of the unit box (the optimum may lie
    beyond it, so agreement of surface and truth there does not mean convergence)."""
    lo = (u - region.lower <= rel * region.width) & (region.lower > 0)
    hi = (region.upper - u <= rel * region.width) & (region.upper < 1)
    return bool(np.any(lo | hi))


import os
_W = os.environ.get("ARSM_W", "none")


def _weights(fi):
    if _W == "none":
        return None
    lo = fi.min()
    s = np.median(fi) - lo
    if s <= 0:
        return None
    r = (fi - lo) / s
    if _W == "inv":
        return 1.0 / (1.0 + r)
    if _W == "inv2":
        return 1.0 / (1.0 + r) ** 2
    if _W == "exp":
        return np.exp(-r)


_T = os.environ.get("ARSM_T", "none")
_Z = os.environ.get("ARSM_Z", "1") == "1"


def _agrees(surf, u, f, region, x_new, pred, f_new, tol):
    """Surface and truth agree: at the new point to tol, and at every fitted point inside the
    region (leave-one-out, where defined) to sqrt(tol), both relative to the spread of the values inside the
    region; and the new point is not on a face the region could still pan across."""
    inside = surf.idx[inherit(u[surf.idx], region)]
    if inside.size == 0 or _on_inner_face(x_new, region):
        return False
    spread = float(np.ptp(np.append(f[inside], f_new)))
    loo = surf.loo_residuals[np.isin(surf.idx, inside)]
    loo = loo[np.isfinite(loo)]  # an interpolated point has no leave-one-out residual
    return bool(abs(pred - f_new) <= tol * spread and np.all(np.abs(loo) <= np.sqrt(tol) * spread))


def _fit(u, f, region, n_want):
    if _T == "square":
        f = f**2
    idx = _fit_set(u, f, region, n_want)
    if idx.size < u.shape[1] + 1:
        return None  # too many failed calls to fit even a plane
    s = fit_quadratic(u[idx], f[idx], region.lower, region.upper, weights=_weights(f[idx]))
    object.__setattr__(s, "idx", idx)
    object.__setattr__(s, "spread", float(np.ptp(f[idx])))
    return s


def minimize(
    fun,
    lower,
    upper,
    budget: int,
    seed: int,
    history_path=None,
    n_initial: int | None = None,
    min_width: float = 1e-4,
    tol: float = 1e-6,
    region_rule: str = "arsm",
    min_shrink: float = 0.5,
    f_target: float | None = None,
    n_fill: int | None = None,
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
        min_width: smallest region width, unit coordinates; the run stops when every width
            has reached it.
        tol: stop when |surface prediction - value| at the surface minimizer is at most
            tol * (spread of the initial values) and the fit's leave-one-out RMS error at most
            sqrt(tol) times that spread (agreement of surface and truth); 0 disables.
        region_rule: "arsm" (Wang et al. 2001) or "srsm" (Stander & Craig 2002).
        min_shrink: ARSM safeguard, the smallest factor one update may scale a width by.
        f_target: stop as soon as a value <= f_target is found (None: never).
        n_fill: when the region holds fewer points than this, an iteration first evaluates one
            space-filling point in it (default 2d + 1; 0 never fills).
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
    method = "arsm" if region_rule == "arsm" else "srsm"
    ev = Evaluator(fun, lower, upper, method, seed, budget, history_path)
    # Fit on the full quadratic once the budget can afford its points, else on the reduced one.
    p_full = n_terms(d, "full")
    n_want = p_full + 1 if p_full + 1 <= budget // 2 else n_terms(d, "reduced")
    n_local = n_terms(d, "reduced") if n_fill is None else int(n_fill)

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
        return evaluate(x[0], phase="fill", region=[region.lower.tolist(), region.upper.tolist()])

    region = Region.unit(d)
    try:
        for u in latin_hypercube(n0, d, seed, optimization="random-cd"):
            evaluate(u, phase="initial")
        ok = np.isfinite(f_list)
        f_scale = float(np.ptp(np.asarray(f_list)[ok])) if ok.sum() > 1 else 0.0
        it = 0
        failed = False
        while True:
            u, f = np.array(u_list), np.array(f_list, dtype=float)
            best = int(np.argmin(np.where(np.isfinite(f), f, np.inf)))
            surf = _fit(u, f, region, n_want)
            if region_rule == "arsm" and surf is not None:
                region = arsm_update(region, surf, second_best(f**2 if _T == 'square' else f), u[best],
                                     _sub_seed(seed, it, 1), min_width, min_shrink, zoom=failed and _Z)
            # A local fit needs local points: when the region holds fewer than a reduced
            # quadratic's worth, spend one call on a space-filling point inside it first.
            if np.sum(inherit(u, region) & np.isfinite(f)) < n_local:
                fill(region, it)
                u, f = np.array(u_list), np.array(f_list, dtype=float)
            surf = _fit(u, f, region, n_want)
            if surf is None:  # failed calls left too few points for even a plane
                fill(region, it)
            else:
                best = int(np.argmin(np.where(np.isfinite(f), f, np.inf)))
                x_new, pred = surf.argmin(region.lower, region.upper, _sub_seed(seed, it, 2),
                                          starts=u[best])
                if np.min(np.max(np.abs(u - x_new) / region.width, axis=1)) < _MIN_SEPARATION:
                    fill(region, it)  # the surface points at a known point: explore instead
                else:
                    f_best = float(np.min(np.where(np.isfinite(f), f, np.inf)))
                    f_new = evaluate(x_new, phase="minimizer", pred=pred, kind=surf.kind,
                                     region=[region.lower.tolist(), region.upper.tolist()])
                    failed = not (f_new < f_best)
                    # agreement: at the minimizer to tol, over the fitted points (leave-one-out)
                    # to sqrt(tol), and not on a face the region could still pan across
                    if tol > 0 and np.isfinite(f_new) and _agrees(surf, u, f, region, x_new,
                                                                  pred, f_new, tol):
                        raise _Stop("agreement")
            if region_rule == "srsm":
                f = np.array(f_list, dtype=float)
                best = int(np.argmin(np.where(np.isfinite(f), f, np.inf)))
                region = srsm_update(region, u_list[best], min_width=min_width)
            if np.all(region.width <= min_width * (1 + 1e-9)):
                raise _Stop("region")
            it += 1
    except BudgetExhausted:
        reason = "budget"
    except _Stop as s:
        reason = str(s)
    return ev.result(reason)


class _Stop(Exception):
    """Internal: a stopping rule fired (the message is the stop reason)."""
