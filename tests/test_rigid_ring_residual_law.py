"""The ring's residual (belt-road) spring above the load (`identify.residual_spring`): the quadratic that
rests at F_z/k_sv with E02's tangent, then a cubic term through E02's largest load, then the end slope.

Checked against its own construction: value, tangent and curvature continuous at the rest (the small
motions about it see the quadratic's law), E02's largest load reached at E02's deflection there, the
slope continuous at that point, a monotone law, its inverse, and numpy and jax agreeing. Tolerances:
algebra and bisection to round-off (1e-9 relative); second-order finite differences over 1 um (their
O(h^2) error: 1e-6 relative on the tangent, 1e-3 on the curvature).
"""

import dataclasses
import math

import jax.numpy as jnp
import numpy as np
import pytest

from jtire.rigid_ring import synthetic
from jtire.rigid_ring.identify import residual_deflection, residual_force, residual_spring
from jtire.rigid_ring.model import Drive, RigidRing
from jtire.rigid_ring.params import RigidRingParams, derive
from jtire.rigid_ring.scenarios import _state, vertical_equilibrium

TANGENT_OVER_SECANT = 1.2  # the shell's load-deflection curves stiffen by 1.10-1.21x at the load
TOP_LOAD, TOP_SLOPE = 1.65, 0.97  # E02's largest load / F_z, and the curve's mean slope to it / its tangent


@pytest.fixture(scope="module")
def rows():
    """The synthetic rated row with a tangent and with E02's largest load (and without it)."""
    char = synthetic.characterization()
    r = char.rated_row()
    k_sv, fz = r.q["k_sv_N_per_m"], r.load_N
    k_t = TANGENT_OVER_SECANT * k_sv
    top = {"max_load_N": TOP_LOAD * fz,
           "settled_deflection_at_max_load_m": fz / k_sv + (TOP_LOAD - 1.0) * fz / (TOP_SLOPE * k_t)}
    base = r.q | {"k_sv_tangent_N_per_m": k_t}
    return char.tire, dataclasses.replace(r, q=base | top), dataclasses.replace(r, q=base)


def _law(d):
    return d.k_vr1, d.k_vr2, d.rho_r, d.rho_max, d.k_vr3


def test_the_law_meets_the_rest_and_e02s_largest_load(rows):
    tire, with_top, _ = rows
    d = derive(with_top, tire)
    assert d.k_vr3 is not None and d.stiffness_source.endswith("through E02's largest load")
    law = _law(d)
    assert residual_force(d.rho_r, *law) == pytest.approx(d.load_N, rel=1e-12)
    h = 1e-6
    for rho in (d.rho_r, d.rho_max):  # slope continuous at both joints (one-sided, second-order stencils)
        f = [residual_force(rho + i * h, *law) for i in (-2, -1, 0, 1, 2)]
        lo, hi = (3 * f[2] - 4 * f[1] + f[0]) / (2 * h), (-3 * f[2] + 4 * f[3] - f[4]) / (2 * h)
        assert hi == pytest.approx(lo, rel=1e-6)
    slope = (residual_force(d.rho_r + h, *law) - residual_force(d.rho_r - h, *law)) / (2 * h)
    assert slope == pytest.approx(d.k_vr, rel=1e-6)  # E02's tangent, split with k_bz
    # curvature continuous at the rest: the small motions about it see the quadratic's 2 k_vr2
    f = [residual_force(d.rho_r + i * h, *law) for i in (-2, -1, 0, 1, 2)]
    assert (f[0] - 2 * f[1] + f[2]) / h**2 == pytest.approx(2 * d.k_vr2, rel=1e-3)
    assert (f[2] - 2 * f[3] + f[4]) / h**2 == pytest.approx(2 * d.k_vr2, rel=1e-3)
    # with the sidewall in series the ring deflects E02's deflection at E02's largest load
    f_max = with_top.q["max_load_N"]
    assert d.residual_deflection(f_max) + f_max / d.k_bz == pytest.approx(
        with_top.q["settled_deflection_at_max_load_m"], rel=1e-9)
    rho = np.linspace(0.0, 3.0 * d.rho_max, 3001)
    assert np.all(np.diff(residual_force(rho, *law)) > 0)  # monotone through all three pieces
    for r in rho[1::50]:  # the inverse, to round-off
        assert residual_deflection(float(residual_force(r, *law)), *law) == pytest.approx(r, rel=1e-9)
    assert np.allclose(np.asarray(residual_force(jnp.asarray(rho), *law, xp=jnp)), residual_force(rho, *law),
                       rtol=1e-12, atol=1e-9)


def test_it_softens_past_the_load_where_e02s_curve_does(rows):
    """A curve whose mean slope above the load is below its tangent there: the law goes below the
    quadratic (which would keep stiffening, and overshoot a drop's peak force)."""
    tire, with_top, without = rows
    d, q = derive(with_top, tire), derive(without, tire)
    assert q.k_vr3 is None and (q.k_vr1, q.k_vr2, q.rho_r) == (d.k_vr1, d.k_vr2, d.rho_r)
    rho = d.rho_max
    quad = q.k_vr1 * rho + q.k_vr2 * rho**2
    assert residual_force(rho, *_law(d)) < quad
    assert q.residual_deflection(d.load_N) == pytest.approx(d.residual_deflection(d.load_N), rel=1e-12)


def test_a_top_it_cannot_meet_is_left_out():
    k_sv, k_bz, fz = 1.4e6, 7.0e6, 45e3
    k_t = 1.2 * k_sv
    ks = 1.0 / (1.0 / k_sv - 1.0 / k_bz)
    k_vr = 1.0 / (1.0 / k_t - 1.0 / k_bz)
    rest = fz / k_sv
    assert residual_spring(fz, k_sv, k_bz, k_vr, (1.02 * fz, rest + 0.02 * fz / k_t))[0]["k_vr3"] is None  # too close
    # a top reached only by a law that turns back (slope <= 0 at its end)
    far = residual_spring(fz, k_sv, k_bz, k_vr, (1.5 * fz, rest + 0.5 * fz / (0.2 * k_t)))[0]
    assert far["k_vr3"] is None and far["rho_r"] == pytest.approx(fz / ks)


def test_the_model_carries_the_law(rows):
    """The ring's contact force on the road at a belt deflection past E02's largest load is the law's,
    and its static rest under that load is E02's deflection."""
    tire, with_top, _ = rows
    d = derive(with_top, tire)
    m = RigidRing(RigidRingParams.from_derived(d), "reduced")
    f_max = with_top.q["max_load_N"]
    eq = vertical_equilibrium(d, f_max)
    assert tire.unloaded_radius_m - eq["z_a"] == pytest.approx(with_top.q["settled_deflection_at_max_load_m"], rel=1e-9)
    for rho in (0.5 * d.rho_r, 0.5 * (d.rho_r + d.rho_max), 1.2 * d.rho_max):
        y = _state(z_a=tire.unloaded_radius_m - rho, z_b=tire.unloaded_radius_m - rho)
        fz = float(m.forces(0.0, y, Drive.make())["F_z"])
        assert fz == pytest.approx(residual_force(rho, *_law(d)), rel=1e-12)
    assert not math.isclose(residual_force(1.2 * d.rho_max, *_law(d)),
                            d.k_vr1 * 1.2 * d.rho_max + d.k_vr2 * (1.2 * d.rho_max) ** 2, rel_tol=1e-3)
