"""ARSM for several responses: one surface per target response, batches of design points.

The study fitted one quadratic to its total error, a sum of absolute percentage errors: a
kinked function (each |.| has a V along a surface in parameter space) that no quadratic
follows, and whose quadratic needs (d + 1)(d + 2) / 2 points. Here each response (DZ, DY, FX1,
FX2) gets its own smooth surface in ln(response) over the unit box of ln(parameters), and the
kinked objective is built from them exactly:

    P(u) = sum_i w_i 100 |exp(s_i(u)) / t_i - 1|

The loop (deterministic given seed and the values seen, so a killed run resumes by replay):

1. Initial batch: the base tire and a Latin hypercube (seeded, centred discrepancy) in the
   initial region, n_initial points (default d + 2: a linear surface per response plus one
   point to spare for leave-one-out).
2. Fit the surfaces (kind: response_surfaces) to the finite points in the region, topped up
   with the nearest ones outside (already paid for).
3. Move the region. "arsm": the bounding box of the part of the region where P is at or below
   the second-best total error (surrogates.region.arsm_update, with its safeguards: the best
   point stays inside, widths shrink by at most min_shrink per step, zoom on the best point
   after a proposal that failed, pan across an inner face). "trust": a box of half-width r about
   the best point, r doubled when a proposal on the box's edge did at least 3/4 of what P
   promised, halved when it did less than 1/4.
4. Propose: the minimizer of P in the region (L-BFGS-B on a smoothed |.| from the best point,
   the region centre and the best of a Sobol sample), with a tiny pull towards the best point so
   that among the many parameter sets that zero all errors (4 targets, 15+ parameters) the
   one closest to the data is taken. batch_size - 1 further points fill the region (maximin)
   to keep the surfaces determined as it shrinks. The batch is evaluated at once.
5. Stop on the budget (evaluations), on tol_percent, or when every width reaches min_width.

Surface kind: compared on the STAND-IN simulator (benchmarks/bench_calibration_arsm.py; the results:
docs/design-notes.md). At d = 20 the per-response kinds tie within their spread (a reduced quadratic
is fitted only once 2d + 2 = 42 points exist; before that it is linear, and linear in ln-ln is
already good on power-law responses); all beat one quadratic of the kinked sum by an order of
magnitude. Where the points can fix curvature (d = 4) the reduced quadratic is best by another
order. Default: "reduced" with the "arsm" region rule (the study's rule). Distance-weighted fits on
every point (rather than the region's points topped up with the nearest, calibration.arsm's rule)
and local fill points were chosen the same way.
"""

import dataclasses

import numpy as np
from scipy.optimize import least_squares
from scipy.optimize import minimize as _scipy_minimize

from ..arsm import _fit_set, _sub_seed
from .response_surfaces import KINDS, fit_responses, terms
from .runlog import BudgetExhausted, RunLog
from ...errors import ConfigError
from ...surrogates import Region, arsm_update, latin_hypercube, maximin_fill, second_best, sobol

__all__ = ["CalibrationResult", "calibrate_arsm", "DEFAULT_SURFACE", "RULES"]

DEFAULT_SURFACE = "reduced"
RULES = ("arsm", "trust")
# |x| is smoothed as sqrt(x^2 + eps^2) for the proposal's polish (relative units: 1e-3 is
# 0.1 %, well below the errors the study could resolve; smaller makes L-BFGS-B crawl).
_EPS = 1e-3
# Pull towards the best point, in percent per unit squared distance: breaks ties between the
# exact solutions of an under-determined problem without moving a unique minimizer measurably.
_PULL = 1e-3
# A proposal within this many region widths (max-norm) of a known point brings nothing new.
_MIN_SEPARATION = 1e-3
_N_STARTS = 4


