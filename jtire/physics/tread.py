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

from .geometry_ops import unit


def outward_normals(X, sign):
    """(T, S, 3) unit normals at real nodes. `sign` (+1/-1) orients them away from the axle."""
    real = X[:, 1:-1]
    t_c = jnp.roll(real, -1, axis=0) - jnp.roll(real, 1, axis=0)
    t_m = X[:, 2:] - X[:, :-2]
    return sign * unit(jnp.cross(t_c, t_m))


def tread_points(X, tread_cols, depth, n_sub, sign):
    """Contact points (N, 3), N = T * n_tread * n_sub, ordered (segment, sub-point, tread column).

    tread_cols: (n_tread,) real-node column indices; depth: (n_tread,) m.
    """
    n = outward_normals(X, sign)[:, tread_cols]
    p = X[:, 1:-1][:, tread_cols] + depth[None, :, None] * n  # (T, n_tread, 3)
    p_next = jnp.roll(p, -1, axis=0)
    w = jnp.arange(n_sub) / n_sub
    pts = (1 - w)[None, :, None, None] * p[:, None] + w[None, :, None, None] * p_next[:, None]
    return pts.reshape(-1, 3)


def tread_stiffness(mesh_arrays, params, n_sub):
    """(N,) normal and tangential stiffness of each contact point, N/m."""
    ma = mesh_arrays
    area = (ma.w_node[:, ma.tread_cols] * ma.l_node[:, ma.tread_cols]) / n_sub  # (T, n_tread)
    k_n = params.tread_E * area / ma.tread_depth[None, :]
    k_t = params.tread_G * area / ma.tread_depth[None, :]
    rep = lambda k: jnp.broadcast_to(k[:, None, :], (k.shape[0], n_sub, k.shape[1])).reshape(-1)  # noqa: E731
    return rep(k_n), rep(k_t), rep(area)
