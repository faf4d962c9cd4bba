"""Contact pressure (jtire.contact_pressure) on states with a closed form, on the coarse ring.

An undeformed tire moved rigidly into a flat road: every contact point that penetrates by pen gets
the tread column's penalty k_n ramp(pen) (k_n = E_tread A / h), so p = E_tread ramp(pen) / h, plus
c_n * (approach speed) / A when the tire moves into the road. The check that the pressure of a
simulated, loaded footprint integrates to the load is in test_figures.py (it shares E01's run).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jtire import contact_pressure as cp
from jtire.physics.contact import OMEGA_REF, RAMP_EPS
from jtire.physics.geometry_ops import V, smooth_ramp
from jtire.state import TireState

REL = 1e-12  # float64 evaluation of the same expressions: round-off only
PEN = 3e-3  # m: the road 3 mm above the lowest tread point


@pytest.fixture(scope="module")
def pressed(coarse_tire):
    """The at-rest tire, its tread points, and a road PEN above its lowest tread point."""
    model, params = coarse_tire.model, coarse_tire.params
    y = TireState.at_rest(model, len(params.relaxation_times))
    P = model.tread_points(model.assemble(y.x, y.q))
    z = np.asarray(P.z)
    return model, params, y, z, float(z.min()) + PEN


def _closed_form(model, params, z, z_road, approach=0.0):
    """p (N,) of a rigidly placed tire: E ramp(pen) / h + c_n * approach / A while in contact."""
    h = np.repeat(np.asarray(model.tread_depth)[None, :], model.n_theta * model.n_sub, axis=0).reshape(-1)
    k_n, _, area = (np.asarray(a) for a in model.contact_stiffness(params))
    pen = z_road - z
    el = k_n * np.asarray(smooth_ramp(jnp.asarray(pen), RAMP_EPS))
    damp = np.where(pen > 0, float(params.tread_loss) * k_n / float(OMEGA_REF) * approach, 0.0)
    assert np.allclose(k_n / area, float(params.tread_E) / h, rtol=REL)  # the column stiffness E A / h
    return (el + damp) / area, area


def test_point_pressure_of_a_rigidly_pressed_tire(pressed):
    model, params, y, z, z_road = pressed
    p, area, P = (np.asarray(a) for a in cp.point_pressure(model, params, y, cp.flat_road(z_road)))
    want, area_cf = _closed_form(model, params, z, z_road)
    assert np.allclose(area, area_cf, rtol=REL)
    assert np.allclose(p, want, rtol=REL, atol=1e-9)
    inside = z_road - z > RAMP_EPS
    # a patch (3 mm into the coarse ring: the lowest crown points, 3 of them), and nothing pulls
    assert inside.sum() >= 3 and np.all(p[z > z_road] == 0.0)
    # deepest point: E_tread (pen - eps/2) / h exactly
    i = int(np.argmin(z))
    h = np.asarray(model.tread_depth)[i % len(model.tread_cols)]
    assert p[i] == pytest.approx(float(params.tread_E) * (PEN - RAMP_EPS / 2) / h, rel=REL)


def test_approach_speed_adds_the_tread_damping(pressed):
    """The state's velocities enter as the solver's normal damping (a moving state, not only positions)."""
    model, params, y, z, z_road = pressed
    v = 0.2  # m/s downward, the rim and every free node
    vz = V(jnp.zeros_like(y.v.x), jnp.zeros_like(y.v.y), jnp.full_like(y.v.z, -v))
    moving = eqx.tree_at(lambda s: (s.v, s.qd), y, (vz, y.qd.at[2].set(-v)))
    p, _, _ = (np.asarray(a) for a in cp.point_pressure(model, params, moving, cp.flat_road(z_road)))
    want, _ = _closed_form(model, params, z, z_road, approach=v)
    assert np.allclose(p, want, rtol=1e-10, atol=1e-9)  # the jvp of the tread-point map: rigid motion, exact


def test_nodal_pressure_carries_the_same_force(pressed):
    model, params, y, z, z_road = pressed
    road = cp.flat_road(z_road)
    F_n, _, _ = cp.point_normal_forces(model, params, y, road)
    pn = np.asarray(cp.nodal_pressure(model, params, y, road))
    assert pn.shape == (model.n_theta, model.n_s)
    node_area = np.asarray(model.w_node) * np.asarray(model.l_node)
    assert np.sum(pn * node_area) == pytest.approx(float(np.sum(F_n)), rel=REL)
    off_tread = np.setdiff1d(np.arange(model.n_s), model.tread_cols)
    assert np.all(pn[:, off_tread] == 0.0) and np.all(pn >= 0.0)


def test_footprint_table_keeps_the_patch(pressed):
    model, params, y, z, z_road = pressed
    t = cp.footprint_table(model, params, y, z_road)
    n = {len(v) for v in t.values()}
    assert len(n) == 1 and n.pop() == int(np.sum(z < z_road))  # every penetrating point, nothing else
    assert np.allclose(t["point_dx_m"] * t["point_dy_m"], t["point_area_m2"], rtol=REL)
    assert np.all(t["contact_pressure_Pa"] > 0)


def test_static_footprint_pressure_integrates_to_the_load(e01_static, coarse_tire):
    """E01's static footprint (the suite's run): the contact pressure times each point's area,
    summed over the patch, is the rim load -- to the static solve's tolerance, far inside 1e-4 --
    and the patch the pressure covers spans E01's reported length (within a contact point's size)."""
    r = e01_static.results[0]
    out = r.outputs[0]
    t = cp.footprint_table(coarse_tire.model, coarse_tire.params, out["y"], float(out["z_road"]))
    total = float(np.sum(t["contact_pressure_Pa"] * t["point_area_m2"]))
    assert total == pytest.approx(r.condition["load_N"], rel=1e-4)
    span = np.ptp(t["point_x_m"]) + np.max(t["point_dx_m"])
    assert abs(span - r.quantities["contact_length_m"]) < 2 * np.max(t["point_dx_m"])