@dataclasses.dataclass(frozen=True)
class CalibrationResult:
    """What a calibration run returns.

    theta: (d,) best log-parameters; values: (m,) its responses (SI); errors_pct: (m,);
    total_error_pct: the objective there; n_evaluations: simulator points used (replayed
    included); n_jacobians: Jacobian calls; n_batches; cost_forward: forward-run equivalents (Jacobians included);
    wall_s: simulator wall time of the records; stop_reason; records: the history records.
    """

    theta: np.ndarray
    values: np.ndarray
    errors_pct: np.ndarray
    total_error_pct: float
    n_evaluations: int
    n_jacobians: int
    n_batches: int
    cost_forward: float
    wall_s: float
    stop_reason: str
    method: str
    records: list


def result_from_log(log: RunLog, reason: str) -> CalibrationResult:
    recs = log.records
    tot = np.array([np.inf if r["total_error_pct"] is None else r["total_error_pct"] for r in recs])
    names = [t.name for t in log.targets]
    if recs and np.isfinite(tot).any():
        k = int(np.argmin(tot))
        r = recs[k]
        theta = np.array(r["theta"])
        vals = np.array([r["responses"][n] for n in names], float)
        errs = np.array([r["errors_pct"][n] for n in names], float)
        total = float(tot[k])
    else:
        theta = np.full(log.sim.space.d, np.nan)
        vals = errs = np.full(len(names), np.nan)
        total = float("inf")
    n_jac = sum(1 for r in recs if "jacobian" in r)
    return CalibrationResult(theta, vals, errs, total, log.n_evaluations, n_jac, log.n_batches,
                             log.cost_forward, log.wall_s, reason, log.method, list(recs))


class _Objective:
    """P(u) from per-response surfaces of ln(response); value and gradient (smoothed)."""

    def __init__(self, surfaces, log_targets, weights):
        self.s, self.lt, self.w = surfaces, np.asarray(log_targets), np.asarray(weights)

    def predict(self, u):
        """Exact P (percent) at u (n, d) -> (n,)."""
        s = np.stack([f.predict(u) for f in self.s], axis=-1)
        return np.sum(self.w * 100.0 * np.abs(np.exp(s - self.lt) - 1.0), axis=-1)

    def smooth(self, u, anchor):
        u = np.atleast_2d(u)
        s = np.stack([f.predict(u) for f in self.s], axis=-1)[0]
        g = np.stack([f.gradient(u)[0] for f in self.s])  # (m, d)
        r = np.exp(s - self.lt) - 1.0
        a = np.sqrt(r**2 + _EPS**2)
        val = np.sum(self.w * 100.0 * a) + _PULL * np.sum((u[0] - anchor) ** 2)
        grad = (self.w * 100.0 * r / a * (r + 1.0)) @ g + 2 * _PULL * (u[0] - anchor)
        return val, grad


def _propose(obj, region, best_u, seed):
    """argmin of P over the region; returns (u, P(u)).

    Least squares on the log-residuals s_i(u) - ln t_i (relative errors to first order; a
    zero of every error is a zero of both), from several starts (the best point, the region
    centre, the best of a Sobol sample), bounded by the region (scipy trf); then the smoothed
    |.| sum polished by L-BFGS-B from the best of them (when the targets cannot all be met, L1
    and least squares part ways). The exact P decides.
    """
    cand = region.lower + sobol(256, region.lower.size, seed) * region.width
    starts = [np.clip(best_u, region.lower, region.upper), region.centre]
    starts += list(cand[np.argsort(obj.predict(cand))[:_N_STARTS - 2]])
    pull = np.sqrt(_PULL / 100.0)
    sw = np.sqrt(obj.w)

    def resid(u):
        s = np.array([f.predict(u)[0] for f in obj.s])
        return np.concatenate([sw * (s - obj.lt), pull * (u - best_u)])

    def jac(u):
        g = np.stack([f.gradient(u)[0] for f in obj.s])
        return np.concatenate([sw[:, None] * g, pull * np.eye(u.size)])

    def score(x):
        return float(obj.predict(x)[0]) + _PULL * float(np.sum((x - best_u) ** 2))

    lo, hi = region.lower, region.upper
    tight = hi - lo <= 0
    hi = np.where(tight, lo + 1e-12, hi)  # least_squares needs lo < hi
    sols = []
    for x0 in starts:
        res = least_squares(resid, np.clip(x0, lo, hi), jac=jac, bounds=(lo, hi), method="trf",
                            max_nfev=100)
        sols.append(np.clip(res.x, region.lower, region.upper))
    best = min(sols, key=score)
    res = _scipy_minimize(obj.smooth, best, args=(best_u,), jac=True, method="L-BFGS-B",
                          bounds=list(zip(region.lower, region.upper)), options={"maxiter": 100})
    polished = np.clip(res.x, region.lower, region.upper)
    if score(polished) < score(best):
        best = polished
    return best, float(obj.predict(best)[0])


