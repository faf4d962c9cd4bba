"""Rotating contact partners: a rigid drum, a rounded cleat riding on it, and their union.

Internal ISO axes (x forward, y left, z up). Every partner turns about an axis parallel to the
wheel axle (along y) through the drum centre (centre_x, centre_z); its angular velocity `omega`
(rad/s, right-handed about +y) is an array leaf like every other parameter, so the partners are
jittable, vmappable and differentiable. A drum with omega < 0 carries its top (where the tire
sits) towards -x: the tire above it rolls forward with a positive spin (`drum(...)` builds it from
a surface speed). Surface velocities are those of the rigid body, omega x (Q - centre), at the
closest surface point Q. Nothing branches: the union picks per point with `jnp.where`.

The drum is infinitely wide (along y) and, in the experiments, infinitely heavy: its speed is a
prescribed parameter, not a degree of freedom.
"""

import math

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..errors import ConfigError
from .contact import AbstractSurface
from .geometry_ops import V

_EPS = 1e-24  # m^2: keeps the distance differentiable at a cylinder's own axis (never reached)


def _rigid_velocity(omega, centre_x, centre_z, Q):
    """Velocity (V) of points Q (V) of a body turning at omega about +y through the centre:
    omega e_y x r = (omega r_z, 0, -omega r_x)."""
    rx, rz = Q.x - centre_x, Q.z - centre_z
    return V(omega * rz, jnp.zeros_like(rx), -omega * rx)


def _cylinder(P, ax, az, radius):
    """Gap (N,), outward normal (V) and closest point (V) of points P to the y-parallel cylinder
    with axis at (ax, az) and the given radius."""
    dx, dz = P.x - ax, P.z - az
    d = jnp.sqrt(dx * dx + dz * dz + _EPS)
    nx, nz = dx / d, dz / d
    zero = jnp.zeros_like(d)
    n = V(nx, zero, nz)
    Q = V(ax + radius * nx, P.y, az + radius * nz)
    return d - radius, n, Q


class Drum(AbstractSurface):
    """Rigid cylinder of `radius` (m) about the y-parallel axis through (centre_x, centre_z) (m),
    turning at `omega` (rad/s about +y)."""

    radius: Float[Array, ""]
    centre_x: Float[Array, ""]
    centre_z: Float[Array, ""]
    omega: Float[Array, ""]

    def query(self, P, t):
        gap, n, Q = _cylinder(P, self.centre_x, self.centre_z, self.radius)
        return gap, n, _rigid_velocity(self.omega, self.centre_x, self.centre_z, Q)

    def frame_velocity(self):
        """The drum's surface velocity at its top, where the tire stands: (omega r, 0, 0)."""
        return jnp.stack([self.omega * self.radius, jnp.zeros_like(self.radius), jnp.zeros_like(self.radius)])


class FreeDrum(AbstractSurface):
    """A rigid drum that spins with its own inertia (E06): radius, axle at (centre_x, centre_z) (m),
    `inertia` (kg m^2) about its axle, `omega` (rad/s about +y) its current spin. The drum's spin is a
    state variable (`TireState.drum` = (angle, omega)): the vector field sets `omega` from the state
    before querying (`spinning`) and, where `free` = 1, turns the contact forces' moment about the
    drum's axle into its angular acceleration (`free` = 0: the spin is held)."""

    radius: Float[Array, ""]
    centre_x: Float[Array, ""]
    centre_z: Float[Array, ""]
    inertia: Float[Array, ""]
    free: Float[Array, ""]
    omega: Float[Array, ""] = None

    def spinning(self, omega):
        return FreeDrum(self.radius, self.centre_x, self.centre_z, self.inertia, self.free, omega)

    def query(self, P, t):
        gap, n, Q = _cylinder(P, self.centre_x, self.centre_z, self.radius)
        return gap, n, _rigid_velocity(self.omega, self.centre_x, self.centre_z, Q)

    def frame_velocity(self):
        """The drum's surface velocity at its top, where the tire stands: (omega r, 0, 0)."""
        return jnp.stack([self.omega * self.radius, jnp.zeros_like(self.radius), jnp.zeros_like(self.radius)])

    def acceleration(self, P, F):
        """Angular acceleration (rad/s^2) of the drum under the reaction -F of the contact forces F (V,
        on the tire's points P): torque about +y of -F, (r x f)_y = r_z f_x - r_x f_z, over the inertia."""
        rx, rz = P.x - self.centre_x, P.z - self.centre_z
        torque = -jnp.sum(rz * F.x - rx * F.z)
        return self.free * torque / self.inertia


