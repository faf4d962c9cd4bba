"""Quadratic response surface fitted by least squares on scaled variables.

The variables are scaled to z = 2 (x - c) / w in [-1, 1] over a box (centre c, widths w), so
the coefficients are comparable and the normal equations stay well conditioned however small
the box becomes. Three bases, from richest to leanest:

- "full":    1, z_i, z_i^2, z_i z_j (i < j)       p = (d + 1)(d + 2) / 2 terms
- "reduced": 1, z_i, z_i^2                         p = 2d + 1  (no interactions)
- "linear":  1, z_i                                p = d + 1

"auto" takes the richest basis the data determine. With gradients (a differentiable
simulator), each point also contributes d rows df/dz_k = (df/dx_k) w_k / 2, so a full quadratic
in d dimensions needs only about (d + 2) / 2 points instead of (d + 1)(d + 2) / 2.
"""

import dataclasses

import numpy as np

from ..errors import ConfigError
from .doe import sobol

__all__ = ["QuadraticSurface", "fit_quadratic", "n_terms"]

_KINDS = ("full", "reduced", "linear")
# h_ii this close to 1 means the point fixes its own coefficient: leave-one-out is undefined.
_HAT_ONE = 1.0 - 1e-10


def n_terms(d: int, kind: str) -> int:
    """Number of coefficients of the basis `kind` in d dimensions."""
    if kind == "full":
        return (d + 1) * (d + 2) // 2
    if kind == "reduced":
        return 2 * d + 1
    if kind == "linear":
        return d + 1
    raise ConfigError(f"surface kind = {kind!r}: must be one of {_KINDS} or 'auto'")


def _pairs(d):
    return np.triu_indices(d, k=1)


def _basis(z, kind):
    """Design-matrix rows (m, p) at scaled points z (m, d)."""
    m, d = z.shape
    cols = [np.ones((m, 1)), z]
    if kind in ("full", "reduced"):
        cols.append(z**2)
    if kind == "full":
        i, j = _pairs(d)
        cols.append(z[:, i] * z[:, j])
    return np.concatenate(cols, axis=1)


def _basis_grad(z, kind):
    """Derivatives of the basis with respect to z: shape (m, d, p)."""
    m, d = z.shape
    eye = np.broadcast_to(np.eye(d), (m, d, d))
    parts = [np.zeros((m, d, 1)), eye]
    if kind in ("full", "reduced"):
        parts.append(2.0 * eye * z[:, None, :])
    if kind == "full":
        i, j = _pairs(d)
        g = np.zeros((m, d, i.size))
        k = np.arange(i.size)
        g[:, i, k] = z[:, j]
        g[:, j, k] = z[:, i]
        parts.append(g)
    return np.concatenate(parts, axis=2)