FILLS = ("local", "region")
WEIGHTINGS = ("distance", "nearest")


def _fit_points(u, ok, region, n_want, weighting):
    """(indices, weights) of the points a surface is fitted to.

    "nearest": the points in the region, topped up with the nearest outside ones until there
    are n_want (calibration.arsm's rule), equal weights. "distance": every finite point, with
    weight 1 / (1 + g^2), g its distance outside the region in region widths (max-norm): all the
    information paid for is used, the region's points dominate.
    """
    if weighting == "nearest":
        idx = _fit_set(u, np.where(ok, 0.0, np.nan), region, n_want)
        return idx, None
    idx = np.flatnonzero(ok)
    gap = np.maximum(region.lower - u[idx], 0) + np.maximum(u[idx] - region.upper, 0)
    g = np.max(gap / np.maximum(region.width, 1e-12), axis=1)
    return idx, 1.0 / (1.0 + g**2)


def _fill(kind, n, u, centre, region, seed):
    """n extra points of a batch: "region": maximin in the whole region; "local": maximin in a
    box of a quarter of the region's widths about `centre` (the proposal), inside the region,
    so that the next surfaces see the neighbourhood of the point they proposed."""
    if kind == "region":
        return maximin_fill(n, u, region.lower, region.upper, seed)
    half = 0.125 * region.width
    lo = np.clip(centre - half, region.lower, region.upper - 2 * half)
    return maximin_fill(n, u, lo, lo + 2 * half, seed)


