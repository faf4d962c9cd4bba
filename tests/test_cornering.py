"""E10 cornering / E11 relaxation length (jtire.experiments.cornering).

Fast: the SAE sign convention of the lateral force, k_f and k_m from curves with known slopes,
config validation. Slow (simulations): antisymmetry F_y(-a) = -F_y(a), M_z(-a) = -M_z(a), and
one compilation for a whole slip-angle sweep (traces counted with eqx.debug.assert_max_traces).
"""

from pathlib import Path

import equinox as eqx
import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.errors import ConfigError
from jtire.experiments import cornering, rolling
from jtire.experiments.registry import REGISTRY

REPO = Path(__file__).resolve().parents[1]
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
    assert rolling.road_velocity(6.7, a)[1] > 0
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


def test_reduce_cornering_needs_three_angles_in_range():
    a = np.radians([0.0, 1.0, 5.0])
    with pytest.raises(ConfigError, match="at least 3"):
        cornering.reduce_cornering(a, a * 0, a, a, np.radians([0.0, 2.0]), np.radians([0.0, 6.0]))


@pytest.mark.parametrize("name", ["cornering", "relaxation_length"])
def test_configs_parse(name):
    from jtire.cli.run import load_run_config

    _, exps, cond, _ = load_run_config(CONFIGS / f"{name}.toml")
    (exp, table), = exps
    assert exp.name == name and cond["load_N"] == pytest.approx(4625 * 9.81)
    assert table["kf_range_deg"] == pytest.approx(np.radians([0.0, 2.0]))
    if name == "cornering":
        assert np.degrees(table["slip_angles_deg"]) == pytest.approx([0, 1, 2, 3, 4, 6, 8, 10, 12, 20])


def test_bad_range_rejected_before_simulating():
    table = dict(speed_mph=6.7, slip_angles_deg=(0.0,), settle_s=0.1, ramp_s=0.06, release_s=0.01, measure_s=0.05,
                 settle_damping_per_s=0.0, kf_range_deg=(0.04, 0.01), km_range_deg=(0.0, 0.05))
    with pytest.raises(ConfigError, match="kf_range_deg"):
        REGISTRY["cornering"].runner(None, {}, None, **table)


def test_config_rejects_out_of_range_angle():
    from jtire.cli.run import load_run_config

    with pytest.raises(ConfigError, match="slip_angles_deg"):
        load_run_config(CONFIGS / "cornering.toml", ["cornering.slip_angles_deg=[0, 45]"])


# ---- simulations (slow) -------------------------------------------------------------------------
TOL_ANTISYM = 1e-8  # relative: the mesh is mirror-symmetric in y and the two cases differ only in the sign of
# the road's lateral velocity, so they are mirror images up to rounding (measured 3e-15 on F_y, 3e-14 on M_z)


@pytest.mark.slow
def test_antisymmetry_and_one_compilation():
    from jtire.config import load_tire, parse_solver
    from jtire.experiments.phases import Protocol
    from jtire.tire import make_tire

    tire = make_tire(load_tire(REPO / "configs" / "tires" / "xone_xda.toml"))
    proto = Protocol.from_dict(parse_solver({}))
    p, load = 120 * 6894.757293168, 4625 * 9.81
    n0 = eqx.debug.get_num_traces(cornering.roll_batch_traced)
    a = np.radians([-2.0, 2.0])
    m, _ = cornering.slip_sweep(tire, p, load, proto, 6.7056, a, 0.1, 0.03, 0.01, 0.02, 0.0)
    assert eqx.debug.get_num_traces(cornering.roll_batch_traced) == n0 + 1  # settle, release, measure: one program
    assert m["F_y"][1] > 0 and m["M_z"][1] < 0  # a > 0: pushed left (ISO), aligning moment (M_z,SAE > 0)
    assert m["F_y"][0] == pytest.approx(-m["F_y"][1], rel=TOL_ANTISYM)
    assert m["M_z"][0] == pytest.approx(-m["M_z"][1], rel=TOL_ANTISYM)
    # a second sweep of the same size, other angles and load: no new trace, no new compilation
    cornering.slip_sweep(tire, p, 0.8 * load, proto, 6.7056, np.radians([1.0, 3.0]), 0.01, 0.01, 0.005, 0.005, 0.0)
    assert eqx.debug.get_num_traces(cornering.roll_batch_traced) == n0 + 1