@dataclasses.dataclass(frozen=True)
class QuadraticSurface:
    """A fitted quadratic; callers pass points in the same coordinates as the fit data.

    Attributes:
        coef: (p,) coefficients in the scaled variable z.
        kind: "full", "reduced" or "linear".
        centre, half_width: (d,) the scaling z = (x - centre) / half_width.
        cov_unscaled: (p, p) pseudo-inverse of the normal matrix; times sigma2 it is the
            covariance of the coefficients.
        sigma2: residual variance (units of f^2); nan when the fit has no residual freedom.
        r2: coefficient of determination on the function values.
        press: sum of squared leave-one-out residuals (units of f^2); inf when undefined.
        loo_residuals: (n,) leave-one-out residuals f_i - prediction without point i (units
            of f); inf where undefined (the point fixes its own coefficient).
        n_points: number of points fitted.
    """

    coef: np.ndarray
    kind: str
    centre: np.ndarray
    half_width: np.ndarray
    cov_unscaled: np.ndarray
    sigma2: float
    r2: float
    press: float
    loo_residuals: np.ndarray
    n_points: int

    @property
    def dim(self) -> int:
        return int(self.centre.size)

    @property
    def loo_rmse(self) -> float:
        """Root-mean-square leave-one-out error (units of f)."""
        return float(np.sqrt(self.press / self.n_points))

    def _z(self, x):
        x = np.asarray(x, dtype=float)
        return (np.atleast_2d(x) - self.centre) / self.half_width

    def predict(self, x) -> np.ndarray:
        """Surface value at x (m, d) or (d,); returns (m,)."""
        return _basis(self._z(x), self.kind) @ self.coef

    def gradient(self, x) -> np.ndarray:
        """df/dx at x (m, d) or (d,); returns (m, d)."""
        return (_basis_grad(self._z(x), self.kind) @ self.coef) / self.half_width

    def variance(self, x) -> np.ndarray:
        """Prediction variance sigma2 * phi(x)^T (A^T A)^+ phi(x) at x (m, d); returns (m,).

        It is the variance of the fitted mean under the usual least-squares assumptions
        (independent residuals of equal variance); nan when sigma2 is unknown.
        """
        phi = _basis(self._z(x), self.kind)
        return self.sigma2 * np.einsum("mp,pq,mq->m", phi, self.cov_unscaled, phi)

    def hessian(self) -> np.ndarray:
        """Constant second-derivative matrix d2f/dx2, shape (d, d)."""
        d = self.dim
        h = np.zeros((d, d))
        if self.kind in ("full", "reduced"):
            h[np.diag_indices(d)] = 2.0 * self.coef[1 + d : 1 + 2 * d]
        if self.kind == "full":
            i, j = _pairs(d)
            h[i, j] = h[j, i] = self.coef[1 + 2 * d :]
        return h / np.outer(self.half_width, self.half_width)

    def argmin(self, lower, upper, seed: int = 0, starts=None, n_samples: int = 1024):
        """Minimizer of the surface over the box [lower, upper]; returns (x (d,), f).

        Without interactions ("reduced", "linear") the problem separates: each coordinate is
        minimized exactly on its interval. A full surface may be indefinite, with several
        local minima on the faces: the best few of a dense Sobol sample (plus `starts`, e.g.
        the best point seen) each descend by projected gradient, then the active set each
        reaches is solved exactly (`_box_qp`). Work is in the scaled variable z, where the
        Hessian is well conditioned.
        """
        lower, upper = np.asarray(lower, float), np.asarray(upper, float)
        zlo, zhi = (lower - self.centre) / self.half_width, (upper - self.centre) / self.half_width
        h_z = self.hessian() * np.outer(self.half_width, self.half_width)
        g_z = self.coef[1 : 1 + self.dim]  # gradient at z = 0
        if self.kind != "full":
            a = 0.5 * np.diag(h_z)  # q_i(z) = a z^2 + g z on [zlo, zhi]
            with np.errstate(divide="ignore", invalid="ignore"):
                vertex = np.where(a > 0, np.clip(-g_z / (2 * a), zlo, zhi), zlo)
            opts = np.stack([zlo, zhi, vertex])
            z = opts[np.argmin(a * opts**2 + g_z * opts, axis=0), np.arange(self.dim)]
        else:
            cand = zlo + sobol(n_samples, self.dim, seed) * (zhi - zlo)
            if starts is not None:
                cand = np.concatenate([(np.atleast_2d(starts) - self.centre) / self.half_width,
                                       cand])
            q = 0.5 * np.einsum("ki,ij,kj->k", cand, h_z, cand) + cand @ g_z
            z = _box_qp(h_z, g_z, zlo, zhi, cand[np.argsort(q)[:_N_STARTS]])
        x = np.clip(self.centre + z * self.half_width, lower, upper)
        return x, float(self.predict(x)[0])


# Starts of the projected-gradient descent on an indefinite surface; its iteration cap.
_N_STARTS = 6
_PG_ITERATIONS = 2000


def _box_qp(h, g, lo, hi, starts):
    """Minimize 1/2 z'hz + g'z over the box [lo, hi] from several starts (k, d); returns (d,).

    Projected gradient with step 1/|h| descends monotonically even when h is indefinite; the
    set of free coordinates it ends with is then solved exactly (Newton on that face) when the
    face's Hessian is positive definite and the solution stays in the box. Plain numpy on tiny
    matrices: no per-call solver overhead (an L-BFGS-B call costs far more: docs/design-notes.md).
    """
    q = lambda z: 0.5 * np.einsum("ki,ij,kj->k", z, h, z) + z @ g  # noqa: E731
    step = 1.0 / max(float(np.max(np.abs(np.linalg.eigvalsh(h)))), 1e-300)
    z = np.clip(starts, lo, hi)
    for _ in range(_PG_ITERATIONS):
        z_new = np.clip(z - step * (z @ h + g), lo, hi)
        done = np.max(np.abs(z_new - z)) <= 1e-12 * max(1.0, float(np.max(hi - lo)))
        z = z_new
        if done:
            break
    best = z[np.argmin(q(z))]
    for zk in z:
        free = (zk > lo + 1e-9 * (hi - lo)) & (zk < hi - 1e-9 * (hi - lo))
        if not free.any():
            continue
        hff = h[np.ix_(free, free)]
        if np.linalg.eigvalsh(hff).min() <= 0:
            continue
        zn = zk.copy()
        zn[free] = np.linalg.solve(hff, -(g[free] + h[np.ix_(free, ~free)] @ zk[~free]))
        if np.all(zn >= lo) and np.all(zn <= hi) and q(zn[None])[0] <= q(best[None])[0]:
            best = zn
    return best


