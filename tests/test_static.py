"""Static experiments on the coarse ring (E01 footprint, E02 vertical stiffness): equilibrium,
symmetry and the expected trends.

E01 runs as one batch of four conditions (load and pressure varied) on the shared grid program;
the assertions are physical trends and balances, not the reported numbers (those come from the
default mesh, see README and benchmarks).
"""

import numpy as np
import pytest

from jtire.config import load_run_config
from jtire.errors import ConfigError

from .conftest import LOAD_RATED, REPO, ok


def test_settled_and_contact_force_equals_load(e01_grid):
    for r in map(ok, e01_grid.results):
        assert r.checks["inflate_settled"] and r.checks["load_settled"]
        # at rest the road carries the applied load to the runs' own equilibrium check, 1 %
        # (measured 0.55 % at the light load: the settle test's force balance stops the phase at
        # 1e-3 of the load on the rim plus the settle damping's load, and friction holds some shear)
        assert r.checks["contact_vs_load_rel_error"] < 0.01


def test_pure_vertical_load_gives_no_lateral_force(e01_grid):
    for r in map(ok, e01_grid.results):
        # mirror-symmetric mesh and load: lateral force below 1e-6 of the load (rounding of
        # 1e5-1e8 N/m stiffnesses) -- a sign error in any term would show at the % level
        assert abs(r.checks["contact_lateral_force_N"]) < 1e-6 * r.condition["load_N"]


def test_footprint_grows_with_load_and_shortens_with_pressure(e01_grid):
    light, rated, high_p, low_p = (ok(r).quantities for r in e01_grid.results)
    assert rated["contact_length_m"] > light["contact_length_m"]
    assert rated["contact_area_m2"] > light["contact_area_m2"]
    # pressure: the patch area shrinks 70 -> 120 -> 150 psi; its length shortens clearly from 70
    # to 120 psi. Between 120 and 150 psi the default mesh shortens it by 6 % (198 -> 187 mm,
    # slow test), which a 32-segment ring (98 mm segments) cannot resolve.
    assert high_p["contact_area_m2"] < rated["contact_area_m2"] < low_p["contact_area_m2"]
    assert rated["contact_length_m"] < 0.95 * low_p["contact_length_m"]


# Two paths to one equilibrium: the rated load ramped on and settled (E01), and the tire dropped 20 mm
# with the load on, bouncing and coming to rest (E04). Each is settled to its own force balance (1 %
# and 2 % of the load, TOL_EQUILIBRIUM of test_drop.py) and friction makes the patch edges path
# dependent, so their secant stiffnesses agree to the sum, 3 % (measured 0.6 %). It replaces a 40 %
# band around the study's 1280 kN/m, a calibration target the uncalibrated tire need not meet.
TOL_TWO_PATHS = 0.03


def test_vertical_stiffness_rises_with_pressure(e01_grid, e04_transient):
    _, rated, high_p, low_p = (ok(r).quantities for r in e01_grid.results)
    assert low_p["k_secant_N_per_m"] < rated["k_secant_N_per_m"] < high_p["k_secant_N_per_m"]
    assert rated["k_secant_N_per_m"] == pytest.approx(ok(e04_transient.results[0]).quantities["k_sv_N_per_m"],
                                                      rel=TOL_TWO_PATHS)


def test_footprint_quantities_consistent(e01_grid, spec):
    for r in map(ok, e01_grid.results):
        q = r.quantities
        assert q["contact_half_length_m"] == q["contact_length_m"] / 2
        # the patch is a cut of the tread surface: inside the length x width rectangle, and more
        # than half of it (an ellipse would fill pi/4)
        assert 0.5 * q["contact_length_m"] * q["contact_width_m"] < q["contact_area_m2"] < \
            q["contact_length_m"] * q["contact_width_m"]
        # the width never exceeds the tread
        assert q["contact_width_m"] <= spec.geometry.tread_width + 1e-9
        assert q["k_secant_N_per_m"] == pytest.approx(r.condition["load_N"] / q["deflection_m"], rel=1e-12)


