"""The check's correction of the emulator's predictive variance, and what its coverage can tell.

After a round of the posterior check (calibration.posterior.run), the check runs are held out k-fold and
the emulator's variance v is corrected per response so that a new run falls inside the corrected
90 % interval with probability >= 90 % (split conformal): a factor a v (`conformal_scale`), a floor
v + b (`conformal_floor`) or the wider of the two (`variance_correction`). COVERAGE_OK is the band
the issue asks of the observed coverage over 32 draws; `band_chance` says how often an exactly valid
correction lands in it.
"""

import numpy as np

from .emulator import fit_emulator

__all__ = ["calibrate_variance", "held_out_residuals", "variance_correction", "conformal_scale",
           "conformal_floor", "band_chance", "COVERAGE_OK"]

COVERAGE_OK = (0.80, 0.97)  # the band a 90 % interval's observed coverage over 32 draws should hit


def calibrate_variance(spec, thetas, y, extra_thetas, extra_y, level: float = 0.9,
                       form: str = "floor") -> tuple:
    """Per-response corrections of the predictive variance of an emulator trained on (thetas, y)
    plus the runs (extra_thetas, extra_y), by k-fold cross-validation over the extra runs only:
    each fold is predicted by an emulator trained on everything else, and the correction is split-
    conformal: a new run falls inside the corrected `level` interval with probability >= level.

    form "scale": variance v -> a v (`conformal_scale`). form "floor": v -> v + b, b >= 0
    (`conformal_floor`): an error that more runs do not shrink. form "wider": the wider of the two at
    each point, max(a v, v + b). Where the emulator is already wide enough (a <= 1) every form narrows
    it to a v. Why not the factor alone: each refined emulator trains on the runs it was checked on,
    so its own variance at the next draws (which land among them) is smaller than it was at the
    held-out runs, and a factor shrinks with it where the error (tied to parameters the emulator
    treats as inert) does not. Why not the floor alone: part of the held-out error is the
    emulator's own, which the added runs do remove. The held-out runs of one round cannot tell the
    two apart (docs/design-notes.md), so "wider" keeps the split-conformal guarantee under either:
    it is the conservative choice.

    Returns (a (m,), b (m,), z (k, m) held-out residuals in units of the uncorrected sd)."""
    r, v = held_out_residuals(spec, thetas, y, extra_thetas, extra_y)
    a, b = variance_correction(r, v, level, form)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = r / np.sqrt(v)
    return a, b, z


def held_out_residuals(spec, thetas, y, extra_thetas, extra_y) -> tuple:
    """k-fold held-out ln residuals r (k, m) and predictive variances v (k, m) of the extra runs:
    each fold (spec.check folds, seeded) predicted by an emulator trained on (thetas, y) and the
    other folds."""
    cal = spec.calibration
    names = [t.name for t in cal.targets]
    k = len(extra_thetas)
    folds = np.array_split(np.random.default_rng(spec.check["seed"]).permutation(k),
                           min(spec.check["folds"], k))
    r = np.full((k, len(names)), np.nan)
    v = np.full((k, len(names)), np.nan)
    for f in folds:
        rest = np.setdiff1d(np.arange(k), f)
        emu = fit_emulator(cal.space, names, np.vstack([thetas, extra_thetas[rest]]),
                           np.vstack([y, extra_y[rest]]), spec.candidates, spec.emulator_seed)
        mu, var = emu.predict(extra_thetas[f])
        with np.errstate(invalid="ignore", divide="ignore"):
            r[f], v[f] = np.log(extra_y[f]) - mu, var
    return r, v


