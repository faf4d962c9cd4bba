"""Rotating contact partners (jtire.physics.drum) against closed forms: gaps, normals, the rigid
surface velocity omega x r, the union with a cleat, periodicity, jit / vmap / grad."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.errors import ConfigError
from jtire.physics import drum as dm
from jtire.physics.geometry_ops import V

TOL_GEOM = 1e-12  # m, m/s: closed forms evaluated in float64, rounding only
R_D = 1.25  # m, the E03 drum
TOP = -0.48  # m, drum top height (a loaded tire's patch sits about here)
SPEED = 50 / 3.6  # m/s
R_C, H_C = 0.1, 0.02  # m, cleat radius and height


def pts(*xyz):
    a = np.asarray(xyz, float).T
    return V(jnp.asarray(a[0]), jnp.asarray(a[1]), jnp.asarray(a[2]))


def arr(v):
    return np.stack([np.asarray(v.x), np.asarray(v.y), np.asarray(v.z)])


def test_drum_gap_normal_velocity_closed_form():
    d = dm.drum(R_D, TOP, SPEED)
    cz = TOP - R_D
    P = pts((0.0, 0.1, TOP + 0.01), (0.3, -0.2, cz + 0.4), (-1.0, 0.0, cz - 2.0), (0.0, 0.0, TOP - 0.005))
    gap, n, v = d.query(P, 0.3)
    r = np.array([[0.0, TOP + 0.01 - cz], [0.3, 0.4], [-1.0, -2.0], [0.0, TOP - 0.005 - cz]])
    dist = np.hypot(r[:, 0], r[:, 1])
    np.testing.assert_allclose(np.asarray(gap), dist - R_D, atol=TOL_GEOM)
    np.testing.assert_allclose(arr(n)[[0, 2]].T, r / dist[:, None], atol=TOL_GEOM)
    np.testing.assert_allclose(arr(n)[1], 0.0, atol=TOL_GEOM)
    # omega x r at the closest surface point, omega = -V / R about +y: the top moves at -V along x
    w = -SPEED / R_D
    Q = r / dist[:, None] * R_D
    np.testing.assert_allclose(arr(v).T, np.stack([w * Q[:, 1], 0 * Q[:, 0], -w * Q[:, 0]], 1), atol=TOL_GEOM)
    np.testing.assert_allclose(float(v.x[0]), -SPEED, atol=TOL_GEOM)


def test_surface_velocity_is_tangent_and_rigid():
    """omega x r: tangent to the drum (v . n = 0) and of magnitude |omega| R everywhere on it."""
    d = dm.drum(R_D, TOP, SPEED)
    ang = np.linspace(0, 2 * np.pi, 13)
    P = pts(*[(R_D * np.sin(a) * 1.01, 0.0, TOP - R_D + R_D * np.cos(a) * 1.01) for a in ang])
    _, n, v = d.query(P, 0.0)
    np.testing.assert_allclose(np.asarray(n.x * v.x + n.z * v.z), 0.0, atol=TOL_GEOM)
    np.testing.assert_allclose(np.hypot(np.asarray(v.x), np.asarray(v.z)), SPEED, rtol=1e-12)


def test_cleat_gap_closed_form_and_position():
    d = dm.drum(R_D, TOP, SPEED)
    phi = 0.2
    c = dm.cleat_on(d, R_C, H_C, phi)
    orbit = R_D + H_C - R_C
    ax, az = orbit * np.sin(phi), TOP - R_D + orbit * np.cos(phi)
    P = pts((ax + 0.3, 0.05, az + 0.4), (ax, 0.0, az + R_C), (ax - 0.05, 0.0, az))
    gap, n, v = c.query(P, 0.0)
    np.testing.assert_allclose(np.asarray(gap), [0.5 - R_C, 0.0, 0.05 - R_C], atol=TOL_GEOM)
    np.testing.assert_allclose(arr(n)[:, 0], [0.6, 0.0, 0.8], atol=TOL_GEOM)
    # the cleat's top stands H_C above the drum surface
    top = np.array([np.sin(phi), np.cos(phi)]) * (orbit + R_C)
    assert abs(np.hypot(*top) - R_D - H_C) < TOL_GEOM
    # it moves with the drum: after t the angle is phi + omega t
    t = 0.01
    ax2, az2 = c.axis(t)
    w = -SPEED / R_D
    assert abs(float(ax2) - orbit * np.sin(phi + w * t)) < TOL_GEOM
    assert abs(float(az2) - (TOP - R_D + orbit * np.cos(phi + w * t))) < TOL_GEOM


def test_union_is_minimum_and_picks_partner():
    d = dm.drum(R_D, TOP, SPEED)
    u = dm.drum_with_cleat(d, R_C, H_C, 0.0)
    rng = np.random.default_rng(0)
    P = pts(*np.column_stack([rng.uniform(-0.6, 0.6, 200), rng.uniform(-0.2, 0.2, 200), rng.uniform(TOP - 0.05, TOP + 0.15, 200)]))
    g, n, v = u.query(P, 0.0)
    gd, nd, vd = d.query(P, 0.0)
    gc, nc, vc = u.cleat.query(P, 0.0)
    np.testing.assert_allclose(np.asarray(g), np.minimum(np.asarray(gd), np.asarray(gc)), atol=0)
    on_cleat = np.asarray(gc) < np.asarray(gd)
    assert 0 < on_cleat.sum() < on_cleat.size  # both partners are picked somewhere
    np.testing.assert_array_equal(arr(n)[:, on_cleat], arr(nc)[:, on_cleat])
    np.testing.assert_array_equal(arr(v)[:, ~on_cleat], arr(vd)[:, ~on_cleat])
    # straight above the cleat its top is H_C above the drum top
    g_top, _, _ = u.query(pts((0.0, 0.0, TOP + 0.05)), 0.0)
    assert abs(float(g_top[0]) - (0.05 - H_C)) < TOL_GEOM


def test_cleat_top_periodic_in_drum_turn():
    """A point over the cleat's top sees the same gap one drum revolution later."""
    d = dm.drum(R_D, TOP, SPEED)
    t0 = 0.013
    u = dm.drum_with_cleat(d, R_C, H_C, 0.0, t_at=t0)
    period = 2 * math.pi * R_D / SPEED
    P = pts((0.0, 0.0, TOP + H_C + 0.003), (0.02, 0.1, TOP + H_C - 0.001))
    g0 = np.asarray(u.query(P, t0)[0])
    g1 = np.asarray(u.query(P, t0 + period)[0])
    np.testing.assert_allclose(g1, g0, atol=1e-9)  # 1e-9 m: the angle phi0 + omega t rounds at ~1e-15 rad x t
    assert abs(g0[0] - 0.003) < TOL_GEOM
    # half a turn later the cleat is at the bottom: the point sees the drum only
    gh = np.asarray(u.query(P, t0 + period / 2)[0])
    assert abs(gh[0] - (H_C + 0.003)) < TOL_GEOM