def glassy_factor(params) -> float:
    """The most any rate can stiffen the rubber: every generalized stiffness K gains at most
    loss * sum c_b of it from its Maxwell branches (their instantaneous limit), with the largest loss."""
    return 1.0 + float(np.max(np.asarray(params.loss))) * float(np.sum(params.prony_weights))


def test_vertical_stiffness_ramp(e02, e02_static, coarse_tire):
    """E02 on the coarse ring with a 0.15 s ramp (was tests/test_cli_static.py, through the CLI). Its
    secant at the stated load lies between the static solve's (long-term moduli: the branches relaxed)
    and the static one times the glassy factor (1.53 here: no loading rate stiffens the rubber more):
    measured 1.105 (it was anywhere in 5e5-3e6 N/m)."""
    r = ok(e02.results[0])
    q, c = r.quantities, r.checks
    k_static = ok(e02_static.results[0]).quantities["k_sv_N_per_m"]
    assert 1.0 < q["k_sv_N_per_m"] / k_static < glassy_factor(coarse_tire.params)
    assert q["stated_load_N"] == LOAD_RATED  # stated_load_kN = 0: the condition's load
    assert c["load_settled"] and c["quasi_static_deflection_rel_error"] < 0.02
    # the fitted slope over 10-60 kN and the secant at the stated load describe one curve: the secant
    # of a stiffening curve lies below its upper-range slope, within 30 %
    assert q["fit_r2"] > 0.99
    assert 0.7 < q["k_sv_N_per_m"] / q["k_sv_fit_N_per_m"] < 1.3
    loads = np.asarray(r.signals["load_N"])
    assert np.all(np.diff(loads) >= 0) and loads[-1] > 0.95 * 60e3
    assert {"time_s", "load_N", "deflection_m", "contact_force_N"} <= set(r.signals)



def test_vertical_stiffness_tangent_at_the_load(e02, e02_static):
    """k_sv_tangent: the slope of the load-deflection curve at the stated load, static levels and ramp
    alike, checked against a chord of the record over ~8 kN around the load (the local quadratic and
    the chord differ by the curve's third derivative and the chord's off-centring: 5 % allows for it).
    No order is asserted between the ramp's tangent and the static one: on the coarse ring the ramp's
    secant is above the static one and its tangent below it (measured 1.55e6 against 1.82e6 N/m)."""
    for res in (e02_static, e02):
        q, s = ok(res.results[0]).quantities, ok(res.results[0]).signals
        F, x = np.asarray(s["load_N"]), np.asarray(s["deflection_m"])
        kt, stated = q["k_sv_tangent_N_per_m"], q["stated_load_N"]
        assert kt > q["k_sv_N_per_m"]  # the inflated tire's curve stiffens: the tangent is above the secant
        below, above = F < stated - 4e3, F > stated + 4e3  # a chord over ~8 kN around the load
        i, j = np.flatnonzero(below)[-1], np.flatnonzero(above)[0]
        assert kt == pytest.approx((F[j] - F[i]) / (x[j] - x[i]), rel=0.05)


@pytest.mark.parametrize("override, message", [
    (["vertical_stiffness.stated_load_kN=70"], "stated_load_kN = 70: must be at most max_load_kN"),
    (["vertical_stiffness.fit_range_kN=[10.0, 80.0]"], "fit_range_kN = \\[10, 80\\]: must end at or below"),
    (["vertical_stiffness.stated_load_kN=0", "condition.load_kg=7000"],
     "the stated load 68.67 kN must be in \\(0, max_load_kN = 60\\]"),
])
def test_vertical_stiffness_inconsistent_settings_refused(override, message):
    with pytest.raises(ConfigError, match=message):
        load_run_config(REPO / "configs" / "experiments" / "vertical_stiffness.toml", override)


# ---- the static method (the default of E01 and E02): static equilibrium at load levels --------------
def test_static_footprint_is_an_exact_equilibrium(e01_static):
    r = ok(e01_static.results[0])
    assert r.checks["static_converged"]
    # Newton converged to 1e-6 of the load scale (~0.07 N): the road carries the load to that level,
    # far tighter than a settled transient (0.5 %); 1e-5 leaves room for the contact resultant's sum
    assert r.checks["contact_vs_load_rel_error"] < 1e-5
    assert abs(r.checks["contact_lateral_force_N"]) < 1e-6 * r.condition["load_N"]  # mirror symmetry
    assert r.info["method"] == "static" and r.info["newton_iterations"] > 0


