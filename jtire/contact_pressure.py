"""Contact pressure of the tread on a rigid surface, from a simulated state.

The model's contact is a penalty per tread contact point (`physics.contact`): the normal force F_n
of a point is the tread column's elastic push k_n * ramp(penetration) plus its viscous part, never
pulling. The tread column's stiffness is k_n = E_tread A / h with A the point's share of the tread
node's area (`physics.tread.tread_stiffness`), so the pressure the model transmits at a point is
p = F_n / A (Pa): for a settled state p = E_tread * penetration / h. The functions here evaluate
exactly the solver's normal force (`physics.contact.contact_forces`, the same stiffness and
damping), so the pressure integrated over the patch, sum(p A) = sum(F_n), is the road's reaction.

Shapes: T = n_theta segments, S real nodes per meridian (beads included), N = T * n_sub * n_tread
contact points ordered (segment, sub-point, tread column) as `model.tread_points` returns them.
"""

import jax
import jax.numpy as jnp

from .physics.contact import OMEGA_REF, FlatRoad, contact_forces


def flat_road(z_road, velocity=None) -> FlatRoad:
    """The rigid plane z = z_road (m, internal z up), at rest unless `velocity` (3,) m/s is given."""
    v = jnp.zeros(3) if velocity is None else jnp.asarray(velocity, dtype=jnp.float64)
    return FlatRoad(jnp.asarray(z_road, dtype=jnp.float64), v)


def point_normal_forces(model, params, y, surface, t=0.0):
    """Normal force of every contact point as the solver computes it. Traceable.

    y: TireState; surface: an `AbstractSurface` (e.g. `flat_road(z)`); t: s (moving surfaces).
    Returns (F_n (N,) N, gap (N,) m (negative = penetrating), points (N, 3) m)."""
    def points(x, q):
        return model.tread_points(model.assemble(x, q))

    P, Pdot = jax.jvp(points, (y.x, y.q), (y.v, y.qd))
    k_n, k_t, _ = model.contact_stiffness(params)
    c_n = params.tread_loss * k_n / OMEGA_REF
    # dt only enters the bristle (tangential) update, which is not used here
    _, _, F_n, gap, _, _ = contact_forces(surface, P, Pdot, t, y.bristle, k_n, k_t, c_n, params.friction, 1.0)
    return F_n, gap, jnp.stack([P.x, P.y, P.z], axis=-1)


def point_pressure(model, params, y, surface, t=0.0):
    """Contact pressure per contact point. Returns (p (N,) Pa, area (N,) m^2, points (N, 3) m);
    sum(p * area) is the total normal force (N). Traceable."""
    F_n, _, P = point_normal_forces(model, params, y, surface, t)
    _, _, area = model.contact_stiffness(params)
    return F_n / area, area, P


def nodal_pressure(model, params, y, surface, t=0.0):
    """Contact pressure at the real nodes of the mid-surface, (T, S) Pa, 0 off the tread. Traceable.

    A contact point at fraction w = k / n_sub between tread nodes t and t+1 gives (1 - w) of its
    force to node t and w to node t+1 (the transpose of its interpolation, as the solver applies
    it), and a node's pressure is its force over its area (w_node * l_node), so the nodal pressure
    integrated over the node areas is the same total force."""
    F_n, _, _ = point_normal_forces(model, params, y, surface, t)
    T, n_sub, cols = model.n_theta, model.n_sub, model.tread_cols
    F = F_n.reshape(T, n_sub, len(cols))
    w = (jnp.arange(n_sub) / n_sub)[None, :, None]
    own = jnp.sum(F * (1 - w), axis=1)  # (T, n_tread) to node t
    nxt = jnp.sum(F * w, axis=1)  # to node t + 1
    force = own + jnp.roll(nxt, 1, axis=0)
    area = model.w_node[:, cols] * model.l_node[:, cols]
    return jnp.zeros((T, model.n_s)).at[:, cols].set(force / area)


def point_patch_size(model):
    """(N,) circumferential and (N,) lateral extent (m) of each contact point's share of the tread on
    the reference shape: the tread node's circumferential width over n_sub, and its meridional
    length. Their product is the point's area."""
    cols, n_sub = model.tread_cols, model.n_sub
    rep = lambda a: jnp.broadcast_to(a[:, None, :], (a.shape[0], n_sub, a.shape[1])).reshape(-1)  # noqa: E731
    return rep(model.w_node[:, cols] / n_sub), rep(model.l_node[:, cols])


def footprint_table(model, params, y, z_road, only_contact: bool = True) -> dict:
    """Host table of the contact pressure on a flat road: equal-length numpy arrays
    point_x_m, point_y_m (relative to the rim centre, internal axes: x forward, y left),
    contact_pressure_Pa, point_area_m2, point_dx_m, point_dy_m (the point's circumferential and
    lateral extent), for the contact points in contact (all of them with only_contact=False).
    Made to be written as a CSV beside result.json (E01's footprint picture)."""
    import numpy as np

    p, area, P = jax.device_get(point_pressure(model, params, y, flat_road(z_road)))
    dx, dy = jax.device_get(point_patch_size(model))
    q = np.asarray(y.q)
    keep = p > 0 if only_contact else np.ones(p.shape, bool)
    return {"point_x_m": P[keep, 0] - q[0], "point_y_m": P[keep, 1] - q[1], "contact_pressure_Pa": p[keep],
            "point_area_m2": area[keep], "point_dx_m": np.asarray(dx)[keep], "point_dy_m": np.asarray(dy)[keep]}
