"""Designs of experiments on the unit box [0, 1]^d, and the maps to and from physical bounds.

Every design is generated in unit coordinates (so a design does not depend on the units of the
variables) and mapped to bounds with `to_bounds`. The random designs (Latin hypercube, Sobol)
come from `scipy.stats.qmc` and take an explicit integer seed.
"""

import warnings

import numpy as np
from scipy.stats import qmc

from ..errors import ConfigError

__all__ = [
    "as_bounds",
    "to_unit",
    "to_bounds",
    "latin_hypercube",
    "sobol",
    "central_composite",
    "star",
    "maximin_fill",
]

# A full factorial core has 2^d corners; beyond this the design is no longer "small".
_MAX_FACTORIAL_DIM = 12


def as_bounds(lower, upper):
    """Validate bounds; returns (lower, upper) as float arrays of shape (d,)."""
    lower = np.atleast_1d(np.asarray(lower, dtype=float))
    upper = np.atleast_1d(np.asarray(upper, dtype=float))
    if lower.ndim != 1 or lower.shape != upper.shape or lower.size == 0:
        raise ConfigError(
            f"bounds: lower {lower.shape} and upper {upper.shape} must be equal-length 1-D vectors"
        )
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
        raise ConfigError("bounds: lower and upper must be finite numbers")
    bad = np.flatnonzero(upper <= lower)
    if bad.size:
        i = int(bad[0])
        raise ConfigError(f"bounds[{i}] = [{lower[i]}, {upper[i]}]: upper must be > lower")
    return lower, upper


def to_unit(x, lower, upper):
    """Physical (..., d) -> unit coordinates (..., d); 0 at `lower`, 1 at `upper`."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    return (np.asarray(x, dtype=float) - lower) / (upper - lower)


def to_bounds(u, lower, upper):
    """Unit coordinates (..., d) -> physical (..., d)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    return lower + np.asarray(u, dtype=float) * (upper - lower)


def _check_n_d(n, d):
    if int(d) < 1:
        raise ConfigError(f"design dimension d = {d}: must be >= 1")
    if int(n) < 1:
        raise ConfigError(f"design size n = {n}: must be >= 1")


def latin_hypercube(n: int, d: int, seed: int, optimization: str | None = None) -> np.ndarray:
    """Latin hypercube of n points in [0, 1]^d, shape (n, d).

    optimization: None, "random-cd" (centred-discrepancy improvement) or "lloyd", as in
    `scipy.stats.qmc.LatinHypercube`.
    """
    _check_n_d(n, d)
    return qmc.LatinHypercube(d=int(d), optimization=optimization, rng=int(seed)).random(int(n))


def sobol(n: int, d: int, seed: int, scramble: bool = True) -> np.ndarray:
    """First n points of a (scrambled) Sobol sequence in [0, 1]^d, shape (n, d).

    Sobol balance is exact only for n a power of two; other n are allowed (scipy warns about it,
    the warning is silenced here because dense surrogate sampling does not need the balance).
    """
    _check_n_d(n, d)
    engine = qmc.Sobol(d=int(d), scramble=scramble, rng=int(seed))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return engine.random(int(n))


def central_composite(d: int, alpha: str | float = "face", n_center: int = 1) -> np.ndarray:
    """Central composite design in [0, 1]^d: 2^d factorial corners, 2d axial points, centres.

    alpha: "face" (axial points on the faces, alpha = 1, CCF), "rotatable" (alpha = 2^(d/4),
    inscribed so that the axial points lie on the faces and the corners are pulled in, CCI), or
    a number >= 1 (the same inscribed scaling with that alpha).
    Returns shape (2^d + 2d + n_center, d).
    """
    _check_n_d(1, d)
    d = int(d)
    if d > _MAX_FACTORIAL_DIM:
        raise ConfigError(
            f"central_composite d = {d}: must be <= {_MAX_FACTORIAL_DIM} (2^d corners)")
    if alpha == "face":
        a = 1.0
    elif alpha == "rotatable":
        a = 2.0 ** (d / 4.0)
    elif isinstance(alpha, (int, float)) and alpha >= 1.0:
        a = float(alpha)
    else:
        raise ConfigError(
            f"central_composite alpha = {alpha!r}: must be 'face', 'rotatable' or >= 1")
    # coded units in [-a, a], then scaled so the design fits the unit box
    corners = np.array(np.meshgrid(*[[-1.0, 1.0]] * d, indexing="ij")).reshape(d, -1).T
    axial = np.concatenate([-a * np.eye(d), a * np.eye(d)])
    centre = np.zeros((max(int(n_center), 0), d))
    coded = np.concatenate([corners, axial, centre]) / a
    return 0.5 + 0.5 * coded


def star(d: int, delta: float = 0.5, centre=None) -> np.ndarray:
    """The 2d+1 star design: a centre and one point each side of it along every axis.

    It is the smallest design that fixes a reduced quadratic (linear + pure squares) exactly.
    delta: half-width in unit coordinates (0.5 puts the arms on the faces of the unit box when
    the centre is 0.5). Returns shape (2d + 1, d), clipped to [0, 1].
    """
    _check_n_d(1, d)
    if not 0.0 < delta <= 0.5:
        raise ConfigError(f"star delta = {delta}: must be in (0, 0.5]")
    c = np.full(int(d), 0.5) if centre is None else np.asarray(centre, dtype=float)
    pts = np.concatenate([c[None], c - delta * np.eye(int(d)), c + delta * np.eye(int(d))])
    return np.clip(pts, 0.0, 1.0)


def maximin_fill(n: int, existing, lower, upper, seed: int, n_candidates: int = 512) -> np.ndarray:
    """n new points in the box [lower, upper] (unit coordinates) far from `existing` and each other.

    Greedy maximin over Sobol candidates: each new point maximizes its distance (scaled by the
    box widths) to the points already present. Returns shape (n, d).
    """
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    d = lower.size
    width = np.maximum(upper - lower, 1e-300)
    cand = lower + sobol(max(int(n_candidates), int(n)), d, seed) * width
    have = np.asarray(existing, dtype=float).reshape(-1, d)
    out = []
    for _ in range(int(n)):
        if have.shape[0] == 0:
            dist = np.linalg.norm((cand - 0.5 * (lower + upper)) / width, axis=1)
            k = int(np.argmin(dist))  # the first point goes to the centre of the box
        else:
            diff = (cand[:, None, :] - have[None, :, :]) / width
            k = int(np.argmax(np.min(np.linalg.norm(diff, axis=2), axis=1)))
        out.append(cand[k])
        have = np.concatenate([have, cand[k][None]])
        cand = np.delete(cand, k, axis=0)
    return np.array(out).reshape(-1, d)
