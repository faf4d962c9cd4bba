"""E03 drum-cleat and E06 traction: configs, input checks and the contact-extent measurement
(fast); the physics on a coarse mesh (slow): the first mode rises with pressure, and the
traction force is ~0 at zero slip and has the sign of the slip."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.config import load_tire, parse_solver
from jtire.errors import ConfigError
from jtire.experiments import drum_cleat, static, traction
from jtire.experiments.phases import Protocol, flat_road
from jtire.experiments.registry import REGISTRY
from jtire.physics import drum as dm
from jtire.cli.run import load_run_config
from jtire.state import TireState
from jtire.tire import make_tire

ROOT = Path(__file__).resolve().parents[1]
TIRE = ROOT / "configs" / "tires" / "xone_xda.toml"
PSI, G0 = 6894.757293168, 9.81
N_COARSE = 32  # segments: half the default, ~2x cheaper per step; enough for the trends tested


def coarse_tire():
    return make_tire(dataclasses.replace(load_tire(TIRE), n_theta=N_COARSE))


@pytest.mark.parametrize("name", ["drum_cleat", "traction"])
def test_configs_load_and_register(name):
    spec, exps, cond, proto = load_run_config(ROOT / "configs" / "experiments" / f"{name}.toml")
    assert exps[0][0] is REGISTRY[name]
    assert abs(cond["pressure_Pa"] - 120 * PSI) < 1e-6 and abs(cond["load_N"] - 4625 * G0) < 1e-6


def test_drum_cleat_table_defaults_in_si():
    _, exps, _, _ = load_run_config(ROOT / "configs" / "experiments" / "drum_cleat.toml")
    t = exps[0][1]
    assert abs(t["speed_kmh"] - 50 / 3.6) < 1e-12  # km/h -> m/s at the edge
    assert abs(t["cleat_diameter_mm"] - 0.2) < 1e-12 and t["drum_diameter_m"] == 2.5


def test_bad_inputs_are_config_errors():
    cond = {"pressure_Pa": 120 * PSI, "load_N": 4625 * G0}
    base = dict(drum_diameter_m=3.4, speed_kmh=10.0, slips=(0.0, 0.01), free_damped_s=0.01, free_s=0.05,
                damped_s=0.0, measure_s=0.05, fit_range=(0.0, 0.1), linear_tol=0.1, half_length_from="flat")
    # validation comes before any simulation, so no tire is needed to reach it
    with pytest.raises(ConfigError, match="slips_percent"):
        traction.run_traction(None, cond, None, **base)
    with pytest.raises(ConfigError, match="half_length_from"):
        traction.run_traction(None, cond, None, **(base | dict(slips=(-0.01, 0.0, 0.01), half_length_from="x")))
    e03 = dict(drum_diameter_m=2.5, speed_kmh=50 / 3.6, cleat_diameter_mm=0.2, cleat_height_mm=0.02,
               roll_settle_s=0.06, lead_time_s=0.005, record_s=0.3, sample_rate_Hz=4000.0,
               f_band_Hz=(20.0, 200.0), pad_resolution_Hz=0.01)
    with pytest.raises(ConfigError, match="cleat_height_mm"):
        drum_cleat.run_drum_cleat(None, cond, None, **(e03 | dict(cleat_height_mm=0.25)))
    with pytest.raises(ConfigError, match="f_band_Hz"):
        drum_cleat.run_drum_cleat(None, cond, None, **(e03 | dict(f_band_Hz=(20.0, 3000.0))))
    with pytest.raises(ConfigError, match="record_s"):
        drum_cleat.run_drum_cleat(None, cond, None, **(e03 | dict(roll_settle_s=0.3, record_s=0.4)))


def test_contact_extent_matches_flat_footprint():
    """On a flat road contact_extent samples the tread exactly like static.footprint, so length
    and width agree to rounding; a drum of 10 km radius is flat over the patch to ~1e-6 m."""
    tire = coarse_tire()
    m = tire.model
    y = TireState.at_rest(m, len(tire.params.relaxation_times))
    z = float(np.min(np.asarray(m.tread_points(m.assemble(y.x, y.q)).z))) + 0.02  # 20 mm into the road
    length, width, _ = static.footprint(m, y, z)
    x0, x1, w = drum_cleat.contact_extent(m, y, flat_road(z))
    assert abs((x1 - x0) - length) < 1e-12 and abs(w - width) < 1e-12
    x0d, x1d, _ = drum_cleat.contact_extent(m, y, dm.drum(1e4, z))
    assert abs((x1d - x0d) - length) < 1e-3  # 1 mm: one fine sample where the drum's sag (l^2 / 8R ~ 1e-6 m) flips it
    assert length > 0.1  # a 20 mm chord cut of a ~0.5 m circle is ~0.28 m long: the patch is there


def _e03(tire, psi, record_s=0.2):
    proto = Protocol.from_dict(parse_solver({}))
    cond = {"pressure_Pa": psi * PSI, "load_N": 4625 * G0}
    return drum_cleat.run_drum_cleat(tire, cond, proto, drum_diameter_m=2.5, speed_kmh=50 / 3.6, cleat_diameter_mm=0.2,
                                     cleat_height_mm=0.02, roll_settle_s=0.05, lead_time_s=0.005, record_s=record_s,
                                     sample_rate_Hz=4000.0, f_band_Hz=(20.0, 200.0), pad_resolution_Hz=0.01)


@pytest.mark.slow
def test_first_mode_rises_with_pressure():
    """Inflation stiffens the sidewalls (their radial stiffness ~ p): the belt's vertical mode
    must move up from 70 to 150 psi. Coarse mesh, 0.2 s record (5 Hz bins, padded to 0.01 Hz)."""
    tire = coarse_tire()
    lo, hi = _e03(tire, 70.0), _e03(tire, 150.0)
    for r in (lo, hi):
        assert r.quantities["padded_resolution_Hz"] <= 0.2 and not r.checks["spectrum_peak_at_band_edge"]
    f_lo, f_hi = lo.quantities["first_mode_Hz"], hi.quantities["first_mode_Hz"]
    assert f_hi > f_lo * 1.02, (f_lo, f_hi)  # 2 %: well above the interpolated-peak error (~0.1 %)


@pytest.mark.slow
def test_traction_force_zero_at_zero_slip_and_signed():
    """Free rolling defines zero slip, so F_x(0) is only the rolling resistance: the curve crosses
    zero within 0.3 % of zero slip; driving pushes the tire forward (+x), braking back."""
    tire = coarse_tire()
    proto = Protocol.from_dict(parse_solver({}))
    cond = {"pressure_Pa": 120 * PSI, "load_N": 4625 * G0}
    r = traction.run_traction(tire, cond, proto, drum_diameter_m=3.4, speed_kmh=10.0, slips=(-0.01, 0.0, 0.01),
                              free_damped_s=0.04, free_s=0.15, damped_s=0.0, measure_s=0.12, fit_range=(-0.01, 0.01),
                              linear_tol=0.1, half_length_from="drum")
    k, fx = np.asarray(r.signals["slip"]), np.asarray(r.signals["force_x_N"])
    assert fx[k < 0][0] < 0 < fx[k > 0][0]
    # 0.3 % slip: rolling resistance (<~1 % of F_z) over a slip stiffness of ~5 F_z is <~0.2 %
    k0 = (fx[k > 0][0] - fx[k < 0][0]) / 0.02
    assert abs(fx[k == 0][0]) / k0 < 0.003, (fx, k0)
    assert r.quantities["k_k_N_per_slip"] > 0 and r.quantities["k_cx_N_per_m"] > 0
