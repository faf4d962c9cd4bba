"""The section's geometry in the tire file and in a calibration (issue: geometry and belt construction
as calibration parameters; the mid-surface at the carcass).

- A tire file without the new fields builds the same mesh, node for node, as the tire file with their
  defaults written out (widest_point_ratio 0.5, mid_surface "section_width"): exact (same arithmetic).
- mid_surface = "carcass" moves the section's widest point inward by half the mid-sidewall's
  thickness, and widest_point_ratio moves its height: checked on a fine section (n_side 100) to
  within one element's length (2.7 mm).
- A free geometry parameter: its SI value and file value round-trip; MaterialParams do not see it;
  the stand-in recovers a known point with the crown radius and the rolling-resistance bias free.
- On the shell model (coarse ring): a point with the crown radius free gives, to the static solve's
  tolerance (1e-6 relative; measured 4e-9: exp(ln 3) is 3 to an ulp, and the Newton solve stops where
  its residual is small, not at one bit pattern), what the tire file edited to that radius gives; the geometry column of the Jacobian (a forward difference of 0.1 % in the
  radius) matches the secant over +-5 % to 5 % (the response is smooth and nearly linear in ln R
  there: its curvature over 5 % moves the secant by ~1 %).
"""

import dataclasses

import numpy as np
import pytest

from .conftest import COARSE_SET, REPO

STUDY = REPO / "configs" / "calibration" / "study.toml"
TIRE = REPO / "configs" / "tires" / "xone_xda.toml"


def test_a_tire_file_without_the_new_fields_builds_the_same_mesh(tmp_path):
    from jtire.config import load_tire
    from jtire.mesh import build_mesh

    text = TIRE.read_text()
    lines = [ln for ln in text.splitlines(keepends=True)
             if not ln.startswith(("widest_point_ratio", "mid_surface"))]
    assert len(lines) == len(text.splitlines()) - 2
    bare = tmp_path / "bare.toml"
    bare.write_text("".join(lines))
    a, b = load_tire(TIRE), load_tire(bare)
    assert a.geometry == b.geometry
    ma = build_mesh(a.geometry, a.masses, a.n_theta, a.n_side, a.n_crown)
    mb = build_mesh(b.geometry, b.masses, b.n_theta, b.n_side, b.n_crown)
    np.testing.assert_array_equal(ma.nodes, mb.nodes)


def _widest(g, n_side=100):
    from jtire.mesh import section_profile

    y, r, _ = section_profile(g, n_side, 4)
    k = int(np.argmax(y))
    return y[k], r[k], float(np.max(np.hypot(np.diff(y), np.diff(r))))


def test_mid_surface_and_widest_point_move_the_section():
    from jtire.config import load_tire

    g = load_tire(TIRE).geometry
    y0, r0, h = _widest(g)
    assert abs(y0 - g.section_width / 2) < h
    assert abs(r0 - (g.rim_radius + 0.5 * g.section_height)) < h
    t = load_tire(TIRE).parts["mid_sidewall"]["thickness"]
    gc = load_tire(TIRE, ['tire.mid_surface="carcass"']).geometry
    assert gc.carcass_inset == pytest.approx(t / 2)
    yc, _, h = _widest(gc)
    assert abs(yc - (g.section_width / 2 - t / 2)) < h
    gw = load_tire(TIRE, ["tire.widest_point_ratio=0.6"]).geometry
    _, rw, h = _widest(gw)
    assert abs(rw - (g.rim_radius + 0.6 * g.section_height)) < h


FREE_GEO = [{"name": "geometry.crown_radius", "bounds": [800.0, 6000.0], "why": "test"},
            {"name": "geometry.widest_point_ratio", "bounds": [0.4, 0.62], "why": "test"}]


def test_geometry_parameters_round_trip_and_stay_out_of_the_material():
    from jtire.calibration.tire.space import ParamSpace
    from jtire.calibration.tire.spec import load_calibration

    study = load_calibration(STUDY)
    sp = ParamSpace.from_config(FREE_GEO + [{"name": "tread.G", "factor": [0.5, 3.0]}], study.base_params,
                                geometry=study.tire.geometry)
    th = sp.default.copy()
    np.testing.assert_allclose(np.exp(th[:2]), [2.0, 0.5], rtol=1e-12)
    th[0] = np.log(3.2)
    assert sp.geometry_at(th).crown_radius == pytest.approx(3.2, rel=1e-12)
    assert sp.geometry_at(th).widest_point_ratio == pytest.approx(0.5, rel=1e-12)
    assert sp.file_values(th)[:2] == [("tire", "crown_radius_mm", pytest.approx(3200.0), "mm"),
                                      ("tire", "widest_point_ratio", pytest.approx(0.5), "")]
    p = sp.to_params(th, study.base_params)
    assert np.array_equal(np.asarray(p.E_meridional), np.asarray(study.base_params.E_meridional))
    np.testing.assert_allclose(sp.from_params(p), sp.default, rtol=0, atol=1e-12)


def test_the_calibrated_tire_carries_the_geometry(tmp_path):
    from jtire.calibration.tire.space import ParamSpace
    from jtire.calibration.tire.spec import load_calibration
    from jtire.calibration.tire.tire_toml import write_calibrated_tire

    study = load_calibration(STUDY)
    sp = ParamSpace.from_config(FREE_GEO, study.base_params, geometry=study.tire.geometry)
    th = np.log([3500.0e-3, 0.55])
    _, spec = write_calibrated_tire(tmp_path / "t.toml", TIRE.read_text(), sp, th)
    assert spec.geometry.crown_radius == pytest.approx(3.5, rel=1e-6)
    assert spec.geometry.widest_point_ratio == pytest.approx(0.55, rel=1e-6)


