"""Small vectorized geometric helpers shared by the force terms."""

import jax.numpy as jnp


def norm(v, axis=-1):
    return jnp.sqrt(jnp.sum(v * v, axis=axis))


def unit(v, axis=-1):
    return v / norm(v, axis)[..., None]


def signed_angle(a, b, axis):
    """Angle from a to b about `axis` (radians, atan2 form).

    atan2 stays regular where the shell goes flat (acos is singular there: physics notes).
    """
    return jnp.arctan2(jnp.sum(jnp.cross(a, b) * unit(axis), -1), jnp.sum(a * b, -1))


def smooth_ramp(x, eps):
    """C1 ramp: 0 for x <= 0, x^2 / (2 eps) on [0, eps], x - eps / 2 beyond. Branchless."""
    xc = jnp.clip(x, 0.0, eps)
    return jnp.where(x > eps, x - 0.5 * eps, xc * xc / (2 * eps))


def smooth_step(s):
    """0 -> 1 smoothly (cubic smoothstep) for s in [0, 1]; clipped outside."""
    s = jnp.clip(s, 0.0, 1.0)
    return s * s * (3 - 2 * s)
