"""E10 cornering / E11 relaxation length (jtire.experiments.cornering).

Fast: the SAE sign convention of the lateral force, k_f and k_m from curves with known slopes,
config validation; one coarse-ring sweep over 4 slip angles (one batch of the shared grid program):
antisymmetry F_y(-a) = -F_y(a), M_z(-a) = -M_z(a), signs, k_f under the brush model's and the trail
at its a / 3; and E11 from that sweep and the static E09. Slow: the same antisymmetry on the default
tire.
"""

import numpy as np
import pytest

from jtire.config import load_run_config
from jtire.errors import ConfigError
from jtire.experiments import cornering, loads, stages

from .conftest import REPO, contact_patch, ok

CONFIGS = REPO / "configs" / "experiments"

TOL_EXACT = 1e-9  # least squares on points exactly on a line: rounding only


def test_lateral_force_sae_sign():
    # a > 0 (SAE): the road pushes the tire LEFT, +y in ISO; in SAE (y right) that is negative
    a = np.radians(3.0)
    assert loads.lateral_sae(a, 0.0, 1000.0) == pytest.approx(-1000.0 * np.cos(a), rel=TOL_EXACT)
    # the drag (F_x < 0) leans into the lateral axis of the road frame: -F_x sin a > 0
    assert loads.lateral_sae(a, -200.0, 0.0) == pytest.approx(200.0 * np.sin(a), rel=TOL_EXACT)


def test_slip_angle_and_force_directions_agree():
    # the tire slides over the road along (tire velocity - road velocity) = -road velocity; the
    # friction on the tire opposes it: along +road velocity, whose y component must be +ISO (left)
    a = np.radians(2.0)
    assert float(stages.road_velocity(6.7, a)[1]) > 0
    assert loads.lateral_sae(a, 0.0, +1.0) < 0  # a left (ISO +y) force is negative in SAE


def test_reduce_cornering_known_slopes():
    a = np.radians([-2.0, -1, 0, 1, 2, 3, 4, 6])
    kf, km, drag = 2.4e5, 9.0e3, 250.0
    lat = -kf * a  # SAE lateral force, exactly linear
    fx = -drag - 0.5 * kf * a**2  # induced drag grows with the angle
    fy_iso = -(lat + fx * np.sin(a)) / np.cos(a)  # invert F_lat = F_y,SAE cos a - F_x sin a
    mz_iso = -km * a  # M_z,SAE = +k_m a
    q, curves = cornering.reduce_cornering(a, fx, fy_iso, mz_iso, np.radians([0.0, 2.0]), np.radians([0.0, 3.0]))
    assert q["k_f_N_per_rad"] == pytest.approx(kf, rel=TOL_EXACT)
    assert q["k_m_Nm_per_rad"] == pytest.approx(km, rel=TOL_EXACT)
    assert q["pneumatic_trail_m"] == pytest.approx(km / kf, rel=TOL_EXACT)
    assert q["k_f_range_deg"] == pytest.approx([0.0, 2.0])
    np.testing.assert_allclose(curves["lateral_force_N"], lat, rtol=TOL_EXACT, atol=1e-6)


def _steady_outputs(angles_deg, solved, k_f=2.5e5, k_m=8e3, load=45e3):
    """What the steady E10's simulate returns, made up: loaded levels that converged, forces exactly
    linear in the slip angle (F_y,ISO = k_f a, M_z,ISO = -k_m a), the sweep's levels one per angle,
    those not `solved` failed (residual 50 N) and repeating the last observation, as the sweep does."""
    from jtire.equilibrium import StaticInfo

    a = np.radians(np.asarray(angles_deg, float))
    n = len(a)

    def infos(conv):
        conv = np.asarray(conv, bool)
        return StaticInfo(np.full(len(conv), 5), np.full(len(conv), 2), np.full(len(conv), 9),
                          np.where(conv, 1e-3, 50.0), np.full(len(conv), 0.07), np.full(len(conv), 7e4), conv)

    f = np.stack([np.zeros(n), k_f * a, np.full(n, load)], axis=1)
    m = np.stack([np.zeros(n), np.zeros(n), -k_m * a], axis=1)
    return {"infos": infos([True] * 4), "sweep_infos": infos(solved), "sweep_values": a,
            "angles": {"contact_force": f, "contact_moment": m, "omega": np.full(n, 13.5)},
            "angle_solved": np.asarray(solved, bool)}