def test_static_and_settled_transient_agree(e01_static, e01_grid):
    """The static solve uses the long-term moduli; the transient settles (KE < 1e-3 J) while the
    Maxwell branches of the rubber still carry some stress (relaxation times up to ~0.1 s), so it
    reads slightly stiffer: the static deflection is larger, by less than 3 % (measured 1.2 % on the
    coarse ring). The patch is the same cut of the tread: length and width within 5 % (a 32-segment
    ring resolves the length to about a sixth of a segment)."""
    s, t = ok(e01_static.results[0]).quantities, ok(e01_grid.results[1]).quantities
    assert t["deflection_m"] < s["deflection_m"] < 1.03 * t["deflection_m"]
    assert s["contact_length_m"] == pytest.approx(t["contact_length_m"], rel=0.05)
    assert s["contact_width_m"] == pytest.approx(t["contact_width_m"], rel=0.05)


def test_static_vertical_curve(e02_static, e01_static):
    r = ok(e02_static.results[0])
    q, c = r.quantities, r.checks
    assert c["static_converged"] and c["contact_vs_load_max_rel_error"] < 1e-5
    loads, defl = (np.asarray(r.signals[k]) for k in ("load_N", "deflection_m"))
    assert np.all(np.diff(loads) >= 0) and loads[-1] == pytest.approx(60e3)
    assert np.all(np.diff(defl) >= -1e-12)  # more load, more deflection
    # a radial tire on a flat road stiffens with load (the patch grows): the incremental stiffness rises
    # over the curve. Not level by level: on the coarse ring (32 segments) a node row entering contact
    # and the friction at the patch edges step it by a few % either way (measured: -3 % .. +39 %
    # between neighbouring levels); from the lightest third of the levels to the heaviest it rises by
    # 36 % (measured), so 15 % is a margin that a softening or a flat curve cannot pass.
    up = np.diff(loads) > 1.0
    k_inc = np.diff(loads)[up] / np.diff(defl)[up]
    assert np.all(k_inc > 0)
    third = len(k_inc) // 3
    assert k_inc[-third:].mean() > 1.15 * k_inc[:third].mean()
    assert q["stated_load_N"] == LOAD_RATED and q["k_sv_N_per_m"] == pytest.approx(LOAD_RATED / q["deflection_m"])
    # E01 reaches the same load by another path of levels: friction makes statics path dependent,
    # but only at the patch edges: the same deflection to 0.1 %
    assert q["deflection_m"] == pytest.approx(ok(e01_static.results[0]).quantities["deflection_m"], rel=1e-3)


def test_static_lateral_stiffness(e09_static, e09, e01_static):
    """E09's static part as a static equilibrium (two lateral levels after E01's load path): it
    converges with the road carrying the load and the lateral force, its vertical part is E01's to
    the bit (the same levels in the same program), and k_l agrees with the settled transient's to
    1 % (measured 0.3 % on the coarse ring). The static solve uses the long-term moduli, the
    transient settles with its Maxwell branches not fully relaxed: the static k_l is not stiffer
    (0.1 % of slack for the friction at the patch edges, which makes the two load paths differ)."""
    s, t = ok(e09_static.results[0]), ok(e09.results[0])
    assert s.info["method"] == "static" and t.info.get("method") != "static"
    assert s.checks["static_converged"] and s.checks["static_residual_max_rel"] < 1e-5
    assert s.checks["contact_vs_load_rel_error"] < 1e-6 and s.checks["contact_vs_lateral_rel_error"] < 1e-6
    assert s.checks["vertical_deflection_m"] == ok(e01_static.results[0]).quantities["deflection_m"]
    k_s, k_t = s.quantities["k_l_N_per_m"], t.quantities["k_l_N_per_m"]
    assert k_s == pytest.approx(k_t, rel=0.01)
    assert k_s <= 1.001 * k_t