class Cleat(AbstractSurface):
    """Rounded cleat: a y-parallel cylinder of `radius` (m) fixed to a drum (radius drum_radius,
    centre (centre_x, centre_z), turning at omega) and standing `height` (m) above its surface.

    Its axis lies at orbit = drum_radius + height - radius from the drum axis, at the angle
    phi(t) = phi0 + omega t measured about +y from the drum's top (+z): axis at
    centre + orbit (sin phi, 0, cos phi). Only the part outside the drum matters; in the union
    with the drum the rest is hidden.
    """

    radius: Float[Array, ""]
    height: Float[Array, ""]
    drum_radius: Float[Array, ""]
    centre_x: Float[Array, ""]
    centre_z: Float[Array, ""]
    omega: Float[Array, ""]
    phi0: Float[Array, ""]

    def angle(self, t):
        """Angle (rad) of the cleat about +y from the drum top at time t (s)."""
        return self.phi0 + self.omega * t

    def axis(self, t):
        """(x, z) of the cleat's axis at time t, m."""
        orbit = self.drum_radius + self.height - self.radius
        phi = self.angle(t)
        return self.centre_x + orbit * jnp.sin(phi), self.centre_z + orbit * jnp.cos(phi)

    def query(self, P, t):
        ax, az = self.axis(t)
        gap, n, Q = _cylinder(P, ax, az, self.radius)
        return gap, n, _rigid_velocity(self.omega, self.centre_x, self.centre_z, Q)


class DrumWithCleat(AbstractSurface):
    """The union of a drum and a cleat: per point, the partner with the smaller gap."""

    drum: Drum
    cleat: Cleat

    def query(self, P, t):
        gd, nd, vd = self.drum.query(P, t)
        gc, nc, vc = self.cleat.query(P, t)
        c = gc < gd
        pick = lambda a, b: V(jnp.where(c, a.x, b.x), jnp.where(c, a.y, b.y), jnp.where(c, a.z, b.z))  # noqa: E731
        return jnp.minimum(gc, gd), pick(nc, nd), pick(vc, vd)

    def frame_velocity(self):
        return self.drum.frame_velocity()


# ---- builders (host side: validate plain numbers, then make array leaves) ---------------------
def _check(name, value, lo, hi, unit):
    v = float(value)
    if not (lo <= v <= hi) or math.isnan(v):
        raise ConfigError(f"{name} = {v:g}: must be in [{lo:g}, {hi:g}] {unit}")
    return v


def drum(radius, top_z, surface_speed=0.0, centre_x=0.0):
    """Drum of `radius` (m) whose top is at height top_z (m) above centre_x, its surface moving
    at `surface_speed` (m/s; > 0: the top moves towards -x, so a tire on it rolls forward).
    omega = -surface_speed / radius."""
    r = _check("drum radius", radius, 0.05, 1e4, "m")
    speed = _check("drum surface_speed", surface_speed, -100.0, 100.0, "m/s")
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    return Drum(radius=f(r), centre_x=f(centre_x), centre_z=f(float(top_z) - r), omega=f(-speed / r))


def cleat_on(d: Drum, radius, height, phi0):
    """Cleat of `radius` (m) standing `height` (m) above drum d, at angle phi0 (rad) at t = 0."""
    r = _check("cleat radius", radius, 1e-3, 1.0, "m")
    h = _check("cleat height", height, 1e-4, 2 * r, "m (at most the cleat's diameter)")
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    return Cleat(radius=f(r), height=f(h), drum_radius=d.radius, centre_x=d.centre_x, centre_z=d.centre_z,
                 omega=d.omega, phi0=f(phi0))


def drum_with_cleat(d: Drum, radius, height, phi_at, t_at=0.0):
    """Union of drum d and a cleat that stands at angle phi_at (rad from the top, + towards +x)
    at time t_at (s): phi0 = phi_at - omega t_at, so a phase starting at t_at finds it there."""
    phi0 = float(phi_at) - float(d.omega) * float(t_at)
    return DrumWithCleat(drum=d, cleat=cleat_on(d, radius, height, phi0))


def cleat_half_chord(radius, height):
    """Half the cleat's width (m) where it leaves the drum surface (flat-drum approximation)."""
    r, h = float(radius), float(height)
    return float(np.sqrt(max(r * r - (r - h) ** 2, 0.0)))
