"""E12 rolling resistance (jtire.experiments.rolling, stages).

Fast: the flat-track kinematics (road velocity vs the spinning tire), the whole-period window, the
damping ramp, the reduction on synthetic signals with known answers, config validation, and one
coarse-ring run (the shared single-case program): steady rolling, loads carried, energy balance.
Slow (default tire): the energy balance to 0.5 %, no drag without losses, drag rising with load.
"""

import dataclasses

import jax.numpy as jnp
import numpy as np
import pytest

from jtire.config import load_run_config
from jtire.errors import ConfigError
from jtire import signals
from jtire.experiments import rolling, stages
from jtire.physics import rim
from jtire.physics.geometry_ops import V

from .conftest import E12_LOAD, P_RATED, REPO, ok

CONFIG = REPO / "configs" / "experiments" / "rolling_resistance.toml"
SPEED = 6.7056  # m/s, 15 mph

TOL_EXACT = 1e-12  # closed-form kinematics and sums: rounding only
TOL_MEAN = 1e-9  # a mean over whole periods of a sampled sinusoid cancels it to rounding


# ---- kinematics and windows -----------------------------------------------------------------
def test_road_matches_bottom_of_tire_spinning_forward():
    # forward rolling = positive spin about +y (ISO): the bottom of the tire moves at -x with the road
    R = 0.4934
    q = jnp.zeros(6)
    qd = jnp.zeros(6).at[4].set(SPEED / R)
    bottom = V(jnp.zeros(1), jnp.zeros(1), jnp.full(1, -R))
    v = rim.frame_velocity(q, qd, bottom)
    np.testing.assert_allclose([float(v.x[0]), float(v.y[0]), float(v.z[0])], stages.road_velocity(SPEED),
                               atol=TOL_EXACT)


@pytest.mark.parametrize("deg", [1.0, 4.0, 20.0])
def test_road_velocity_slip_angle_sign(deg):
    # SAE slip angle a > 0: the wheel travels to the right of its heading. Its ground velocity is
    # minus the road's; in ISO (y left) its direction is at -a from +x.
    a = np.radians(deg)
    wheel = -np.asarray(stages.road_velocity(SPEED, a))
    assert np.linalg.norm(wheel) == pytest.approx(SPEED, rel=TOL_EXACT)
    assert np.arctan2(wheel[1], wheel[0]) == pytest.approx(-a, abs=TOL_EXACT)
    np.testing.assert_allclose(np.asarray(stages.road_velocity(SPEED, np.array([a, -a])))[:, 1],
                               [SPEED * np.sin(a), -SPEED * np.sin(a)], rtol=TOL_EXACT)


def test_release_schedule_ramps_to_zero():
    # (the schedule now gives damping fractions; the old one took the damping c0 and gave c0 x fraction)
    sched = stages.release_schedule(0.06)
    c = [c for c, _ in sched]
    assert len(sched) == round(0.06 / stages.RAMP_STAGE_S)
    assert sum(d for _, d in sched) == pytest.approx(0.06, rel=TOL_EXACT)
    assert all(a > b for a, b in zip(c, c[1:])) and 0 < c[-1] < 0.05 and c[0] > 0.95
    # smoothstep is antisymmetric about the ramp's middle: c(k) + c(n-1-k) = 1
    np.testing.assert_allclose(np.add(c, c[::-1]), 1.0, rtol=TOL_EXACT)
    assert stages.release_schedule(0.0) == []
    assert stages.stage_names(0.06, 0.02) == ["settle"] + ["ramp"] * 12 + ["release", "measure"]
    assert stages.stage_names(0.0, 0.0) == ["settle", "measure"]


def test_whole_periods_and_segment_period():
    omega = SPEED / 0.4934
    T = float(stages.segment_period(64, omega))
    assert T == pytest.approx(2 * np.pi * 0.4934 / (64 * SPEED), rel=TOL_EXACT)
    w = float(stages.whole_periods(0.1, T))
    assert w / T == pytest.approx(round(w / T), abs=1e-9) and abs(w - 0.1) <= T / 2
    assert float(stages.whole_periods(1e-6, T)) == pytest.approx(T)  # never zero periods