def calibrate_arsm(sim, targets, log: RunLog, seed: int = 0, batch_size: int = 4,
                   n_initial: int = 0, surface: str = DEFAULT_SURFACE, region_rule: str = "arsm",
                   min_width: float = 1e-3, min_shrink: float = 0.5, initial_width: float = 1.0,
                   tol_percent: float = 0.0, weights=None, fill: str = "local",
                   weighting: str = "distance", progress=None) -> CalibrationResult:
    """Multi-response ARSM (module docstring) through `log` (budget, history, replay).

    sim: Simulator (its space fixes d and the box); targets: the Targets (measured values);
    batch_size: points per iteration after the initial batch; n_initial: initial batch (0:
    d + 2); initial_width: the first region's width in unit coordinates, about the base tire;
    progress: optional callable(result-so-far) after each batch.
    """
    space = sim.space
    d, m = space.d, len(targets)
    if surface not in KINDS:
        raise ConfigError(f"arsm.surface = {surface!r}: must be one of {KINDS}")
    if weighting not in WEIGHTINGS:
        raise ConfigError(f"arsm.weighting = {weighting!r}: must be one of {WEIGHTINGS}")
    if fill not in FILLS:
        raise ConfigError(f"arsm.fill = {fill!r}: must be one of {FILLS}")
    if region_rule not in RULES:
        raise ConfigError(f"arsm.region_rule = {region_rule!r}: must be one of {RULES}")
    n0 = d + 2 if not n_initial else int(n_initial)
    if not 2 <= n0 <= log.budget:
        raise ConfigError(f"arsm.n_initial = {n0}: must be in [2, budget = {log.budget}]")
    w = np.ones(m) if weights is None else np.asarray(weights, float)
    lt = np.log([t.measured for t in targets])
    u0 = space.to_unit(space.default)
    half = 0.5 * float(initial_width)
    lo0 = np.clip(u0 - half, 0.0, 1.0 - 2 * half)
    region = Region(lo0, lo0 + 2 * half) if half < 0.5 else Region.unit(d)
    n_want = terms(surface, d, m) + 1
    U, Y = [], []  # unit coordinates and responses of every evaluated point

    def run(batch_u, phase, extras=None):  # noqa: E306
        batch_u = np.atleast_2d(batch_u)[: log.remaining]
        if batch_u.shape[0] == 0:
            raise BudgetExhausted("budget")
        y = log.evaluate(space.from_unit(batch_u), phase, extras)
        U.extend(batch_u), Y.extend(y)
        if progress is not None:
            progress(result_from_log(log, "running"))
        return y

    def totals():
        y = np.array(Y)
        with np.errstate(invalid="ignore"):
            f = np.sum(w * 100.0 * np.abs(y / np.exp(lt) - 1.0), axis=1)
        return np.where(np.all(np.isfinite(y), axis=1), f, np.nan)

    reason, failed, radius = "budget", False, half
    try:
        design = region.lower + latin_hypercube(n0, d, seed, "random-cd") * region.width
        design[0] = u0  # the base tire is always evaluated: the errors before calibration
        run(design, "initial")
        for it in range(10 * log.budget):
            u, f = np.array(U), totals()
            if np.nanmin(f) <= tol_percent:
                reason = "target"
                break
            ok = np.isfinite(f)
            best = int(np.nanargmin(f))
            idx, wts = _fit_points(u, ok, region, n_want, weighting)
            surfaces = fit_responses(u[idx], np.log(np.array(Y)[idx]), surface,
                                     region.lower, region.upper, wts)
            obj = _Objective(surfaces, lt, w)
            if region_rule == "arsm":
                region = arsm_update(region, obj, second_best(f[ok]), u[best],
                                     _sub_seed(seed, it, 1), min_width, min_shrink, zoom=failed)
            else:
                c = u[best]
                lo = np.clip(c - radius, 0.0, 1.0)
                region = Region(lo, np.clip(c + radius, 0.0, 1.0))
            x_new, pred = _propose(obj, region, u[best], _sub_seed(seed, it, 2))
            near = np.max(np.abs(u - x_new) / np.maximum(region.width, 1e-12), axis=1)
            extras = [{"pred_total_error_pct": pred, "kind": surfaces[0].kind,
                       "region": [region.lower.tolist(), region.upper.tolist()]}]
            reg = {"region": [region.lower.tolist(), region.upper.tolist()]}
            if near.min() < _MIN_SEPARATION:
                batch, phases, extras = np.empty((0, d)), [], []
                n_fill, centre = max(batch_size, 1), u[best]
            else:
                batch, phases, n_fill, centre = x_new[None], ["minimizer"], batch_size - 1, x_new
                extras = [{"pred_total_error_pct": pred, "kind": surfaces[0].kind, **reg}]
            if n_fill > 0:
                batch = np.concatenate([batch, _fill(fill, n_fill, u, centre, region,
                                                     _sub_seed(seed, it, 3))])
                phases += [f"fill_{fill}"] * n_fill
                extras += [reg] * n_fill
            f_best_old = f[best]
            k = min(len(batch), log.remaining)
            y = run(batch, phases[:k], extras[:k])
            f_new = totals()[-len(y):]
            got = np.nanmin(f_new) if np.isfinite(f_new).any() else np.inf
            failed = not got < f_best_old
            if region_rule == "trust":
                promised = f_best_old - pred
                rho = (f_best_old - got) / promised if promised > 0 else -1.0
                edge = np.max(np.abs(x_new - u[best])) >= 0.9 * radius
                radius = (min(2 * radius, 0.5) if rho >= 0.75 and edge
                          else 0.5 * radius if rho < 0.25 else radius)
                radius = max(radius, 0.5 * min_width)
            if np.all(region.width <= min_width * (1 + 1e-9)):
                reason = "region"
                break
    except BudgetExhausted:
        reason = "budget"
    return result_from_log(log, reason)