def variance_correction(r, v, level: float = 0.9, form: str = "floor") -> tuple:
    """(a (m,), b (m,)) of `calibrate_variance`'s form from held-out residuals r and variances v (k, m)."""
    if form not in ("scale", "floor", "wider"):
        raise ValueError(f"form = {form!r}: 'scale', 'floor' or 'wider'")
    with np.errstate(invalid="ignore", divide="ignore"):
        z = r / np.sqrt(v)
    m = r.shape[1]
    a = np.clip([conformal_scale(z[:, j], level) for j in range(m)], 1e-4, 1e6)
    b = np.zeros(m)
    for j in range(m):
        if form != "scale" and a[j] > 1.0:
            b[j] = conformal_floor(r[:, j], v[:, j], level)
            a[j] = 1.0 if form == "floor" else a[j]
    return np.asarray(a, float), b


def conformal_floor(r, v, level: float = 0.9) -> float:
    """The smallest b >= 0 with which held-out residuals r (n,) of predictive variances v (n,) give
    split-conformal coverage: the k-th smallest |r_i| / sqrt(v_i + b), k = ceil((n + 1) level), equals
    the normal interval's half-width (each score falls as b grows, so bisection). With n < 1/(1 - level)
    - 1 runs the largest score is used; fewer than 2 finite runs, or scores already inside: 0."""
    from scipy import stats

    r, v = np.asarray(r, float), np.asarray(v, float)
    ok = np.isfinite(r) & np.isfinite(v) & (v >= 0)
    r, v = np.abs(r[ok]), v[ok]
    if len(r) < 2:
        return 0.0
    k = min(int(np.ceil((len(r) + 1) * level)), len(r))
    zq = float(stats.norm.ppf(0.5 + level / 2))

    def score(b):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.sort(np.where(r > 0, r / np.sqrt(v + b), 0.0))[k - 1]

    if score(0.0) <= zq:
        return 0.0
    lo, hi = 0.0, float(np.max(r) / zq) ** 2  # at hi every score is <= zq
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if score(mid) <= zq else (mid, hi)
    return hi


def band_chance(n_cal: int, n_test: int, level: float = 0.9, band=COVERAGE_OK) -> float:
    """Chance that an interval made exactly valid by split conformal on n_cal exchangeable held-out
    runs shows an observed coverage inside `band` on n_test fresh draws.

    Its true coverage is Beta(k, n_cal + 1 - k), k = ceil((n_cal + 1) level) (the k-th smallest of
    n_cal + 1 exchangeable scores; `conformal_scale`), so the count inside is beta-binomial. 32
    held-out runs, 32 draws, 80-97 %: 0.81 per response, ~0.42 for four independent responses.
    What the check's band can tell: a miss is not by itself proof of a bad correction."""
    from scipy import stats

    n_cal, n_test = int(n_cal), int(n_test)
    if n_cal < 1 or n_test < 1:
        return float("nan")
    k = min(int(np.ceil((n_cal + 1) * level)), n_cal)
    x = np.arange(n_test + 1)
    ok = (x / n_test >= band[0]) & (x / n_test <= band[1])
    return float(stats.betabinom.pmf(x[ok], n_test, k, n_cal + 1 - k).sum())


def conformal_scale(z, level: float = 0.9) -> float:
    """Factor on a predictive variance from held-out standardized residuals z (n,), by split
    conformal prediction: the interval +- q sd with q the k-th smallest |z|, k = ceil((n + 1) level),
    holds a new exchangeable run with probability >= level (exactly k / (n + 1) on average), where the
    plain `level` quantile of n scores falls short by ~1/n (32 runs: the 30th smallest |z| instead of
    the 28.9th). Returned as (q / z_level)^2, z_level the normal interval's half-width. With
    n < 1/(1 - level) - 1 runs the guarantee needs more runs than there are: the largest |z| is used.
    Fewer than 2 finite scores: 1 (no information)."""
    from scipy import stats

    a = np.sort(np.abs(np.asarray(z, float)[np.isfinite(z)]))
    if len(a) < 2:
        return 1.0
    k = int(np.ceil((len(a) + 1) * level))
    q = a[min(k, len(a)) - 1]
    return float(q / stats.norm.ppf(0.5 + level / 2)) ** 2
