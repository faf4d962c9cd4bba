"""E10 cornering / E11 relaxation length (jtire.experiments.cornering).

Fast: the SAE sign convention of the lateral force, k_f and k_m from curves with known slopes,
config validation, E11's combination; and one coarse-ring sweep over 4 slip angles (one batch of
the shared grid program): antisymmetry F_y(-a) = -F_y(a), M_z(-a) = -M_z(a), signs, positive
stiffnesses. Slow: the same antisymmetry on the default tire.
"""

import numpy as np
import pytest

from jtire.config import load_run_config
from jtire.errors import ConfigError
from jtire.experiments import cornering, stages
from jtire.experiments.result import ExperimentResult

from .conftest import REPO, ok

CONFIGS = REPO / "configs" / "experiments"

TOL_EXACT = 1e-9  # least squares on points exactly on a line: rounding only


def test_lateral_force_sae_sign():
    # a > 0 (SAE): the road pushes the tire LEFT, +y in ISO; in SAE (y right) that is negative
    a = np.radians(3.0)
    assert cornering.lateral_sae(a, 0.0, 1000.0) == pytest.approx(-1000.0 * np.cos(a), rel=TOL_EXACT)
    # the drag (F_x < 0) leans into the lateral axis of the road frame: -F_x sin a > 0
    assert cornering.lateral_sae(a, -200.0, 0.0) == pytest.approx(200.0 * np.sin(a), rel=TOL_EXACT)


def test_slip_angle_and_force_directions_agree():
    # the tire slides over the road along (tire velocity - road velocity) = -road velocity; the
    # friction on the tire opposes it: along +road velocity, whose y component must be +ISO (left)
    a = np.radians(2.0)
    assert float(stages.road_velocity(6.7, a)[1]) > 0
    assert cornering.lateral_sae(a, 0.0, +1.0) < 0  # a left (ISO +y) force is negative in SAE


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
        assert [c["slip_angle"] for c in exp.cases(rc.condition)] == pytest.approx(list(exp.slip_angles))
    else:
        assert float(exp.lateral.force) == pytest.approx(5e3) and not exp.lateral.with_decay


def test_bad_range_rejected_before_simulating():
    with pytest.raises(ConfigError, match="kf_range_deg"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.kf_range_deg=[2.0, 0.5]"])


def test_config_rejects_out_of_range_angle():
    with pytest.raises(ConfigError, match="slip_angles_deg"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.slip_angles_deg=[0, 45]"])


def test_relaxation_length_combines_k_f_and_k_l():
    exp = load_run_config(CONFIGS / "relaxation_length.toml").experiments[0]
    cond = {"pressure_Pa": 8.27e5, "load_N": 45e3}
    kf = ExperimentResult("cornering", cond, {"k_f_N_per_rad": 2.4e5, "k_f_fit_r2": 0.999, "k_f_range_deg": [0.0, 2.0]},
                          checks={"load_settled": True})
    kl = ExperimentResult("lateral_stiffness", cond, {"k_l_N_per_m": 4.5e5, "lateral_force_N": 5e3,
                                                      "lateral_deflection_m": 5e3 / 4.5e5}, checks={"load_settled": True})
    r = exp.combine(cond, [kf, kl])
    assert r.quantities["sigma_m"] == pytest.approx(2.4e5 / 4.5e5, rel=1e-15)
    assert r.checks["lateral_load_settled"] and r.checks["load_settled"]


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


def test_sweep_stiffnesses(e10):
    r = ok(e10.results[0])
    q, c = r.quantities, r.checks
    settled = [v for k, v in c.items() if "_settled" in k]
    assert len(settled) == 2 * 4 and all(settled)  # inflate and load of every angle settled before rolling
    assert q["k_f_N_per_rad"] > 0 and q["k_m_Nm_per_rad"] > 0
    # the lateral force is linear in 0-2 deg (r^2 of the fit) and the load carried at every angle
    assert q["k_f_fit_r2"] > 0.99
    assert c["max_vertical_force_vs_load_rel_error"] < 0.01
    assert q["peak_lateral_force_over_load"] < 0.8  # far below mu = 0.8 at 2 deg
    assert len(r.signals["slip_angle_deg"]) == 4


# ---- the default tire (slow) --------------------------------------------------------------------
@pytest.mark.slow
def test_antisymmetry_on_the_default_tire(spec, protocol):
    from jtire import batch
    from jtire.tire import make_tire

    from .conftest import RATED, make_experiment

    tire = make_tire(spec)
    exp = make_experiment("cornering", protocol, spec, slip_angles_deg=[-2.0, 0.0, 1.0, 2.0], km_range_deg=[0.0, 2.0],
                          settle_s=0.1, ramp_s=0.03, release_s=0.01, measure_s=0.02)
    n0 = batch.program_traces()
    (r,) = batch.run(exp, tire, [RATED])
    r = ok(r)
    assert batch.program_traces() - n0 <= 1  # every phase of every angle: one program
    fy, mz = -r.signals["F_y_SAE_N"], r.signals["M_z_SAE_Nm"]
    assert fy[3] > 0 and mz[3] > 0
    assert fy[0] == pytest.approx(-fy[3], rel=TOL_ANTISYM)
    assert mz[0] == pytest.approx(-mz[3], rel=TOL_ANTISYM)
    # a second sweep of the same size, other angles and load: no new trace, no new compilation
    exp2 = make_experiment("cornering", protocol, spec, slip_angles_deg=[0.0, 1.0, 3.0, 4.0], settle_s=0.01,
                           ramp_s=0.01, release_s=0.005, measure_s=0.005, kf_range_deg=[0.0, 4.0], km_range_deg=[0.0, 4.0])
    n1 = batch.program_traces()
    batch.run(exp2, tire, [dict(RATED, load_N=0.8 * RATED["load_N"])])
    assert batch.program_traces() == n1
