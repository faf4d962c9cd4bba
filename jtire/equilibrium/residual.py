"""The static residual: the net force on every degree of freedom of a tire at rest.

A static state has no rate, so the Maxwell branches carry no stress (long-term moduli only), the
contact has no damping and the settling damping is absent. What is left is the gradient of

    Pi(x, q, b) = 1/2 sum K (s - s0)^2 - p V + sum_i k_n,i R(-gap_i) - f_rim . q - m g . x

(R the integral of the contact's smooth ramp, below) plus two forces that have no potential of
their own: the tread friction (whose limit mu F_n depends on the state) and a belt load spread
over a rigid belt. The residual is computed like the dynamic force (`physics.vector_field`): one
linearization of the kinematic map (strains, cavity volume, tread points, free-node positions)
transposed onto (K d, -p, -F_contact, -f_nodal), so at rest it is minus the dynamic force with
the Maxwell stresses zero (tests/test_equilibrium.py checks this identity).

Unknowns: one flat vector u = (x (T, F, 3) segment-major, q (6,), b (6,) with a rigid belt).
Rim DOFs that are held and, with a rigid belt, the belt nodes are *dummies*: the mechanics uses
the prescribed rim coordinate and the rigid belt's positions instead, and the dummy's own
residual is DUMMY_SCALE (u - target), so the Jacobian keeps its shape and one Newton step puts
the dummy where it belongs. `state_parts` returns the mechanical values.

Static friction (`StaticSetup.anchors`, an `Anchors`). Each contact point's tread column is
sheared by the trial shear
    z_t = tangential part of ( z0 + phi (P - P0) ),
z0 its shear and P0 its position at the anchor state (the previous load level), phi the part
of the step spent in contact: 1 for a point that was in contact already, -gap / (gap0 - gap)
for one that touched down during the step (its motion before touchdown, interpolated linearly
along the step, does not shear it), 0 out of contact. The column carries the force -k_t z with
    z = z_t L / (L^m + (k_t |z_t|)^m)^(1/m),   L = mu F_n,  m = FRICTION_SHARPNESS,
a smooth saturation at the Coulomb limit (|k_t z| < L always; z -> z_t for small shear). This
is the dynamic bristle of `physics.contact` for one monotone loading step taken at once: the
dynamic model accumulates slip increments and clips them onto the cone every time step (path
dependent, exactly Coulomb); here a level's whole tangential motion is one trial shear and the
clip is smoothed (at |k_t z_t| = L the force is 2^(-1/m) = 92 % of L instead of L). What it
does not model: a point that slips back and forth within one level, or whose F_n falls and rises
again (the dynamic bristle would keep the slip), and the sharp stick-slip corner. Load levels
(`sequences`: z0, P0 := the solved z, P after each level) make the path follow the incremental
law; the step size is the remaining path error (tests/test_equilibrium.py measures it).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..physics import rim
from ..physics.contact import RAMP_EPS, AbstractSurface, NoSurface
from ..physics.geometry_ops import V, dot, smooth_ramp
from ..physics.rigid_belt import belt_load_forces

FRICTION_SHARPNESS = 8  # m of the smooth saturation (even: smooth at z = 0)
DUMMY_SCALE = 1e6  # N/m: residual per metre of a dummy DOF (held rim DOF, rigid-belt node)


class Anchors(eqx.Module):
    """Friction state at the anchor (previous) level: points P0 and shear z0 (V of (N,), m), and
    each point's gap to this level's surface there, gap0 (N,) m (positive: apart)."""

    points: V
    shear: V
    gap: Float[Array, " N"]


class StaticSetup(eqx.Module):
    """Everything imposed on a tire at rest, as arrays (so setups vmap and differentiate).

    pressure: Pa. rim_force: (6,) N and N m on the rim (like `Drive.rim_force`), used on the
    free DOFs. rim_free: (6,) 1 = free, 0 = held at rim_position (6,) (m, rad).
    surface: any `AbstractSurface` (FlatRoad, NoSurface, Drum, ...), queried at `time` (s).
    gravity: (3,) m/s^2 on nodes and rim. anchors: `Anchors` (module docstring), None =
    frictionless contact; friction_on: 1 or 0, multiplies the friction coefficient (so
    frictionless and frictional levels of one path share a structure). belt_load: (6,) force and moment about the belt's mass centre
    (`Drive.belt_load`), only with rigid_belt (static: the belt nodes are replaced by the rigid
    motion b (6,) of the reference belt, as `physics.rigid_belt` keeps it in the dynamics).
    """

    pressure: Float[Array, ""]
    rim_force: Float[Array, " 6"]
    rim_free: Float[Array, " 6"]
    rim_position: Float[Array, " 6"]
    surface: AbstractSurface
    gravity: Float[Array, " 3"]
    time: Float[Array, ""]
    friction_on: Float[Array, ""]
    anchors: Anchors = None
    belt_load: Float[Array, " 6"] = None
    rigid_belt: bool = eqx.field(static=True, default=False)

    def __check_init__(self):
        if self.belt_load is not None and not self.rigid_belt:
            raise ValueError("StaticSetup.belt_load needs rigid_belt=True (a load spread by the deformed belt's "
                             "inertia couples every belt node: no banded Jacobian)")

    @property
    def n_border(self) -> int:
        return 12 if self.rigid_belt else 6


def make_setup(pressure, *, rim_force=np.zeros(6), rim_free=np.zeros(6), rim_position=np.zeros(6), surface=None,
               gravity=np.zeros(3), time=0.0, anchors=None, friction_on=1.0, belt_load=None, rigid_belt=False):
    """StaticSetup from numbers or arrays (every leaf float64, never weakly typed)."""
    f = lambda v: jnp.asarray(v, jnp.float64)  # noqa: E731
    belt = f(np.zeros(6) if belt_load is None else belt_load) if rigid_belt else None
    return StaticSetup(f(pressure), f(rim_force), f(rim_free), f(rim_position),
                       NoSurface() if surface is None else surface, f(gravity), f(time), f(friction_on), anchors, belt,
                       bool(rigid_belt))


# ---- layout of the unknowns ---------------------------------------------------------------------
def n_free(model) -> int:
    return model.n_s - 2


def seg_size(model) -> int:
    """DOFs per segment: 3 per free node."""
    return 3 * n_free(model)


def pack(x: V, q, b=None):
    """Flat u from free-node positions (V of (T, F)), rim q (6,) and belt pose b (6,) or None."""
    xs = jnp.stack([x.x, x.y, x.z], axis=-1).reshape(-1)
    return jnp.concatenate([xs, q] + ([] if b is None else [b]))


def unpack(model, u, rigid_belt: bool):
    T, F = model.n_theta, n_free(model)
    xs = u[: T * F * 3].reshape(T, F, 3)
    x = V(xs[..., 0], xs[..., 1], xs[..., 2])
    q = u[T * F * 3: T * F * 3 + 6]
    b = u[T * F * 3 + 6:] if rigid_belt else None
    return x, q, b


def belt_reference(model):
    """Mass centre (3,) of the belt in the reference shape (the rigid belt turns about it)."""
    mb = model.node_mass * model.belt_mask
    M = jnp.sum(mb)
    x = model.x_ref
    return jnp.stack([jnp.sum(mb * x.x), jnp.sum(mb * x.y), jnp.sum(mb * x.z)]) / M


def rigid_belt_positions(model, b):
    """V (T, F): the reference belt moved rigidly by b = (translation (3,), rotation (3,) in the
    rim's angle convention) about its reference mass centre. Non-belt entries are meaningless."""
    c = belt_reference(model)
    r = model.x_ref - V(c[0], c[1], c[2])
    R = rim.rotation(jnp.concatenate([jnp.zeros(3), b[3:]]))
    return V(*(c[k] + b[k] + R[k, 0] * r.x + R[k, 1] * r.y + R[k, 2] * r.z for k in range(3)))


def _with_rigid_belt(model, x, b):
    """x with the belt nodes replaced by the rigid belt at pose b."""
    xr = rigid_belt_positions(model, b)
    m = model.belt_mask > 0
    return V(*(jnp.where(m, a, c) for a, c in ((xr.x, x.x), (xr.y, x.y), (xr.z, x.z))))


def mechanical(model, setup, u):
    """(x, q, b) the mechanics sees: held rim DOFs at their prescribed value, the belt rigid."""
    x, q, b = unpack(model, u, setup.rigid_belt)
    q = jnp.where(setup.rim_free > 0, q, setup.rim_position)
    if setup.rigid_belt:
        x = _with_rigid_belt(model, x, b)
    return x, q, b


def dummy_residual(model, setup, u):
    """Residual of the dummy DOFs (DUMMY_SCALE (u - target)), zero on the mechanical ones."""
    x, q, b = unpack(model, u, setup.rigid_belt)
    rq = jnp.where(setup.rim_free > 0, 0.0, DUMMY_SCALE * (q - setup.rim_position))
    if setup.rigid_belt:
        m = model.belt_mask > 0
        rx = x.map(lambda a: jnp.where(m, DUMMY_SCALE * a, 0.0))
        return pack(rx, rq, jnp.zeros(6))
    return pack(x.map(jnp.zeros_like), rq)


def mechanical_mask(model, setup):
    """(n,) 1 on DOFs whose residual is a force, 0 on dummies (numpy when setup is concrete)."""
    T, F = model.n_theta, n_free(model)
    xm = jnp.ones((T, F))
    if setup.rigid_belt:
        xm = xm * (1 - model.belt_mask)
    xs = jnp.broadcast_to(xm[..., None], (T, F, 3)).reshape(-1)
    return jnp.concatenate([xs, setup.rim_free] + ([jnp.ones(6)] if setup.rigid_belt else []))


# ---- contact ------------------------------------------------------------------------------------
def ramp_energy(x, eps):
    """Integral of geometry_ops.smooth_ramp (m^2): x^3 / (6 eps) on [0, eps], x^2/2 - eps x/2 + eps^2/6
    beyond, 0 below. Its derivative is smooth_ramp, so k_n ramp_energy(-gap) is the potential of the
    penalty normal force."""
    xc = jnp.clip(x, 0.0, eps)
    return jnp.where(x > eps, 0.5 * x * x - 0.5 * eps * x + eps * eps / 6.0, xc**3 / (6.0 * eps))


def friction_shear(z_t, limit, k_t, m: int = FRICTION_SHARPNESS):
    """Smoothly saturated tread shear z (V) for a trial shear z_t (V), limit = mu F_n (N); m (even) the
    sharpness of the saturation."""
    eps = k_t * 1e-9  # N: keeps 0/0 away where a point is out of contact and unsheared
    kz2 = k_t * k_t * dot(z_t, z_t)
    den = (limit**m + kz2 ** (m // 2) + eps**m) ** (1.0 / m)
    return z_t * (limit / den)


def contact(model, params, setup, P):
    """Contact forces F (V of (N,)) on the tread points P, the static tread shear z (V) and F_n."""
    k_n, k_t, _ = model.contact_stiffness(params)
    gap, n, _ = setup.surface.query(P, setup.time)
    F_n = k_n * smooth_ramp(-gap, RAMP_EPS)
    F = n * F_n
    if setup.anchors is None:
        z = P.map(jnp.zeros_like)
    else:
        a = setup.anchors
        g0 = jnp.maximum(a.gap, 0.0)
        inside = gap < 0
        phi = jnp.where(inside, -gap / jnp.where(inside, g0 - gap, 1.0), 0.0)
        d = a.shear + (P - a.points) * phi
        z_t = d - n * dot(d, n)
        z = friction_shear(z_t, params.friction * setup.friction_on * F_n, k_t)
        F = F - z * k_t
    return F, z, F_n


def contact_energy(model, params, setup, P):
    """Potential (J) of the normal penalty forces (no friction)."""
    k_n, _, _ = model.contact_stiffness(params)
    gap, _, _ = setup.surface.query(P, setup.time)
    return jnp.sum(k_n * ramp_energy(-gap, RAMP_EPS))


# ---- residual -----------------------------------------------------------------------------------
def _rim_mass6(model):
    return jnp.concatenate([jnp.full(3, model.rim_mass), model.rim_inertia])


def residual_and_rim(model, params, setup, u):
    """(residual (n,), tire_on_rim (6,)): minus the net static force on every mechanical DOF (N on
    nodes and rim translations, N m on rotations), DUMMY_SCALE (u - target) on dummies; and the
    generalized force of the tire on the rim (N, N m; what a hub dynamometer reads; for a held
    rim, minus the force that holds it)."""
    K = model.stiffness(params)
    g = setup.gravity
    x_u, q_u, b = unpack(model, u, setup.rigid_belt)
    q = jnp.where(setup.rim_free > 0, q_u, setup.rim_position)

    def kinematics(x_, q_, b_):
        x = _with_rigid_belt(model, x_, b_) if setup.rigid_belt else x_
        X = model.assemble(x, q_)
        return model.strains(X), model.volume(X), model.tread_points(X), x

    (s, _, P, x), vjp = jax.vjp(kinematics, x_u, q, b)
    F, _, _ = contact(model, params, setup, P)
    m = model.node_mass
    f_nodal = V(m * g[0], m * g[1], m * g[2])
    if setup.belt_load is not None:
        f_nodal = f_nodal + belt_load_forces(x, m, model.belt_mask, setup.belt_load)
    rx, rq, rb = vjp((K * (s - model.s0), -setup.pressure, -F, -f_nodal))
    f_rim = setup.rim_force + jnp.concatenate([g * model.rim_mass, jnp.zeros(3)])
    r = pack(rx, rq - f_rim, rb)
    mask = mechanical_mask(model, setup)
    return r * mask + dummy_residual(model, setup, u), -rq


def residual(model, params, setup, u):
    """(n,) residual (see `residual_and_rim`)."""
    return residual_and_rim(model, params, setup, u)[0]


def potential(model, params, setup, u):
    """Pi (J) for a frictionless setup without belt load: residual = grad Pi on mechanical DOFs."""
    x, q, _ = mechanical(model, setup, u)
    X = model.assemble(x, q)
    g = setup.gravity
    m = model.node_mass
    grav = -jnp.sum(m * (g[0] * x.x + g[1] * x.y + g[2] * x.z)) - model.rim_mass * jnp.dot(g, q[:3])
    return (model.strain_energy(params, X) - setup.pressure * model.volume(X)
            + contact_energy(model, params, setup, model.tread_points(X)) - jnp.dot(setup.rim_force, q) + grav)


def state_parts(model, params, setup, u):
    """Mechanical (x, q) and the static tread shear z (V of (N,)) at u."""
    x, q, _ = mechanical(model, setup, u)
    P = model.tread_points(model.assemble(x, q))
    _, z, _ = contact(model, params, setup, P)
    return x, q, z