# ---- reduction on synthetic signals -----------------------------------------------------------
def _synthetic(drag=210.0, power=1408.0, k=14, n=201):
    """Hub force = -drag + two ripple harmonics over k whole periods; dissipated energy = linear
    + a periodic ripple (vanishes at whole periods). Returns t, fx, fz, dissipated."""
    T = 0.1
    t = np.linspace(0.0, T, n)
    w = 2 * np.pi * k / T
    fx = -drag + 900.0 * np.sin(w * t + 0.3) + 250.0 * np.sin(2 * w * t + 1.1)
    fz = 41400.0 + 300.0 * np.cos(w * t)
    d = 500.0 + power * t + 0.4 * np.sin(w * t)
    return t, fx, fz, d


def test_reduce_rolling_recovers_known_drag_and_power():
    t, fx, fz, d = _synthetic()
    q = rolling.reduce_rolling(t, fx, fz, d, SPEED)
    assert q["rolling_resistance_N"] == pytest.approx(210.0, rel=TOL_MEAN)
    assert q["dissipated_power_W"] == pytest.approx(1408.0, rel=TOL_MEAN)
    assert q["rolling_resistance_from_power_N"] == pytest.approx(1408.0 / SPEED, rel=TOL_MEAN)
    assert q["rrc"] == pytest.approx(210.0 / 41400.0, rel=TOL_MEAN)
    assert q["energy_balance_rel_diff"] == pytest.approx((210.0 - 1408.0 / SPEED) / (1408.0 / SPEED), rel=1e-7)
    assert abs(q["dissipated_power_halves_rel_diff"]) < 1e-3  # ripple 0.4 J over 0.05 s halves
    # a sliding loss of 34 W joins the rubber's 1408 W in the balance
    qf = rolling.reduce_rolling(t, fx, fz, d, SPEED, friction=2.0 + 34.0 * t)
    assert qf["friction_power_W"] == pytest.approx(34.0, rel=1e-9)
    assert qf["rubber_power_W"] == pytest.approx(q["dissipated_power_W"], rel=1e-12)
    assert qf["rolling_resistance_from_power_N"] == pytest.approx((q["dissipated_power_W"] + 34.0) / SPEED, rel=1e-12)


def test_block_stderr_closed_form():
    means = np.arange(10.0)
    y = np.repeat(means, 20)  # 10 blocks of 20 equal samples: stderr = std(means) / sqrt(10)
    assert signals.block_stderr(y) == pytest.approx(np.std(means, ddof=1) / np.sqrt(10), rel=TOL_EXACT)
    with pytest.raises(ConfigError):
        signals.block_stderr(np.ones(5))


# ---- config ---------------------------------------------------------------------------------
def test_config_parses_to_si():
    rc = load_run_config(CONFIG)
    (exp,) = rc.experiments
    assert exp.name == "rolling_resistance"
    assert float(exp.speed) == pytest.approx(SPEED, rel=TOL_EXACT)
    assert rc.condition["load_N"] == pytest.approx(41400.0)
    assert [L for L, _ in exp.calibration] == pytest.approx([38700.0, 41400.0])  # kN -> N
    assert [t for _, t in exp.calibration] == [1529.39, 1701.11]


@pytest.mark.parametrize("override, field", [("rolling_resistance.speed_mph=-3", "speed_mph"),
                                             ("rolling_resistance.measure_s=100", "measure_s"),
                                             ("rolling_resistance.nonsense=1", "nonsense"),
                                             ("rolling_resistance.calibration_targets_N=[1529.39]",
                                              "calibration_targets_N")])
def test_config_rejects_bad_fields(override, field):
    with pytest.raises(ConfigError, match=field):
        load_run_config(CONFIG, [override])