def test_steady_sweep_that_stops_beyond_the_fit_ranges(spec, protocol):
    """A steady sweep whose Newton solve stops at 6 deg (the angles beyond repeat the failure): k_f and
    k_m come from the solved angles (as from the whole sweep), the curve and signals hold only the solved
    angles, the peak force is not reported (it may lie among the unsolved), and the result names the
    missing angles and why. A stop inside a fit range (2 deg, in k_f's 0-2) is the case's error."""
    from jtire.errors import SimulationError

    from .conftest import make_experiment

    deg = [0, 1, 2, 3, 4, 6, 8]
    exp = make_experiment("cornering", protocol, spec, slip_angles_deg=deg, kf_range_deg=[0.0, 2.0],
                          km_range_deg=[0.0, 3.0])
    cond = {"pressure_Pa": 120 * 6894.757293168, "load_N": 45e3}
    full = exp._reduce_steady(cond, _steady_outputs(deg, [True] * 7))
    r = exp._reduce_steady(cond, _steady_outputs(deg, [True] * 5 + [False] * 2))
    for k, v in (("k_f_N_per_rad", 2.5e5), ("k_m_Nm_per_rad", 8e3)):  # the road frame's cos(a): 0.1 %
        assert r.quantities[k] == pytest.approx(full.quantities[k], rel=TOL_EXACT)
        assert r.quantities[k] == pytest.approx(v, rel=1e-3)
    assert r.quantities["peak_lateral_force_N"] is None
    assert list(r.signals["slip_angle_deg"]) == pytest.approx([0, 1, 2, 3, 4])
    assert r.info["unsolved_slip_angles_deg"] == pytest.approx([6.0, 8.0])
    assert r.info["sweep_stopped"].startswith("slip angle 6 deg: not converged")
    assert r.checks["sweep_converged"] and not r.checks["sweep_complete"]
    assert full.checks["sweep_complete"] and "unsolved_slip_angles_deg" not in full.info
    assert full.quantities["peak_lateral_force_N"] == pytest.approx(2.5e5 * np.radians(8) * np.cos(np.radians(8)),
                                                                    rel=TOL_EXACT)
    with pytest.raises(SimulationError, match="slip angle 2 deg"):
        exp._reduce_steady(cond, _steady_outputs(deg, [True, True] + [False] * 5))


