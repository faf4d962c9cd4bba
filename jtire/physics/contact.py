"""Contact of the tread points with rigid surfaces: penalty normal force, bristle friction.

Every rigid partner implements `AbstractSurface.query(P, t) -> (gap, normal, surface_velocity)`;
the contact law below is the same for all of them, so a rotating drum or a cleat is a new
surface, not a new contact law. All of it is branchless (`jnp.where`, smooth ramps).

Normal: F_n = k_n * ramp(-gap) + c_n * (-gap_rate) while in contact, never pulling (clipped at
zero); k_n the tread column's stiffness, c_n its viscoelastic loss (tread_loss * k_n / omega_ref).
Tangential: an elasto-plastic bristle per point, the tread column's shear deflection z. Each step
z <- z + v_slip dt, then z is scaled back so that k_t |z| <= mu F_n (a return mapping). This is
regularized Coulomb friction with the tread's own tangential compliance, and unlike a viscous
regularization (F = mu F_n v / v_eps) it adds no velocity stiffness: it does not shrink the
stable step (a viscous one does, by far: docs/design-notes.md).
"""

import abc

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .geometry_ops import V, dot, smooth_ramp

OMEGA_REF = 2 * jnp.pi * 50.0  # rad/s: tread loss quoted at the footprint-passage band
RAMP_EPS = 2e-5  # m: width of the smoothed onset of contact (0.02 mm, far below any deflection)


class AbstractSurface(eqx.Module):
    @abc.abstractmethod
    def query(self, P, t):
        """P: V of (N,) points. Returns gap (N,) (positive = apart), the surface's outward unit
        normal (V) and its material velocity at the closest point (V)."""

    def frame_velocity(self):
        """(3,) m/s: the velocity of the road's frame (the ground the tire rolls on, seen from the
        axle): what the study's nodal damping takes velocities relative to. Still by default."""
        return jnp.zeros(3)


class FlatRoad(AbstractSurface):
    """The plane z = height (internal z up), moving with `velocity` (a belt under the tire)."""

    height: Float[Array, ""]
    velocity: Float[Array, " 3"]

    def query(self, P, t):
        gap = P.z - self.height
        zero = jnp.zeros_like(gap)
        n = V(zero, zero, zero + 1.0)
        v = V(zero + self.velocity[0], zero + self.velocity[1], zero + self.velocity[2])
        return gap, n, v

    def frame_velocity(self):
        return jnp.asarray(self.velocity)


class NoSurface(AbstractSurface):
    """No road at all (rim-locked sidewall experiments): gaps are infinite."""

    def query(self, P, t):
        zero = jnp.zeros_like(P.z)
        return zero + 1e3, V(zero, zero, zero + 1.0), V(zero, zero, zero)


def contact_forces(surface, P, Pdot, t, bristle, k_n, k_t, c_n, mu, dt):
    """Forces on the contact points and the updated bristle state.

    P, Pdot, bristle: V of (N,). Returns F (V), bristle_new (V), F_n (N,) normal force
    magnitudes, gap (N,), the power dissipated by normal damping (W) and the power lost to
    sliding (W): the return mapping's plastic slip z_trial - z_new against the bristle force
    k_t z_new, per step, over dt. (With it, the work of the contact forces balances elastic
    storage plus losses to O(dt): the remainder per step is k_t |z_new - z_old|^2 / 2.)
    """
    gap, n, v_s = surface.query(P, t)
    rel = Pdot - v_s
    gap_rate = dot(rel, n)
    pen = -gap
    in_contact = pen > 0
    fn_el = k_n * smooth_ramp(pen, RAMP_EPS)
    fn_damp = jnp.where(in_contact, -c_n * gap_rate, 0.0)
    F_n = jnp.maximum(fn_el + fn_damp, 0.0)
    p_damp = jnp.sum(jnp.where(in_contact & (fn_el + fn_damp > 0), c_n * gap_rate**2, 0.0))
    # bristle: tangential slip, return mapping onto the friction cone
    v_t = rel - gap_rate * n
    z_trial = bristle + v_t * dt
    z_trial = z_trial - dot(z_trial, n) * n
    zmag = jnp.sqrt(dot(z_trial, z_trial) + 1e-30)
    limit = mu * F_n
    scale = jnp.minimum(1.0, limit / (k_t * zmag + 1e-30))
    z_new = z_trial * scale
    F = F_n * n - k_t * z_new
    p_slide = jnp.sum(k_t * dot(z_new, z_trial - z_new)) / dt
    return F, z_new, F_n, gap, p_damp, p_slide