# ---- the coarse-ring run (fast) ---------------------------------------------------------------
# The coarse ring rolls roughly: its 32-segment polygon shakes the hub force (std ~2 kN around a
# ~200 N mean, block standard error ~0.6 kN over 80 ms) and the spin (std ~0.4 rad/s), so neither
# the drag nor the energy balance can be checked on it (the slow tests check them on the default
# ring, where the noise is far smaller); the loads and the loss bookkeeping can.
def test_coarse_rolling_loads_and_losses(e12):
    r = ok(e12.results[0])
    q, c = r.quantities, r.checks
    assert c["inflate_settled"] and c["load_settled"]
    assert c["vertical_force_vs_load_rel_error"] < 0.01  # the held load carries through to the road
    assert c["settle_work_in_measurement_J"] == 0.0  # no artificial damping while measuring
    assert q["rubber_power_W"] > 0 and q["rolling_resistance_from_power_N"] > 0
    assert 0 < q["friction_power_W"] < 0.2 * q["dissipated_power_W"]  # micro-slip: a small share
    assert q["dissipated_power_W"] == pytest.approx(q["rubber_power_W"] + q["friction_power_W"], rel=1e-12)
    assert q["rolling_resistance_from_power_N"] == pytest.approx(q["dissipated_power_W"] / SPEED, rel=1e-12)
    assert q["rrc"] == pytest.approx(q["rolling_resistance_N"] / q["vertical_force_N"], rel=1e-12)


def test_calibration_target_lookup(e12, coarse_tire):
    """The target of the calibration load within 0.5 % of the condition's load, or None (the reduction
    is host-only: re-reduced at other loads on the same outputs)."""
    r = ok(e12.results[0])
    exp = e12.exp
    assert r.quantities["target_N"] == 1701.11
    assert r.quantities["error_vs_target_rel"] == pytest.approx((r.quantities["rolling_resistance_N"] - 1701.11) / 1701.11)
    near = exp.reduce(coarse_tire, {"pressure_Pa": P_RATED, "load_N": 38.7e3 * 1.004}, r.outputs)
    assert near.quantities["target_N"] == 1529.39
    far = exp.reduce(coarse_tire, {"pressure_Pa": P_RATED, "load_N": 45370.0}, r.outputs)
    assert far.quantities["target_N"] is None and far.quantities["error_vs_target_rel"] is None


def test_rolling_signals_cover_every_stage(e12):
    r = ok(e12.results[0])
    sig = r.signals
    n = {len(v) for v in sig.values()}
    assert len(n) == 1
    names = e12.exp.stages()[2:]
    assert list(np.unique(sig["stage"])) == sorted({stages.STAGE_CODE[s] for s in names})
    assert np.all(np.diff(sig["time_s"]) >= 0)


# ---- simulations on the default tire (slow) -----------------------------------------------------
@pytest.fixture(scope="module")
def e12_default(spec, protocol):
    """run(load_N, lossless=False) -> quantities | checks, cached: the default tire, 120 psi, 15 mph,
    the E12 default stages (one compiled program serves every run)."""
    from jtire import batch
    from jtire.tire import make_tire

    from .conftest import make_experiment

    tire = make_tire(spec)
    exp = make_experiment("rolling_resistance", protocol, spec, method="transient")
    cache = {}

    def run(load, lossless=False):
        if (load, lossless) not in cache:
            t = dataclasses.replace(tire, params=tire.params.without_damping()) if lossless else tire
            (res,) = batch.run(exp, t, [{"pressure_Pa": P_RATED, "load_N": load}], devices=1)
            res = ok(res)
            cache[load, lossless] = res.quantities | res.checks
        return cache[load, lossless]

    return run