def test_jit_vmap_and_gradient():
    """Branchless: jit over traced parameters, vmap over speeds, and a finite gradient of the gap
    with respect to the drum's radius (d gap / d R = -1 for a point off the cleat)."""
    d = dm.drum(R_D, TOP, SPEED)
    u = dm.drum_with_cleat(d, R_C, H_C, 0.5)
    P = pts((0.0, 0.0, TOP + 0.01), (0.6, 0.0, TOP))
    f = eqx.filter_jit(lambda s, t: s.query(P, t)[0])
    np.testing.assert_allclose(np.asarray(f(u, 0.0)), np.asarray(u.query(P, 0.0)[0]), atol=TOL_GEOM)
    speeds = jnp.array([1.0, 5.0, 10.0])
    vx = jax.vmap(lambda w: eqx.tree_at(lambda s: s.omega, d, w).query(P, 0.0)[2].x)(-speeds / R_D)
    # the material velocity at the closest surface point (radius R_D), not at the query point
    np.testing.assert_allclose(np.asarray(vx[:, 0]), -np.asarray(speeds), rtol=1e-12)
    g = jax.grad(lambda r: eqx.tree_at(lambda s: s.drum.radius, u, r).query(P, 0.0)[0][0])(u.drum.radius)
    assert abs(float(g) + 1.0) < TOL_GEOM


def test_builders_reject_bad_input():
    with pytest.raises(ConfigError, match="drum radius"):
        dm.drum(-1.0, 0.0)
    d = dm.drum(R_D, TOP)
    with pytest.raises(ConfigError, match="cleat height"):
        dm.cleat_on(d, R_C, 3 * R_C, 0.0)
