"""E03 drum-cleat: config, input checks and the contact-extent measurement (fast); the physics on
the coarse mesh (slow: its drum surface and sample count make a phase program of their own): the
first mode rises with pressure.

(E06 traction is being rebuilt on a free drum; its tests will come with it. `physics/drum.py` is
tested in test_drum.py.)
"""

import numpy as np
import pytest

from jtire.config import load_run_config
from jtire.errors import ConfigError
from jtire.experiments import REGISTRY, patch
from jtire.experiments.cleat import drum_at
from jtire.experiments.phases import first_contact_height
from jtire.state import TireState

from .conftest import REPO, ok

CONFIG = REPO / "configs" / "experiments" / "drum_cleat.toml"
PSI, G0 = 6894.757293168, 9.81


def test_config_loads_and_registers():
    rc = load_run_config(CONFIG)
    (exp,) = rc.experiments
    assert type(exp) is REGISTRY["drum_cleat"]
    assert abs(rc.condition["pressure_Pa"] - 120 * PSI) < 1e-6 and abs(rc.condition["load_N"] - 4625 * G0) < 1e-6


def test_table_defaults_in_si():
    exp = load_run_config(CONFIG).experiments[0]
    assert abs(float(exp.speed) - 50 / 3.6) < 1e-12  # km/h -> m/s at the edge
    assert abs(float(exp.cleat_radius) - 0.1) < 1e-12 and float(exp.drum_radius) == 1.25
    assert abs(float(exp.cleat_height) - 0.02) < 1e-12
    # the impact phase holds lead + crossing + record at the sample rate
    assert exp.n_save == int(round((0.005 + 0.06 + 0.3) * 4000.0)) + 1


@pytest.mark.parametrize("override, field", [
    ("drum_cleat.cleat_height_mm=250", "cleat_height_mm"),  # taller than the cleat's diameter
    ("drum_cleat.f_band_Hz=[20.0, 3000.0]", "f_band_Hz"),  # beyond Nyquist at 4 kHz
    ("drum_cleat.f_band_Hz=[200.0, 20.0]", "f_band_Hz"),  # inverted
])
def test_bad_inputs_are_config_errors(override, field):
    # validation comes before any simulation (the experiment is built from the table)
    with pytest.raises(ConfigError, match=field):
        load_run_config(CONFIG, [override])


def test_cleat_coming_round_twice_is_refused():
    with pytest.raises(ConfigError, match="record_s"):
        load_run_config(CONFIG, ["drum_cleat.roll_settle_s=0.3", "drum_cleat.record_s=0.4"])


def test_contact_extent_on_a_drum_matches_the_flat_footprint(coarse_tire):
    """On a flat road the traced patch extent (E03's `x_range_traced`) and the host footprint
    (`patch.extent`, E01) sample the same spline surface and find the edges by the same rule: they
    differ only by the spline's implementation (scipy vs a fixed operator), 1e-12 m. A drum of 10 km
    radius is flat over the patch to ~1e-6 m: within 1 mm (one fine sample where the drum's sag
    l^2 / 8R flips it)."""
    m = coarse_tire.model
    y = TireState.at_rest(m, len(coarse_tire.params.relaxation_times))
    z = float(first_contact_height(m, y)) + 0.02  # 20 mm into the road
    length, width, area = patch.extent(m, y, patch.flat_gap(z))
    x0, x1 = (float(v) for v in patch.x_range_traced(m, y, patch.flat_gap(z)))
    assert abs((x1 - x0) - length) < 1e-12
    lt, wt = (float(v) for v in patch.extent_traced(m, y, patch.flat_gap(z)))
    assert abs(lt - length) < 1e-12 and abs(wt - width) < 1e-12
    x0d, x1d = (float(v) for v in patch.x_range_traced(m, y, patch.surface_gap(drum_at(1e4, z))))
    assert abs((x1d - x0d) - length) < 1e-3
    # and the host extent through the drum's own gap function (any contact partner)
    ld, wd, _ = patch.extent(m, y, patch.host_gap(patch.surface_gap(drum_at(1e4, z))))
    assert abs(ld - length) < 1e-3 and abs(wd - width) < 1e-3
    # a 20 mm chord cut of a ~0.57 m circle is ~0.3 m long: the patch is there
    assert length > 0.1 and 0 < area < length * width


def test_no_contact_gives_a_zero_patch(coarse_tire):
    m = coarse_tire.model
    y = TireState.at_rest(m, len(coarse_tire.params.relaxation_times))
    z = float(first_contact_height(m, y)) - 0.01  # the road 10 mm below the tire
    assert patch.extent(m, y, patch.flat_gap(z)) == (0.0, 0.0, 0.0)
    assert [float(v) for v in patch.extent_traced(m, y, patch.flat_gap(z))] == [0.0, 0.0]


@pytest.mark.slow
def test_first_mode_rises_with_pressure(spec, protocol, coarse_tire):
    """Inflation stiffens the sidewalls (their radial stiffness ~ p): the belt's vertical mode
    must move up from 70 to 150 psi. Coarse mesh, 0.2 s record (5 Hz bins, padded to 0.01 Hz)."""
    from jtire import batch

    from .conftest import make_experiment

    exp = make_experiment("drum_cleat", protocol, spec, roll_settle_s=0.05, record_s=0.2)
    lo, hi = (ok(r) for r in batch.run(exp, coarse_tire, [{"pressure_Pa": p * PSI, "load_N": 4625 * G0}
                                                           for p in (70.0, 150.0)], devices=1))
    for r in (lo, hi):
        assert r.quantities["padded_resolution_Hz"] <= 0.2 and not r.checks["spectrum_peak_at_band_edge"]
        assert r.checks["load_contact_vs_load_rel_error"] < 0.01
    f_lo, f_hi = lo.quantities["first_mode_Hz"], hi.quantities["first_mode_Hz"]
    assert f_hi > f_lo * 1.02, (f_lo, f_hi)  # 2 %: well above the interpolated-peak error (~0.1 %)
    assert np.isfinite(hi.quantities["k_dv_N_per_m"]) and hi.quantities["k_dv_N_per_m"] > 0
