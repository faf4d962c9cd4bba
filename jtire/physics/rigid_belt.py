"""A rigid belt: the crown nodes move as one rigid body (E05, E07, E08 of the study).

The study makes the tread and undertread rigid so that only the sidewalls deform. Here the
constraint is imposed on accelerations: the forces on the belt nodes are summed into a net force
and moment, the rigid body's linear and angular accelerations follow from Newton-Euler with the
belt's own mass and current inertia tensor, and every belt node gets the acceleration of that
rigid motion. Starting from rest (a rigid velocity field), the belt stays rigid to O(h^2 w^2) per
step, far below the deflections measured (rotations of a few milliradians). It costs no smaller
step, unlike making the crown moduli huge.
"""

import jax.numpy as jnp

from .geometry_ops import V, cross, dot


def _solve3(A, b):
    return jnp.linalg.solve(A, b)


def _frame(x, m, mask):
    mb = m * mask
    M = jnp.sum(mb)
    c = V(jnp.sum(mb * x.x), jnp.sum(mb * x.y), jnp.sum(mb * x.z)) / M
    r = x - c
    rr = dot(r, r)
    comps = (r.x, r.y, r.z)
    I = jnp.stack([jnp.stack([jnp.sum(mb * ((i == j) * rr - comps[i] * comps[j])) for j in range(3)]) for i in range(3)])
    return mb, M, c, r, I


def belt_load_forces(x, m, mask, load):
    """Nodal forces (V) that put the resultant `load` = (force (3), moment about the belt's mass
    centre (3)) on the belt, distributed like the rigid-body inertia (f_i = m_i (F / M + a x r_i)
    with a = I^-1 moment): on a rigid belt it is exactly the resultant; on a deformable one it is
    a smooth, mass-proportional load."""
    mb, M, c, r, I = _frame(x, m, mask)
    a = jnp.linalg.solve(I, load[3:])
    return (cross(V(a[0], a[1], a[2]), r) + V(load[0], load[1], load[2]) / M) * mb


def belt_motion(x, x_ref, m, mask):
    """Rigid-body fit of the belt's motion from the reference: mean displacement of its mass
    centre (3,) and small rotation (3,) about x, y, z (least squares, linearized), m and rad."""
    mb, M, c0, r0, I0 = _frame(x_ref, m, mask)
    u = x - x_ref
    disp = (u * mb).sum() / M
    L = cross(r0, (u - disp) * mb).sum()
    return disp.array(), jnp.linalg.solve(I0, L.array())


def rigid_belt_accelerations(x, v, f, m, mask):
    """Accelerations (V) of the free nodes with the masked ones moving rigidly.

    x, v, f: V of (T, F) positions, velocities, total forces; m: (T, F) masses; mask: (T, F) 1 on
    belt nodes. Non-belt nodes keep f / m.
    """
    mb = m * mask
    M = jnp.sum(mb)
    c = V(jnp.sum(mb * x.x), jnp.sum(mb * x.y), jnp.sum(mb * x.z)) / M
    r = x - c
    F = (f * mask).sum()
    Mo = cross(r, f * mask).sum()
    rr = dot(r, r)
    comps = (r.x, r.y, r.z)
    I = jnp.stack([jnp.stack([jnp.sum(mb * ((i == j) * rr - comps[i] * comps[j])) for j in range(3)]) for i in range(3)])
    L = cross(r, v * mb).sum()
    w = _solve3(I, L.array())
    Iw = I @ w
    wv = V(w[0], w[1], w[2])
    gyro = cross(wv, V(Iw[0], Iw[1], Iw[2]))
    alpha = _solve3(I, (Mo - gyro).array())
    av = V(alpha[0], alpha[1], alpha[2])
    a_rigid = cross(av, r) + cross(wv, cross(wv, r)) + F / M
    a_free = f / m
    return V(*(jnp.where(mask > 0, ar, af) for ar, af in ((a_rigid.x, a_free.x), (a_rigid.y, a_free.y), (a_rigid.z, a_free.z))))
