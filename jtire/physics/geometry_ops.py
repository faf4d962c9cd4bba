"""Vectors as three component planes, and the geometric helpers the force terms share.

A `V` holds x, y, z as separate arrays of equal shape; slicing `V[...]` slices every component.
XLA on a CPU fuses plane-wise arithmetic on 2-D arrays into single loops, which makes planes the
fastest layout (docs/design-notes.md). So the physics is written on planes.
"""

import jax
import jax.numpy as jnp


@jax.tree_util.register_pytree_node_class
class V:
    __slots__ = ("x", "y", "z")

    def __init__(self, x, y, z):
        self.x, self.y, self.z = x, y, z

    @staticmethod
    def of(a):
        """From an array with the components on its first axis."""
        return V(a[0], a[1], a[2])

    def array(self):
        return jnp.stack([self.x, self.y, self.z])

    def tree_flatten(self):
        return (self.x, self.y, self.z), None

    @classmethod
    def tree_unflatten(cls, aux, children):
        return cls(*children)

    def __getitem__(self, idx):
        return V(self.x[idx], self.y[idx], self.z[idx])

    def __add__(self, o):
        return V(self.x + o.x, self.y + o.y, self.z + o.z) if isinstance(o, V) else V(self.x + o, self.y + o, self.z + o)

    def __sub__(self, o):
        return V(self.x - o.x, self.y - o.y, self.z - o.z) if isinstance(o, V) else V(self.x - o, self.y - o, self.z - o)

    def __neg__(self):
        return V(-self.x, -self.y, -self.z)

    def __mul__(self, s):
        return V(self.x * s, self.y * s, self.z * s)

    __rmul__ = __mul__

    def __truediv__(self, s):
        return V(self.x / s, self.y / s, self.z / s)

    def roll(self, shift, axis):
        return V(jnp.roll(self.x, shift, axis), jnp.roll(self.y, shift, axis), jnp.roll(self.z, shift, axis))

    def sum(self, axis=None):
        return V(self.x.sum(axis), self.y.sum(axis), self.z.sum(axis))

    def map(self, f):
        return V(f(self.x), f(self.y), f(self.z))


def dot(a, b):
    return a.x * b.x + a.y * b.y + a.z * b.z


def cross(a, b):
    return V(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x)


def norm(a):
    return jnp.sqrt(dot(a, a))


def unit(a):
    return a * (1.0 / norm(a))


def signed_angle(a, b, axis):
    """Angle from a to b about `axis` (radians, atan2 form).

    atan2 stays regular where the shell goes flat (acos is singular there: physics notes).
    """
    return jnp.arctan2(dot(cross(a, b), unit(axis)), dot(a, b))


def smooth_ramp(x, eps):
    """C1 ramp: 0 for x <= 0, x^2 / (2 eps) on [0, eps], x - eps / 2 beyond. Branchless."""
    xc = jnp.clip(x, 0.0, eps)
    return jnp.where(x > eps, x - 0.5 * eps, xc * xc / (2 * eps))


def smooth_step(s):
    """0 -> 1 smoothly (cubic smoothstep) for s in [0, 1]; clipped outside."""
    s = jnp.clip(s, 0.0, 1.0)
    return s * s * (3 - 2 * s)