N_SIGMA = 3.0  # standard errors of the hub-force mean (block means) allowed on top
BALANCE_TOL = 0.005  # drag * V vs rubber + sliding losses: the remainder is the O(dt) bristle storage
# k_t |dz|^2 / 2 per step and the window's ends (measured -0.07 % at 41.4 kN; +2.4 % before sliding
# was counted)
LOSSLESS_FRACTION = 0.1  # without rubber losses only the friction slip (~5 N) and noise remain


@pytest.mark.slow
@pytest.mark.gate
def test_energy_balance(e12_default):
    q = e12_default(E12_LOAD)
    assert q["vertical_force_vs_load_rel_error"] < 0.01  # the held load carries through to the road
    assert q["rolling_resistance_from_power_N"] > 0
    noise = N_SIGMA * q["rolling_resistance_stderr_N"] / q["rolling_resistance_from_power_N"]
    # drag * V = rubber + sliding losses, both counted by the model
    assert abs(q["energy_balance_rel_diff"]) <= BALANCE_TOL + noise
    assert 0 < q["friction_power_W"] < 0.2 * q["dissipated_power_W"]  # micro-slip: a small share
    assert abs(q["dissipated_power_halves_rel_diff"]) < 0.02  # steady: both halves dissipate alike


@pytest.mark.slow
def test_no_drag_without_losses(e12_default):
    q0, q = e12_default(E12_LOAD, lossless=True), e12_default(E12_LOAD)
    assert q0["rubber_power_W"] == pytest.approx(0.0, abs=1e-9)  # every rubber loss is zero
    assert abs(q0["rolling_resistance_N"]) < LOSSLESS_FRACTION * q["rolling_resistance_N"]
    # what drag is left is the sliding loss: drag * V = friction power, up to the hub-force noise
    noise = N_SIGMA * q0["rolling_resistance_stderr_N"]
    assert abs(q0["rolling_resistance_N"] - q0["friction_power_W"] / SPEED) <= noise + 0.05 * q0["rolling_resistance_N"]


@pytest.mark.slow
def test_drag_rises_with_load(e12_default):
    lo, hi = e12_default(25000.0), e12_default(E12_LOAD)
    assert hi["rolling_resistance_from_power_N"] > 1.2 * lo["rolling_resistance_from_power_N"]
    assert hi["rolling_resistance_N"] - lo["rolling_resistance_N"] > N_SIGMA * np.hypot(
        hi["rolling_resistance_stderr_N"], lo["rolling_resistance_stderr_N"])


# The steady solve (the default) against the settled transient on the default mesh, where the README's
# figures come from. The lost power over the speed is the steadier reading of the transient (its hub
# force carries the polygon's ripple): the steady one agrees to 3 % (the goal; measured -0.7 %
# at 38.7 kN). The steady hub drag is the other reading of the same discretized flow, apart from its
# own lost power by up to a few percent on this mesh (docs/steady-rolling.md): against the transient's
# hub drag to 5 % plus 3 of its standard errors (measured -3.6 % at 38.7 kN).
@pytest.mark.slow
@pytest.mark.gate
def test_steady_agrees_with_the_settled_transient(e12_default, spec, protocol):
    from jtire import batch
    from jtire.tire import make_tire

    from .conftest import make_experiment

    exp = make_experiment("rolling_resistance", protocol, spec, method="steady")
    (res,) = batch.run(exp, make_tire(spec), [{"pressure_Pa": P_RATED, "load_N": E12_LOAD}], devices=1)
    s, t = ok(res).quantities, e12_default(E12_LOAD)
    assert s["rolling_resistance_from_power_N"] == pytest.approx(t["rolling_resistance_from_power_N"], rel=0.03)
    tol = 0.05 * t["rolling_resistance_N"] + N_SIGMA * t["rolling_resistance_stderr_N"]
    assert abs(s["rolling_resistance_N"] - t["rolling_resistance_N"]) <= tol
    assert s["spin_rad_per_s"] == pytest.approx(t["spin_rad_per_s"], rel=2e-3)  # measured 0.07 %
