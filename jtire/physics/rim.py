"""The rigid rim: 6 generalized coordinates q = (x, y, z, rx, ry, rz).

Rotation R = Rz(rz) Rx(rx) Ry(ry): ry is the spin about the axle (any size), rx (camber-wise) and
rz (steer-wise) are the small out-of-plane rotations. Bead nodes and their ghosts are attached to
the rim: X = q[:3] + R(q) X_ref. Each DOF is free (integrated under the forces), or prescribed
(its velocity follows the drive; locked is a prescribed velocity of zero).
The generalized forces on q are the transposed Jacobian of this map applied to the node forces,
done by autodiff, so no rim force is derived by hand.
"""

import jax.numpy as jnp

from .geometry_ops import V, cross


def rotation(q):
    cx, sx = jnp.cos(q[3]), jnp.sin(q[3])
    cy, sy = jnp.cos(q[4]), jnp.sin(q[4])
    cz, sz = jnp.cos(q[5]), jnp.sin(q[5])
    one, zero = jnp.ones_like(cx), jnp.zeros_like(cx)
    Rx = jnp.stack([jnp.stack([one, zero, zero]), jnp.stack([zero, cx, -sx]), jnp.stack([zero, sx, cx])])
    Ry = jnp.stack([jnp.stack([cy, zero, sy]), jnp.stack([zero, one, zero]), jnp.stack([-sy, zero, cy])])
    Rz = jnp.stack([jnp.stack([cz, -sz, zero]), jnp.stack([sz, cz, zero]), jnp.stack([zero, zero, one])])
    return Rz @ Rx @ Ry


def attached_positions(q, X_ref):
    """World positions (V) of rim-attached points X_ref (V, rim frame)."""
    R = rotation(q)
    return V(*(q[k] + R[k, 0] * X_ref.x + R[k, 1] * X_ref.y + R[k, 2] * X_ref.z for k in range(3)))


def frame_velocity(q, qd, X):
    """Velocity (V) of the rim frame at world points X (V) (small out-of-plane rotations)."""
    r = V(X.x - q[0], X.y - q[1], X.z - q[2])
    w = V(qd[3], qd[4], qd[5])
    return cross(w, r) + V(qd[0], qd[1], qd[2])
