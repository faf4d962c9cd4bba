"""Contact-patch extent: length (x) and width (y) of the tread surface inside a contact partner.

The tread surface is sampled finely: each circumferential line of tread points is interpolated by a
periodic cubic spline (the belt is smooth between nodes; linear interpolation would snap the patch
ends to the nodes on a coarse ring), then linearly across the tread columns. The patch edges are
where that surface crosses the partner's surface, found by linear interpolation between the last
sample inside and the first one outside, so length and width are continuous (and differentiable)
functions of the tire's shape, resolved between samples.

Two implementations of the same reduction: `extent` on the host (scipy's CubicSpline, numpy) for
result files, and `extent_traced` in JAX (the periodic spline as a fixed linear operator) for
batched programs, calibration and sensitivities; a test checks they agree.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np

from ..physics import tread
from ..physics.geometry_ops import V

N_FINE = 24  # samples per segment and per column gap


@functools.lru_cache(maxsize=8)
def spline_operator(n_theta: int, n_fine: int = N_FINE) -> np.ndarray:
    """(n_theta * n_fine, n_theta) matrix: periodic cubic-spline values at the fine samples from
    the node values (the spline is linear in the data: interpolate the unit vectors once)."""
    from scipy.interpolate import CubicSpline

    k = np.arange(n_theta + 1)
    eye = np.eye(n_theta)
    closed = np.concatenate([eye, eye[:1]], axis=0)
    fine = np.linspace(0, n_theta, n_theta * n_fine, endpoint=False)
    return CubicSpline(k, closed, axis=0, bc_type="periodic")(fine)


def _tread_grid(model, y, xp):
    """Tread points, one per node: (T, n_tread, 3) array (numpy or jax via xp)."""
    X = model.assemble(y.x, y.q)
    p = tread.tread_points(X, model.tread_cols, model.tread_depth, 1, model.normal_sign)
    return xp.stack([xp.asarray(p.x), xp.asarray(p.y), xp.asarray(p.z)], -1).reshape(
        model.n_theta, len(model.tread_cols_t), 3)


def _surface(P, xp, n_fine):
    """Fine surface (M, n_tread - 1, n_fine, 3) from the fine circumferential lines P (M, n_tread, 3)."""
    v = xp.linspace(0.0, 1.0, n_fine)[None, None, :, None]
    return (1 - v) * P[:, :-1, None] + v * P[:, 1:, None]


def _edge_range(coord, gap, xp, axis, periodic):
    """(max, min) of `coord` over the patch edges found along `axis` of the sample grid: every pair
    of neighbouring samples, one inside the partner (gap < 0) and one outside, gives an edge point
    by linear interpolation to gap = 0; on a non-periodic axis an inside end sample is an edge too.
    (-inf, inf) when nothing is inside."""
    g = xp.moveaxis(gap, axis, 0)
    c = xp.moveaxis(coord, axis, 0)
    if periodic:
        g0, c0, g1, c1 = g, c, xp.roll(g, -1, 0), xp.roll(c, -1, 0)
    else:
        g0, c0, g1, c1 = g[:-1], c[:-1], g[1:], c[1:]
    change = (g0 < 0) != (g1 < 0)
    denom = xp.where(change, g0 - g1, 1.0)
    edge = c0 + xp.where(change, g0 / denom, 0.0) * (c1 - c0)
    hi = xp.max(xp.where(change, edge, -xp.inf))
    lo = xp.min(xp.where(change, edge, xp.inf))
    if not periodic:
        ends = xp.stack([c[0], c[-1]])
        inside = xp.stack([g[0], g[-1]]) < 0
        hi = xp.maximum(hi, xp.max(xp.where(inside, ends, -xp.inf)))
        lo = xp.minimum(lo, xp.min(xp.where(inside, ends, xp.inf)))
    return hi, lo


def _extent(S, gap, xp):
    """(length, width) of the inside region of the fine surface S (M, n_gaps, n_fine, 3): length
    along the circumferential lines (periodic), width across the tread."""
    hi, lo = _edge_range(S[..., 0], gap, xp, 0, True)
    length = hi - lo
    M = S.shape[0]
    hi, lo = _edge_range(S[..., 1].reshape(M, -1), gap.reshape(M, -1), xp, 1, False)
    return length, hi - lo


def extent(model, y, gap_fn, n_fine: int = N_FINE):
    """Host: (length (m), width (m), area (m^2)) of the tread surface of state y inside a partner.

    gap_fn(S) -> gaps (positive apart) of points S (..., 3) numpy. Returns zeros when nothing is in
    contact. Area: each fine sample stands for its cell of the surface.
    """
    from scipy.interpolate import CubicSpline

    p = _tread_grid(model, y, np)
    T = model.n_theta
    closed = np.concatenate([p, p[:1]], axis=0)
    fine = np.linspace(0, T, T * n_fine, endpoint=False)
    P = CubicSpline(np.arange(T + 1), closed, axis=0, bc_type="periodic")(fine)
    S = _surface(P, np, n_fine)
    gap = gap_fn(S)
    inside = gap < 0
    if not inside.any():
        return 0.0, 0.0, 0.0
    length, width = _extent(S, gap, np)
    du = np.roll(S, -1, axis=0) - S
    dv = (P[:, 1:] - P[:, :-1])[:, :, None, :]
    cell = np.linalg.norm(np.cross(du, dv), axis=-1) / n_fine
    return float(length), float(width), float((cell * inside).sum())


def extent_traced(model, y, gap_fn, n_fine: int = N_FINE):
    """Traced: (length, width) in m as in `extent` (the spline as a fixed linear operator)."""
    p = _tread_grid(model, y, jnp)
    A = jnp.asarray(spline_operator(model.n_theta, n_fine))
    P = jnp.einsum("mt,tcd->mcd", A, p)
    S = _surface(P, jnp, n_fine)
    length, width = _extent(S, gap_fn(S), jnp)
    none = ~jnp.isfinite(length)
    return jnp.where(none, 0.0, length), jnp.where(none, 0.0, width)


def flat_gap(z_road):
    """gap_fn of the flat road z = z_road (works on numpy and traced arrays)."""
    return lambda S: S[..., 2] - z_road


def surface_gap(surface, t=0.0):
    """gap_fn of any contact partner (`AbstractSurface.query`), traced or host."""
    def gap(S):
        flat = S.reshape(-1, 3)
        g = surface.query(V(jnp.asarray(flat[:, 0]), jnp.asarray(flat[:, 1]), jnp.asarray(flat[:, 2])), t)[0]
        return g.reshape(S.shape[:-1])
    return gap


def host_gap(gap_fn):
    """A traced-style gap_fn made to return numpy (for `extent` on the host)."""
    return lambda S: np.asarray(jax.device_get(gap_fn(S)))


def x_range_traced(model, y, gap_fn, n_fine: int = N_FINE):
    """Traced: (x_rear, x_front) in m of the patch of state y inside a partner (e.g. a drum)."""
    p = _tread_grid(model, y, jnp)
    P = jnp.einsum("mt,tcd->mcd", jnp.asarray(spline_operator(model.n_theta, n_fine)), p)
    S = _surface(P, jnp, n_fine)
    hi, lo = _edge_range(S[..., 0], gap_fn(S), jnp, 0, True)
    return lo, hi
