"""ParamSpace, targets and the calibrated-tire writer: names <-> leaves, traceability, round trips,
and the one-line errors of a bad calibration config."""

import tomllib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jtire.calibration.tire.space import ParamSpace, allowed_names
from jtire.calibration.tire.spec import load_calibration
from jtire.calibration.tire.tire_toml import substitute, write_calibrated_tire
from jtire.config import tire_from_dict
from jtire.errors import ConfigError
from jtire.tire import params_from_spec

from .conftest import REPO, TIRE_TOML

STUDY = REPO / "configs" / "calibration" / "study.toml"


@pytest.fixture(scope="module")
def base(spec):
    return params_from_spec(spec)


FREE = [{"name": "parts.mid_sidewall.E_meridional", "factor": [0.5, 2.0]},
        {"name": "parts.crown.loss", "bounds": [0.05, 0.3]},
        {"name": "parts.lower_sidewall.E_meridional", "factor": [0.5, 2.0]},
        {"name": "tread.G", "bounds": [1.0, 3.0]}]


def test_names_map_to_leaves_and_back(base):
    sp = ParamSpace.from_config(FREE, base)
    assert sp.d == 4
    # the default is the tire's own value (bounds in the file's unit: MPa, none)
    np.testing.assert_allclose(np.exp(sp.default), [1300e6, 0.12, 1000e6, 1.5e6], rtol=1e-12)
    np.testing.assert_allclose(np.exp(sp.lower), [650e6, 0.05, 500e6, 1.0e6], rtol=1e-12)
    theta = sp.default + np.array([0.1, -0.2, 0.3, 0.05])
    p = sp.to_params(theta, base)
    assert float(p.E_meridional[2]) == pytest.approx(1300e6 * np.exp(0.1), rel=1e-12)
    assert float(p.E_meridional[1]) == pytest.approx(1000e6 * np.exp(0.3), rel=1e-12)
    assert float(p.loss[5]) == pytest.approx(0.12 * np.exp(-0.2), rel=1e-12)
    assert float(p.tread_G) == pytest.approx(1.5e6 * np.exp(0.05), rel=1e-12)
    # untouched leaves are the base's, dtypes kept
    np.testing.assert_array_equal(p.E_bending, base.E_bending)
    assert float(p.E_meridional[0]) == float(base.E_meridional[0])
    assert p.E_meridional.dtype == base.E_meridional.dtype and p.tread_G.dtype == base.tread_G.dtype
    np.testing.assert_allclose(sp.from_params(p), theta, rtol=0, atol=1e-14)


def test_to_params_is_traceable(base):
    """jit, vmap and jvp through to_params: the lead's simulator batches and differentiates it."""
    sp = ParamSpace.from_config(FREE, base)
    f = lambda th: sp.to_params(th, base).E_meridional[2] * sp.to_params(th, base).loss[5]  # noqa: E731
    thetas = jnp.asarray(sp.default + 0.1 * np.arange(12).reshape(3, 4) / 12)
    vals = jax.jit(jax.vmap(f))(thetas)
    np.testing.assert_allclose(vals, np.exp(thetas[:, 0]) * np.exp(thetas[:, 1]), rtol=1e-12)
    # d/dtheta of exp(t0) exp(t1) along e0 + e1 is 2 f (exact in log space)
    _, tangent = jax.jvp(f, (thetas[0],), (jnp.array([1.0, 1.0, 0.0, 0.0]),))
    assert float(tangent) == pytest.approx(2 * float(vals[0]), rel=1e-12)