def test_needs_three_angles_in_range_before_simulating():
    # (was a check of reduce_cornering; the angles are now checked when the experiment is built)
    with pytest.raises(ConfigError, match="need at least 3"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.slip_angles_deg=[0.0, 1.0, 5.0]"])
    with pytest.raises(ConfigError, match="lists an angle twice"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.slip_angles_deg=[0.0, 1.0, 1.0, 2.0]"])


@pytest.mark.parametrize("name", ["cornering", "relaxation_length"])
def test_configs_parse(name):
    rc = load_run_config(CONFIGS / f"{name}.toml")
    (exp,) = rc.experiments
    assert exp.name == name and rc.condition["load_N"] == pytest.approx(4625 * 9.81)
    kf = exp.kf_range if name == "cornering" else exp.cornering.kf_range
    assert kf == pytest.approx(tuple(np.radians([0.0, 2.0])))
    if name == "cornering":
        assert np.degrees(exp.slip_angles) == pytest.approx([0, 1, 2, 3, 4, 6, 8, 10, 12, 20])
        assert exp.method == "steady" and len(exp.cases(rc.condition)) == 1  # one continuation over the angles
        transient = load_run_config(CONFIGS / f"{name}.toml", ["cornering.method=transient"]).experiments[0]
        assert [c["slip_angle"] for c in transient.cases(rc.condition)] == pytest.approx(list(exp.slip_angles))
    else:
        assert float(exp.lateral.force) == pytest.approx(5e3) and not exp.lateral.with_decay


def test_bad_range_rejected_before_simulating():
    with pytest.raises(ConfigError, match="kf_range_deg"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.kf_range_deg=[2.0, 0.5]"])


def test_config_rejects_out_of_range_angle():
    with pytest.raises(ConfigError, match="slip_angles_deg"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.slip_angles_deg=[0, 45]"])


def test_relaxation_length_from_real_e09_and_e10_runs(e10, e09_static, e01_static, spec, protocol):
    """E11 on the coarse ring from the suite's real E10 sweep and static E09 at the rated condition:
    its components are exactly those runs' experiments (so the batch runner would run the very same
    cases: E11 is those two results combined), sigma = k_f / k_l of the two runs, and the quantities
    it declares. Independent bound (brush / stretched-string theory): a tread element reaches its
    steady deflection only after crossing the patch, and a compliant carcass adds its own lag, so
    the relaxation length exceeds the contact half length a (E01, same condition) -- measured
    sigma = 0.348 m = 3.3 a on the coarse ring."""
    import equinox as eqx

    from jtire.config import validate_table
    from jtire.experiments import REGISTRY

    from .conftest import E10_TABLE, RATED

    table = {k: E10_TABLE[k] for k in ("slip_angles_deg", "kf_range_deg", "settle_s", "ramp_s", "release_s",
                                       "measure_s")} | {"lateral_force_kN": 5.0, "method": "transient"}
    cls = REGISTRY["relaxation_length"]
    table = validate_table(table, cls.schema, cls.name)
    e11 = cls.from_table(table, protocol, spec)
    assert bool(eqx.tree_equal(e11.cornering, e10.exp))
    lat = e09_static.exp
    assert (e11.lateral.method, e11.lateral.with_decay) == (lat.method, lat.with_decay) == ("static", False)
    assert float(e11.lateral.force) == float(lat.force)
    kf_res, kl_res = ok(e10.results[0]), ok(e09_static.results[0])
    r = e11.combine(dict(RATED), [kf_res, kl_res])
    q = r.quantities
    assert set(q) == set(cls.produces(table))
    assert q["sigma_m"] == kf_res.quantities["k_f_N_per_rad"] / kl_res.quantities["k_l_N_per_m"]
    assert r.checks["lateral_static_converged"] and r.checks["load_settled (slip 2 deg)"]
    a = ok(e01_static.results[0]).quantities["contact_half_length_m"]
    assert q["sigma_m"] > a, (q["sigma_m"], a)


# ---- the coarse-ring sweep (fast) -----------------------------------------------------------------
TOL_ANTISYM = 1e-8  # relative: the mesh is mirror-symmetric in y and the two cases differ only in the sign of
# the road's lateral velocity, so they are mirror images up to rounding (measured 3e-15 on F_y, 3e-14 on M_z)


def test_antisymmetry_and_signs(e10):
    r = ok(e10.results[0])
    a = np.radians(r.signals["slip_angle_deg"])
    fy, mz = -r.signals["F_y_SAE_N"], r.signals["M_z_SAE_Nm"]  # ISO F_y
    neg, pos = int(np.argmin(a)), int(np.argmax(a))
    assert a[neg] == -a[pos] and a[pos] > 0
    assert fy[pos] > 0 and mz[pos] > 0  # a > 0: pushed left (ISO), aligning moment (M_z,SAE > 0)
    assert fy[neg] == pytest.approx(-fy[pos], rel=TOL_ANTISYM)
    assert mz[neg] == pytest.approx(-mz[pos], rel=TOL_ANTISYM)
    # the drag and the vertical force are even in the slip angle
    assert r.signals["F_x_N"][neg] == pytest.approx(r.signals["F_x_N"][pos], rel=TOL_ANTISYM)
    assert r.signals["F_z_N"][neg] == pytest.approx(r.signals["F_z_N"][pos], rel=TOL_ANTISYM)


def brush_cornering_stiffness(tire, e01_static) -> float:
    """k_f of the brush model with a rigid carcass (N/rad) on the model's own patch at the rated load
    (E01's static state): a tread point entering at the patch's front edge x_f and sticking is sheared
    by alpha (x_f - x) by the time it reaches x, so k_f = sum k_t (x_f - x) over the points in contact
    (k_t: each point's tread shear stiffness)."""
    x, k_t = contact_patch(tire, e01_static)
    return float(np.sum(k_t * (x.max() - x)))


def test_sweep_stiffnesses(e10, e01_static, coarse_tire):
    """k_f below the rigid-carcass brush model's, on the same patch and tread (the carcass's compliance
    -- its twist under the aligning moment, the belt's lateral bending -- only takes slip away from the
    tread: measured k_f = 0.53 of it); the pneumatic trail k_m / k_f inside the patch (0 < t < a: every
    tread point pushes the same way at small slip, so the resultant acts between the patch's ends)
    and at the brush model's a / 3 within 3 of its standard errors (from the fits' k_f and k_m
    standard errors; measured t = 0.0375 m, a / 3 = 0.035 m, 0.7 standard errors)."""
    r = ok(e10.results[0])
    q, c = r.quantities, r.checks
    settled = [v for k, v in c.items() if "_settled" in k]
    assert len(settled) == 2 * 4 and all(settled)  # inflate and load of every angle settled before rolling
    k_f, k_m = q["k_f_N_per_rad"], q["k_m_Nm_per_rad"]
    assert 0 < k_f < brush_cornering_stiffness(coarse_tire, e01_static)
    a = ok(e01_static.results[0]).quantities["contact_half_length_m"]
    t = q["pneumatic_trail_m"]
    assert t == pytest.approx(k_m / k_f, rel=1e-12) and 0 < t < a
    se_t = t * np.hypot(q["k_m_stderr_Nm_per_rad"] / k_m, q["k_f_stderr_N_per_rad"] / k_f)
    assert abs(t - a / 3) < 3 * se_t, (t, a / 3, se_t)
    # the lateral force is linear in 0-2 deg (r^2 of the fit) and the load carried at every angle
    assert q["k_f_fit_r2"] > 0.99
    assert c["max_vertical_force_vs_load_rel_error"] < 0.01
    assert q["peak_lateral_force_over_load"] < 0.8  # far below mu = 0.8 at 2 deg
    assert len(r.signals["slip_angle_deg"]) == 4


# ---- the default tire (slow) --------------------------------------------------------------------
@pytest.mark.slow
def test_antisymmetry_on_the_default_tire(spec, protocol):
    from jtire import batch, cache
    from jtire.tire import make_tire

    from .conftest import RATED, make_experiment

    tire = make_tire(spec)
    exp = make_experiment("cornering", protocol, spec, method="transient", slip_angles_deg=[-2.0, 0.0, 1.0, 2.0],
                          km_range_deg=[0.0, 2.0], settle_s=0.1, ramp_s=0.03, release_s=0.01, measure_s=0.02)
    n0 = batch.program_traces()
    (r,) = batch.run(exp, tire, [RATED])
    r = ok(r)
    assert batch.program_traces() - n0 <= 1  # every phase of every angle: one program
    fy, mz = -r.signals["F_y_SAE_N"], r.signals["M_z_SAE_Nm"]
    assert fy[3] > 0 and mz[3] > 0
    assert fy[0] == pytest.approx(-fy[3], rel=TOL_ANTISYM)
    assert mz[0] == pytest.approx(-mz[3], rel=TOL_ANTISYM)
    # a second sweep of the same size, other angles and load: no new trace, no new compilation
    exp2 = make_experiment("cornering", protocol, spec, method="transient", slip_angles_deg=[0.0, 1.0, 3.0, 4.0],
                           settle_s=0.01,
                           ramp_s=0.01, release_s=0.005, measure_s=0.005, kf_range_deg=[0.0, 4.0], km_range_deg=[0.0, 4.0])
    n1, c1 = batch.program_traces(), cache.clears()
    batch.run(exp2, tire, [dict(RATED, load_N=0.8 * RATED["load_N"])])
    assert batch.program_traces() - n1 <= cache.clears() - c1  # none, unless the programs were dropped
