"""The tread-rubber layer between the belt and the road.

Each tread node (a node with tread depth h > 0) carries a column of tread rubber along its
outward surface normal; its outer end is where the road is touched. `n_sub` contact points per
segment are interpolated along the circumference between neighbouring tread nodes (with one point
per node the segment-passing frequency shows up as ripple in rolling forces: physics notes).
The rubber column is the contact compliance: normal stiffness E_tread A / h, tangential
G_tread A / h per point (A the point's share of the node's area), so the contact penalty is the
tread's own, physical and calibratable, not a numerical constant.
"""

import jax.numpy as jnp

from .geometry_ops import cross, unit


def outward_normals(X, sign):
    """V of (T, S) unit normals at real nodes. `sign` (+1/-1) orients them away from the axle."""
    real = X[:, 1:-1]
    t_c = real.roll(-1, 0) - real.roll(1, 0)
    t_m = X[:, 2:] - X[:, :-2]
    return unit(cross(t_c, t_m)) * sign


def tread_points(X, tread_cols, depth, n_sub, sign):
    """Contact points, a V of (N,), N = T * n_sub * n_tread, ordered (segment, sub-point, column).

    tread_cols: (n_tread,) real-node column indices; depth: (n_tread,) m.
    """
    n = outward_normals(X, sign)[:, tread_cols]
    p = X[:, 1:-1][:, tread_cols] + n * depth  # (T, n_tread) planes
    p_next = p.roll(-1, 0)
    w = (jnp.arange(n_sub) / n_sub)[:, None]
    pts = p[:, None] * (1 - w) + p_next[:, None] * w  # (T, n_sub, n_tread)
    return pts.map(lambda a: a.reshape(-1))


def tread_stiffness(mesh_arrays, params, n_sub):
    """(N,) normal and tangential stiffness of each contact point, N/m."""
    ma = mesh_arrays
    area = (ma.w_node[:, ma.tread_cols] * ma.l_node[:, ma.tread_cols]) / n_sub  # (T, n_tread)
    k_n = params.tread_E * area / ma.tread_depth[None, :]
    k_t = params.tread_G * area / ma.tread_depth[None, :]
    rep = lambda k: jnp.broadcast_to(k[:, None, :], (k.shape[0], n_sub, k.shape[1])).reshape(-1)  # noqa: E731
    return rep(k_n), rep(k_t), rep(area)