def test_standin_lm_recovers_a_known_crown_radius_and_bias():
    """The stand-in's k_v moves with the crown radius (calibration.tire.standin): DZ pins it, FX1 then pins b."""
    from jtire.calibration.tire.gradient import calibrate_lm
    from jtire.calibration.tire.runlog import RunLog
    from jtire.calibration.tire.space import ParamSpace
    from jtire.calibration.tire.spec import load_calibration
    from jtire.calibration.tire.standin import StandinSimulator

    study = load_calibration(STUDY)
    chosen = tuple(t for t in study.targets if t.name in ("DZ", "FX1"))
    free = [FREE_GEO[0], {"name": "bias.drag", "bounds": [0.0, 3000.0], "targets": ["FX1"]}]
    sp = ParamSpace.from_config(free, study.base_params, targets=chosen, geometry=study.tire.geometry)
    sim = StandinSimulator(sp, study.base_params, chosen)
    u_true = np.array([0.7, 0.3])
    y = sim.evaluate(sp.from_unit(u_true)[None])[0]
    targets = tuple(dataclasses.replace(t, measured=float(v)) for t, v in zip(chosen, y))
    res = calibrate_lm(sim, targets, RunLog(sim, targets, None, "lm", 0, 10**9, forward_budget=1e6),
                       tol_percent=1e-4, max_iterations=30)
    assert res.records[0]["total_error_pct"] > 1.0
    np.testing.assert_allclose(sp.to_unit(res.theta), u_true, atol=1e-4)


@pytest.fixture(scope="module")
def coarse_dz():
    """study.toml's DZ on the coarse ring with the crown radius free."""
    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.space import ParamSpace
    from jtire.calibration.tire.spec import load_calibration

    study = load_calibration(STUDY, COARSE_SET)
    chosen = tuple(t for t in study.targets if t.name == "DZ")
    sp = ParamSpace.from_config(FREE_GEO[:1], study.base_params, geometry=study.tire.geometry)
    spec = dataclasses.replace(study, targets=chosen, weights=(1.0,), space=sp)
    return study, spec, ShellSimulator(spec, spec.tire)


@pytest.mark.slow
def test_a_geometry_point_is_the_tire_file_at_that_geometry(coarse_dz):
    """Slow: 50 s from a cold compile cache (the fast suite's 15-minute budget)."""
    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration

    study, spec, sim = coarse_dz
    y = sim.evaluate(np.log([[3.0]]))[0, 0]
    edited = load_calibration(STUDY, COARSE_SET + ["tire.tire.crown_radius_mm=3000"])
    ref_spec = dataclasses.replace(edited, targets=spec.targets, weights=(1.0,))
    y_ref = ShellSimulator(ref_spec, edited.tire).evaluate(edited.space.default[None])[0, 0]
    assert y == pytest.approx(y_ref, rel=1e-6)
    assert abs(y / sim.evaluate(np.log([[2.0]]))[0, 0] - 1) > 1e-3  # and the radius moves it


@pytest.mark.slow
def test_the_geometry_column_is_a_forward_difference_of_the_response(coarse_dz):
    """Slow: the Jacobian compiles its own forward-mode programs (~70 s cold on the coarse ring)."""
    _, _, sim = coarse_dz
    th = np.log([2.0])
    _, J = sim.jacobian(th)
    lo, hi = sim.evaluate(np.array([[th[0] - 0.05], [th[0] + 0.05]]))[:, 0]
    assert J[0, 0] == pytest.approx((hi - lo) / 0.1, rel=0.05)


@pytest.mark.slow
def test_lm_through_the_shell_model_recovers_a_known_crown_radius_and_bias():
    """Known-point recovery through the shell model (coarse ring) with a geometry parameter and b free:
    DZ and DY (static) and FX1 (the steady-rolling solve), the crown radius, the tread's shear modulus
    and b on FX1. Tolerances: the crown radius's column is a forward difference (FD_STEP 1e-3 in ln R,
    truncation ~1e-3 relative), so LM converges linearly near the end rather than quadratically; it
    still reaches 0.01 % total and the point to 0.005 of the unit box (a 1e-4 error in DZ moves ln R by
    ~1e-4 / 0.12, under 1e-3 of its box; b's box is 3000 N wide, and FX1 to 1e-4 is 0.15 N of it)."""
    from jtire.calibration.tire.gradient import calibrate_lm

    from .test_calibration_shell_recovery import make_problem

    free = [FREE_GEO[0], {"name": "tread.G", "factor": [0.5, 3.0], "why": "synthetic"},
            {"name": "bias.drag", "bounds": [0.0, 3000.0], "targets": ["FX1"], "why": "synthetic"}]
    u_true = np.array([0.3, 0.6, 0.4])
    spec, targets, sim, RunLog = make_problem(("DZ", "DY", "FX1"), free, u_true)
    log = RunLog(sim, targets, None, "lm", 0, 10**9, forward_budget=1e6)
    res = calibrate_lm(sim, targets, log, tol_percent=0.01, max_iterations=20)
    assert res.records[0]["total_error_pct"] > 1.0
    assert res.stop_reason == "target" and res.total_error_pct <= 0.01
    np.testing.assert_allclose(spec.space.to_unit(res.theta), u_true, atol=0.005)