@pytest.mark.parametrize("entry, words", [
    ({"name": "parts.mid_sidewall.E_radial", "factor": [0.5, 2]}, "unknown parameter"),
    ({"name": "parts.nose.loss", "factor": [0.5, 2]}, "unknown parameter"),
    ({"name": "tread.loss", "factor": [2.0, 0.5]}, "inverted"),
    ({"name": "tread.loss", "factor": [1.0, 1.0]}, "empty"),
    ({"name": "tread.loss", "bounds": [0.2, 0.3]}, "contain the tire's value"),
    ({"name": "tread.loss"}, "exactly one of factor"),
    ({"name": "tread.loss", "factor": [0.5, 2], "bounds": [0.1, 0.2]}, "exactly one of factor"),
    ({"name": "tread.loss", "factor": "wide"}, "two numbers"),
])
def test_bad_free_parameters_one_line(base, entry, words):
    with pytest.raises(ConfigError) as e:
        ParamSpace.from_config([entry], base)
    msg = str(e.value)
    assert words in msg and "\n" not in msg and "free[0]" in msg
    if "unknown parameter" in msg:
        assert allowed_names() in msg  # the message lists what is allowed


def test_duplicate_parameter_refused(base):
    with pytest.raises(ConfigError, match="listed twice"):
        ParamSpace.from_config([FREE[0], FREE[0]], base)


def test_shipped_configs_parse_with_reasons():
    # study, track: + the crown's three moduli, the crown radius and the drag bias
    for name, d in (("study", 25), ("study_moduli_only", 15), ("track", 25)):
        spec = load_calibration(REPO / "configs" / "calibration" / f"{name}.toml")
        assert spec.space.d == d and spec.response_names == ("DZ", "DY", "FX1", "FX2")
        assert all(len(r) > 10 for r in spec.space.reasons), name  # every parameter says why
    spec = load_calibration(STUDY)
    meas = [t.measured for t in spec.targets]
    np.testing.assert_allclose(meas, [39.0625e-3, 11.0997e-3, 1529.39, 1701.11], rtol=1e-12)
    assert spec.targets[0].table["stated_load_kN"] == pytest.approx(50e3)  # SI inside
    shown = spec.fingerprint()["targets"][0]["table"]  # the config's units where people read it
    assert shown["stated_load_kN"] == pytest.approx(50.0) and shown["max_load_kN"] == pytest.approx(60.0)
    assert shown["fit_range_kN"] == pytest.approx([10.0, 60.0])
    assert spec.targets[2].condition["load_N"] == pytest.approx(38.7e3)


def test_track_targets_come_from_the_data_fit():
    """track.toml: FX = RRC_trend(F_z) F_z of the 120 psi linear track fit (jtire.data)."""
    from jtire.data import analyze

    spec = load_calibration(REPO / "configs" / "calibration" / "track.toml")
    fit = analyze().fits["track_120psi"].linear
    for t in spec.targets[2:]:
        load = t.condition["load_N"]
        assert t.measured == pytest.approx((fit.a + fit.b * load) * load, rel=1e-12)
        assert "track_120psi" in t.source


def test_calibrated_tire_round_trips(tmp_path, base):
    sp = ParamSpace.from_config(FREE, base)
    theta = sp.default + np.array([0.2, 0.1, -0.3, 0.4])
    text = TIRE_TOML.read_text()
    path, spec2 = write_calibrated_tire(tmp_path / "t.toml", text, sp, theta, "made by a test")
    new = path.read_text()
    raw = tomllib.loads(new)
    assert raw["parts"]["mid_sidewall"]["E_meridional_MPa"] == pytest.approx(1300 * np.exp(0.2), rel=1e-5)
    assert raw["tread"]["G_MPa"] == pytest.approx(1.5 * np.exp(0.4), rel=1e-5)
    # comments and untouched lines are kept
    assert "calibrated (was 1300.0); steel carcass ply (same cords, thinner wall)" in new
    assert "# bead filler/apex rubber, stiff compound (8-15 MPa)" in new
    assert new.count("\n") == text.count("\n") + 1  # one header line added, nothing else
    np.testing.assert_allclose(ParamSpace.from_config(FREE, params_from_spec(spec2)).from_params(
        params_from_spec(spec2)), theta, atol=1e-5)
    assert tire_from_dict(raw).n_theta == 64


def test_substitute_refuses_a_missing_key():
    with pytest.raises(ConfigError, match="no key parts.crown.loss"):
        substitute("[parts.crown]\nE_bending_MPa = 3\n", [("parts.crown", "loss", 0.1, "")])