def _choose_kind(n_eq, d):
    for kind in _KINDS:
        if n_eq >= n_terms(d, kind):
            return kind
    raise ConfigError(
        f"fit_quadratic: {n_eq} equations in d = {d}: need >= {d + 1} for even a linear surface"
    )


def _solve(a, b):
    """Least squares with a rank-revealing solve; returns (coef, pinv(A^T A), rank)."""
    coef, _, rank, _ = np.linalg.lstsq(a, b, rcond=None)
    return coef, np.linalg.pinv(a.T @ a), int(rank)


def fit_quadratic(
    x, f, lower=None, upper=None, kind: str = "auto", grad=None, weights=None
) -> QuadraticSurface:
    """Fit a quadratic response surface by (weighted) least squares.

    Args:
        x: (n, d) points; f: (n,) values.
        lower, upper: (d,) box that defines the scaling (default: the bounding box of x).
        kind: "full", "reduced", "linear" or "auto" (richest basis the data determine).
        grad: optional (n, d) gradients df/dx; adds d equations per point (gradient-enhanced).
        weights: optional (n,) non-negative weights of the points (all their rows).
    """
    x = np.atleast_2d(np.asarray(x, dtype=float))
    f = np.asarray(f, dtype=float).reshape(-1)
    n, d = x.shape
    if f.size != n:
        raise ConfigError(f"fit_quadratic: f has {f.size} values for {n} points; must be equal")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(f))):
        raise ConfigError("fit_quadratic: x and f must be finite (drop failed evaluations first)")
    lo = x.min(axis=0) if lower is None else np.asarray(lower, float)
    hi = x.max(axis=0) if upper is None else np.asarray(upper, float)
    centre = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    half = np.where(half > 0, half, 1.0)  # a degenerate axis keeps unit scaling
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float).reshape(-1)
    if w.size != n or np.any(w < 0):
        raise ConfigError(f"fit_quadratic: weights must be {n} non-negative numbers")
    g = None if grad is None else np.asarray(grad, dtype=float).reshape(n, d)
    n_eq = n if g is None else n * (d + 1)
    kind = _choose_kind(n_eq, d) if kind == "auto" else kind
    p = n_terms(d, kind)

    z = (x - centre) / half
    phi = _basis(z, kind)
    sw = np.sqrt(w)
    rows, rhs, owner = [phi * sw[:, None]], [f * sw], [np.arange(n)]
    if g is not None:
        dphi = _basis_grad(z, kind).reshape(n * d, p)  # row (i, k) = d phi / d z_k at point i
        rows.append(dphi * np.repeat(sw, d)[:, None])
        rhs.append((g * half).reshape(-1) * np.repeat(sw, d))  # chain rule df/dz = df/dx * w/2
        owner.append(np.repeat(np.arange(n), d))
    a, b, owner = np.concatenate(rows), np.concatenate(rhs), np.concatenate(owner)
    coef, cov, rank = _solve(a, b)

    resid = f - phi @ coef
    sse = float(np.sum(resid**2))
    sst = float(np.sum((f - f.mean()) ** 2))
    r2 = 1.0 - sse / sst if sst > 0 else (1.0 if sse <= 1e-24 else 0.0)
    dof = a.shape[0] - rank
    sigma2 = float(np.sum((a @ coef - b) ** 2) / dof) if dof > 0 else float("nan")

    if g is None:
        # closed-form leave-one-out residuals e_i / (1 - h_ii) (weights cancel for one row)
        h = np.einsum("np,pq,nq->n", phi * sw[:, None], cov, phi * sw[:, None])
        with np.errstate(divide="ignore", invalid="ignore"):
            loo = np.where(h > _HAT_ONE, np.inf, resid / (1 - h))
    else:
        # each point owns d + 1 rows, so leave-one-out means refitting without them
        loo = np.empty(n)
        for i in range(n):
            keep = owner != i
            ci, _, ri = _solve(a[keep], b[keep])
            loo[i] = f[i] - phi[i] @ ci if ri == p else np.inf
    press = float(np.sum(loo**2))
    return QuadraticSurface(
        coef=coef, kind=kind, centre=centre, half_width=half, cov_unscaled=cov,
        sigma2=sigma2, r2=float(r2), press=press, loo_residuals=loo, n_points=n,
    )
