"""One least-squares surface per response, for several responses that share their inputs.

With 45 evaluations in 15-20 dimensions a full quadratic (231 terms in d = 20) is out of reach,
and even a reduced one (linear + squares, 2d + 1 = 41 terms) only fits at the end of the
budget. The kinds offered here (all in unit coordinates u of the log-parameter box, fitted to
ln(response) so that power laws become planes):

- "linear":   1, z                                             d + 1 terms
- "reduced":  1, z, z_i^2 (as surrogates.fit_quadratic), when the points fix it with one to
              spare; linear before that                       2d + 1 terms
- "ridge":    1, z, (w . z)^2 with w the response's own fitted gradient direction: the curvature
              of a smooth monotone response (a series spring, a saturating power law) lies
              mostly along its gradient                         d + 2 terms
- "subspace": 1, z, and every quadratic monomial of the k <= m coordinates p = W^T z, W the
              leading right singular vectors of the m responses' fitted gradients (the
              directions the targets see, an active subspace); "ridge" until the points fix it
                                                               d + 1 + k (k + 1) / 2 terms

z = 2 (u - c) / w over the fitting box (as in surrogates.quadratic). The choice for the tire
(calibration.tire.arsm_multi) was made on the stand-in; see that module and docs/design-notes.md.
"""

import dataclasses

import numpy as np

from ...surrogates import fit_quadratic, n_terms

__all__ = ["KINDS", "ProjectedQuadratic", "fit_responses", "terms"]

KINDS = ("linear", "reduced", "ridge", "subspace")
_HAT_ONE = 1.0 - 1e-10


def terms(kind: str, d: int, m: int = 4) -> int:
    """Coefficients of a surface of this kind in d dimensions (m responses for "subspace")."""
    if kind in ("linear", "reduced"):
        return n_terms(d, kind)
    if kind == "ridge":
        return d + 2
    k = min(m, d)
    return d + 1 + k * (k + 1) // 2


@dataclasses.dataclass(frozen=True)
class ProjectedQuadratic:
    """y = c0 + g . z + sum_ab h_ab p_a p_b with p = W^T z, z = (u - centre) / half_width.

    W: (d, k) orthonormal directions. coef: (1 + d + k (k + 1) / 2,). sigma2: residual variance
    (nan without residual freedom); cov_unscaled: pinv of the normal matrix; loo_residuals:
    (n,) leave-one-out residuals (inf where a point fixes its own coefficient).
    """

    coef: np.ndarray
    W: np.ndarray
    kind: str
    centre: np.ndarray
    half_width: np.ndarray
    cov_unscaled: np.ndarray
    sigma2: float
    loo_residuals: np.ndarray
    n_points: int

    def _phi(self, u):
        z = (np.atleast_2d(np.asarray(u, float)) - self.centre) / self.half_width
        return _features(z, self.W), z

    def predict(self, u) -> np.ndarray:
        """(n,) at u (n, d) or (d,)."""
        return self._phi(u)[0] @ self.coef

    def gradient(self, u) -> np.ndarray:
        """(n, d) derivatives with respect to u."""
        z = (np.atleast_2d(np.asarray(u, float)) - self.centre) / self.half_width
        d, k = self.W.shape
        p = z @ self.W
        g = np.broadcast_to(self.coef[1:1 + d], z.shape).copy()
        a, b = _pairs(k)
        h = self.coef[1 + d:]
        # d(p_a p_b)/dz = p_b W[:, a] + p_a W[:, b]
        g += (p[:, b] * h) @ self.W[:, a].T + (p[:, a] * h) @ self.W[:, b].T
        return g / self.half_width

    def variance(self, u) -> np.ndarray:
        """Variance of the fitted mean at u, (n,) (nan without residual freedom)."""
        phi = self._phi(u)[0]
        return self.sigma2 * np.einsum("np,pq,nq->n", phi, self.cov_unscaled, phi)

    @property
    def loo_rmse(self) -> float:
        return float(np.sqrt(np.mean(self.loo_residuals**2)))


_PAIRS = {}


def _pairs(k):
    if k not in _PAIRS:
        _PAIRS[k] = np.triu_indices(k)
    return _PAIRS[k]


def _features(z, W):
    p = z @ W
    a, b = _pairs(W.shape[1])
    return np.concatenate([np.ones((z.shape[0], 1)), z, p[:, a] * p[:, b]], axis=1)


def _fit_projected(u, y, W, lo, hi, kind, weights=None):
    centre, half = 0.5 * (lo + hi), np.where(hi > lo, 0.5 * (hi - lo), 1.0)
    z = (u - centre) / half
    phi = _features(z, W)
    sw = np.ones(len(y)) if weights is None else np.sqrt(np.asarray(weights, float))
    a = phi * sw[:, None]
    coef, _, rank, _ = np.linalg.lstsq(a, y * sw, rcond=None)
    cov = np.linalg.pinv(a.T @ a)
    resid = y - phi @ coef
    dof = phi.shape[0] - rank
    sigma2 = float(np.sum((sw * resid) ** 2) / dof) if dof > 0 else float("nan")
    h = np.einsum("np,pq,nq->n", a, cov, a)
    with np.errstate(divide="ignore", invalid="ignore"):
        loo = np.where(h > _HAT_ONE, np.inf, resid / (1 - h))
    return ProjectedQuadratic(coef, W, kind, centre, half, cov, sigma2, loo, u.shape[0])


def _direction_basis(G, k):
    """Orthonormal (d, k') basis of the leading row space of G (m, d), k' <= k."""
    _, s, vt = np.linalg.svd(np.atleast_2d(G), full_matrices=False)
    keep = s > 1e-10 * max(s[0], 1e-300)
    return vt[keep][:k].T


def fit_responses(u, Y, kind: str, lo=None, hi=None, weights=None) -> list:
    """One surface per column of Y.

    u: (n, d) unit coordinates; Y: (n, m) values to fit (ln responses), all finite;
    lo, hi: (d,) the box that scales the fit (default: the points' bounding box).
    weights: optional (n,) non-negative weights of the points (weighted least squares).
    A kind the points cannot fix with one point to spare falls back to the next leaner one
    (subspace -> ridge -> linear; reduced -> linear); the surface's .kind says what was fitted.
    """
    u, Y = np.atleast_2d(np.asarray(u, float)), np.asarray(Y, float).reshape(len(u), -1)
    n, d = u.shape
    m = Y.shape[1]
    lo = u.min(axis=0) if lo is None else np.asarray(lo, float)
    hi = u.max(axis=0) if hi is None else np.asarray(hi, float)
    if kind not in KINDS:
        raise ValueError(f"surface kind {kind!r}: must be one of {KINDS}")
    if kind == "reduced":
        k = "reduced" if n >= n_terms(d, "reduced") + 1 else "linear"
        return [fit_quadratic(u, Y[:, j], lo, hi, kind=k, weights=weights) for j in range(m)]
    linear = [fit_quadratic(u, Y[:, j], lo, hi, kind="linear", weights=weights) for j in range(m)]
    if kind == "linear":
        return linear
    grads = np.array([s.coef[1:1 + d] for s in linear])  # (m, d) in the scaled variable z
    if kind == "subspace" and n >= terms("subspace", d, m) + 1:
        W = _direction_basis(grads, m)
        return [_fit_projected(u, Y[:, j], W, lo, hi, "subspace", weights) for j in range(m)]
    if n < terms("ridge", d) + 1:
        return linear
    return [_fit_projected(u, Y[:, j], _direction_basis(grads[j], 1), lo, hi, "ridge", weights)
            for j in range(m)]
