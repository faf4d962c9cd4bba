"""Invariants of the force model: rigid-body motion, closed-surface pressure, autodiff vs FD."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jtire.physics.geometry_ops import V

# central differences in ln E: h large enough that the O(h^2) term (measured 1.7e-5 of the derivative
# at h = 1e-2, 4.2e-6 at 5e-3: a ratio of 0.250) stands far above rounding (1e-16 f / h ~ 1e-13), so
# its convergence can be seen
H_FD = 1e-2
TOL_FD = 1e-5  # relative, at h = H_FD / 2: the measured O(h^2) term with a margin of 2.4
from jtire.physics.rim import rotation


def _rigid(model, x, q_shift):
    """Move the whole net rigidly: free nodes by the same transform as the rim coordinates."""
    R = rotation(q_shift)
    xs = V(*(q_shift[k] + R[k, 0] * x.x + R[k, 1] * x.y + R[k, 2] * x.z for k in range(3)))
    return xs


def test_strains_unchanged_by_rigid_motion(coarse_tire):
    m = coarse_tire.model
    q = jnp.array([0.03, -0.02, 0.05, 0.01, 0.7, -0.015])  # includes a large spin
    X = m.assemble(_rigid(m, m.x_ref, q), q)
    # generalized strains are lengths, cosines and angles: invariant to 1e-12 (float64 rounding)
    np.testing.assert_allclose(m.strains(X), m.s0, atol=1e-12)
    assert float(m.volume(X)) == pytest.approx(float(m.volume(m.assemble(m.x_ref, jnp.zeros(6)))), rel=1e-12)


def test_zero_internal_force_at_rest_and_under_rigid_motion(coarse_tire):
    from jtire.experiments import phases
    from jtire.physics.vector_field import evaluate
    from jtire.state import TireState

    m, p = coarse_tire.model, coarse_tire.params
    drive = phases.make_drive(0.0, 1e-5, surface=phases.flat_road(-phases.FAR))
    y = TireState.at_rest(m, 3)
    q = jnp.array([0.01, 0.02, -0.01, 0.0, 1.3, 0.0])
    y = eqx.tree_at(lambda s: (s.x, s.q), y, (_rigid(m, m.x_ref, q), q))
    upd, _ = evaluate(m, p, drive, 0.0, y)
    # zero pressure, no contact, no motion: every acceleration is zero up to rounding of
    # stiff terms (k ~ 1e8 N/m times 1e-17 m residuals, over masses of 1e-2 kg)
    assert float(jnp.max(jnp.abs(upd.ax.array()))) < 1e-6
    assert float(jnp.max(jnp.abs(upd.aq))) < 1e-6


def test_pressure_forces_balance(coarse_tire):
    """p grad V over nodes and rim sums to zero force and zero moment (closed surface)."""
    m = coarse_tire.model
    rng = np.random.default_rng(0)
    x = m.x_ref + V.of(jnp.asarray(rng.normal(scale=2e-3, size=(3,) + m.node_mass.shape)))
    q = jnp.array([0.001, 0.0, -0.002, 0.0, 0.1, 0.0])
    gx, gq = jax.grad(lambda Y: m.volume(m.assemble(*Y)))((x, q))
    total = gx.sum().array() + gq[:3]
    scale = float(jnp.sum(jnp.abs(gx.array())))
    assert float(jnp.max(jnp.abs(total))) < 1e-12 * max(scale, 1.0)
    # moment about the wheel centre: node moments + the rim's generalized moments (small angles)
    mom = (V(x.y * gx.z - x.z * gx.y, x.z * gx.x - x.x * gx.z, x.x * gx.y - x.y * gx.x)).sum().array()
    # the rim's rotational coordinates are Euler angles; at rx = rz = 0 the spin one is exact
    assert abs(float(mom[1] + gq[4] + (q[2] * gq[0] - q[0] * gq[2]))) < 1e-9 * max(scale, 1.0)


def test_gradient_through_the_force_model_matches_central_differences(coarse_tire):
    """d f / d ln E of a function nonlinear in the modulus E (the crown's circumferential one): the
    strain energy after one steepest-descent step, f = U(x1; E) with x1 = x0 - c dU/dx(x0; E). Its
    derivative runs through the internal forces (first and second derivatives of the nonlinear
    strains) and E enters twice, so f is not linear in E and a central difference has an O(h^2)
    error. That gives the test its teeth: the differences must converge to the autodiff value as h^2
    (halving h divides their distance by ~4; below 0.3 allows rounding), which a derivative that is
    off by any amount cannot do, and at the smaller step they agree to TOL_FD."""
    m, p = coarse_tire.model, coarse_tire.params
    rng = np.random.default_rng(1)
    x0 = m.x_ref + V.of(jnp.asarray(rng.normal(scale=1e-3, size=(3,) + m.node_mass.shape)))
    q0 = jnp.zeros(6)

    def with_modulus(log_scale):
        return eqx.tree_at(lambda pp: pp.E_circumferential, p, p.E_circumferential.at[2].multiply(jnp.exp(log_scale)))

    def energy(pp, x):
        return m.strain_energy(pp, m.assemble(x, q0))

    g0 = jax.grad(energy, argnums=1)(p, x0)
    c = 1e-3 / float(jnp.max(jnp.abs(g0.array())))  # a step of 1 mm at the most loaded node

    def f(log_scale):
        pp = with_modulus(log_scale)
        return energy(pp, x0 - c * jax.grad(energy, argnums=1)(pp, x0))

    g = float(jax.grad(f)(0.0))
    fd = [(float(f(h)) - float(f(-h))) / (2 * h) for h in (H_FD, H_FD / 2)]
    err = [abs(d - g) for d in fd]
    assert err[1] < 0.3 * err[0], (g, fd)  # second order: the differences converge to the autodiff value
    assert err[1] < TOL_FD * abs(g), (g, fd)


def test_tire_on_rim_balances_node_forces_and_contact(coarse_tire):
    """Action and reaction: with no gravity and no settle damping, the forces on the free nodes
    sum to the road's force on the tread minus the tire's force on the rim (`tire_on_rim`, the
    hub reading). Checked on a random deformed, moving, pressurized state pressed into the road,
    for force and for moment about the rim centre (spin component; the rim's rx, rz are Euler
    angles, exact at rx = rz = 0). Exact up to rounding: 1e-9 of the summed force magnitudes."""
    from jtire.experiments import phases
    from jtire.physics.vector_field import evaluate
    from jtire.state import TireState

    m, p = coarse_tire.model, coarse_tire.params
    rng = np.random.default_rng(3)
    y = TireState.at_rest(m, len(p.relaxation_times))
    x = m.x_ref + V.of(jnp.asarray(rng.normal(scale=1e-3, size=(3,) + m.node_mass.shape)))
    v = V.of(jnp.asarray(rng.normal(scale=0.2, size=(3,) + m.node_mass.shape)))
    q = jnp.array([0.0, 0.0, 0.0, 0.0, 0.3, 0.0])
    y = eqx.tree_at(lambda s: (s.x, s.v, s.q, s.qd), y, (x, v, q, jnp.array([0.0, 0, 0, 0, 2.0, 0])))
    z_low = float(phases.first_contact_height(m, y))
    drive = phases.make_drive(8.0e5, 1e-5, surface=phases.flat_road(z_low + 0.01))
    upd, d = evaluate(m, p, drive, 0.0, y)
    f_nodes = upd.ax * m.node_mass  # gravity is zero in this drive
    fq, F, P = d["tire_on_rim"], d["F"], d["P"]
    assert float(jnp.sum(d["F_n"] > 0)) > 5  # the road really pushes
    total = f_nodes.sum().array() + fq[:3] - F.sum().array()
    scale = float(jnp.sum(jnp.abs(f_nodes.array())))
    assert float(jnp.max(jnp.abs(total))) < 1e-9 * scale
    my = lambda r, f: (r.z * f.x - r.x * f.z).sum()  # noqa: E731  moment about y (axle)
    mom = my(y.x, f_nodes) + fq[4] - my(P, F)
    assert abs(float(mom)) < 1e-9 * scale
