"""The rolling-resistance measurement model FX_measured = FX_tire + b (calibration.tire.space `bias.*`):
a named, non-negative, non-tire bias that the calibration fits and the posterior samples beside the
tire's parameters, and that never enters the tire file.

On the closed-form STAND-IN simulator (not physics): what is checked is the machinery (the bias
enters the responses and the Jacobian exactly, a known tire + bias is recovered, the outputs split
tire and bias, a config without a bias is unchanged, bad bias entries are one line, exit 2).
"""

import dataclasses
import json

import numpy as np
import pytest

from jtire.calibration.tire.gradient import calibrate_lm
from jtire.calibration.tire.runlog import RunLog
from jtire.calibration.tire.space import ParamSpace
from jtire.calibration.tire.spec import load_calibration
from jtire.calibration.tire.standin import StandinSimulator
from jtire.errors import ConfigError

from .conftest import REPO

STUDY = REPO / "configs" / "calibration" / "study.toml"
BIAS = {"name": "bias.non_tire_drag", "bounds": [0.0, 3000.0], "targets": ["FX1", "FX2"],
        "why": "test"}
FREE = [{"name": "parts.mid_sidewall.E_bending", "factor": [0.33, 3]},
        {"name": "tread.G", "factor": [0.5, 3]},
        {"name": "parts.mid_sidewall.loss", "bounds": [0.03, 0.4]}, BIAS]


@pytest.fixture(scope="module")
def study():
    return load_calibration(STUDY)


def test_bias_enters_the_responses_and_the_jacobian_exactly(study):
    sp = ParamSpace.from_config(FREE, study.base_params, targets=study.targets)
    assert sp.is_bias(3) and sp.has_bias and sp.tire_indices == [0, 1, 2]
    assert sp.default[3] == 0.0  # starts with no bias: the tire alone
    sim = StandinSimulator(sp, study.base_params, study.targets)
    th = sp.from_unit(np.array([0.4, 0.4, 0.4, 0.0]))
    th_b = th.copy()
    th_b[3] = 750.0
    y0, yb = sim.evaluate(np.stack([th, th_b]))
    # DZ, DY untouched; FX1, FX2 moved by exactly b (a sum: 1e-9 relative of ~1 kN)
    np.testing.assert_array_equal(y0[:2], yb[:2])
    np.testing.assert_allclose(yb[2:] - y0[2:], 750.0, rtol=1e-9)
    v, J = sim.jacobian(th_b)
    np.testing.assert_allclose(v, yb, rtol=1e-12)
    np.testing.assert_array_equal(J[:, 3], [0.0, 0.0, 1.0, 1.0])  # d(tire + b)/db
    # the tire's own parameters and file never see the bias
    assert [t for t, *_ in sp.file_values(th_b)] == ["parts.mid_sidewall", "tread",
                                                      "parts.mid_sidewall"]
    assert sp.values(th_b)["bias.non_tire_drag"] == 750.0
    p0, pb = sp.to_params(th, study.base_params), sp.to_params(th_b, study.base_params)
    np.testing.assert_array_equal(np.asarray(p0.loss), np.asarray(pb.loss))


def test_lm_recovers_a_known_tire_and_bias(study):
    # The truth: a tire point inside the box and b = 900 N. Two loads 7 % apart separate a
    # constant b from the tire's load-growing drag only weakly, but on a deterministic simulator
    # Gauss-Newton still converges: 1e-4 % total error, b to 1 N (measured: 0.3 N) and the tire's
    # coordinates to 1e-3 of the box.
    sp = ParamSpace.from_config(FREE, study.base_params, targets=study.targets)
    truth = sp.from_unit(np.array([0.7, 0.35, 0.6, 0.3]))
    y = StandinSimulator(sp, study.base_params, study.targets).evaluate(truth[None])[0]
    tg = tuple(dataclasses.replace(t, measured=float(v)) for t, v in zip(study.targets, y))
    sim = StandinSimulator(sp, study.base_params, tg)
    log = RunLog(sim, tg, None, "lm", 0, 10**9, forward_budget=1e6)
    res = calibrate_lm(sim, tg, log, tol_percent=1e-4, max_iterations=60)
    assert res.records[0]["total_error_pct"] > 10.0  # no bias and the default tire: far off
    assert res.total_error_pct <= 1e-4
    assert abs(res.theta[3] - truth[3]) < 1.0
    np.testing.assert_allclose(sp.to_unit(res.theta)[:3], sp.to_unit(truth)[:3], atol=1e-3)


def test_outputs_split_tire_and_bias(tmp_path, study):
    from jtire.calibration.tire.run import run_calibration

    spec = dataclasses.replace(study, space=ParamSpace.from_config(FREE, study.base_params,
                                                                   targets=study.targets))
    sim = StandinSimulator(spec.space, spec.base_params, spec.targets)
    res, paths = run_calibration(spec, sim, tmp_path, "lm", 30)
    s = json.loads(paths["summary"].read_text())
    b = s["bias_SI"]["bias.non_tire_drag"][0]
    assert s["bias_SI"]["bias.non_tire_drag"][1:] == ["N", ["FX1", "FX2"]]
    for n in ("FX1", "FX2"):
        assert s["responses_SI"][n] - s["tire_responses_SI"][n] == pytest.approx(b, rel=1e-12)
    for n in ("DZ", "DY"):
        assert s["responses_SI"][n] == s["tire_responses_SI"][n]
    md = paths["table_md"].read_text()
    assert "| tire | bias |" in md
    # beside each free loss: the true tan delta and E'/K at the rolling frequencies (15 mph: the
    # wheel of 0.5095 m outer radius turns at 2.1 Hz; the footprint passes at V over the FL check's
    # simulated length: the stand-in's ~0.2 m, ~33 Hz)
    assert "What each loss parameter means" in md and "parts.mid_sidewall.loss" in md
    row = s["loss_factors"][0]
    assert row["rotation_Hz"] == pytest.approx(6.7056 / (2 * 3.14159265 * 0.5095), rel=1e-3)
    assert row["footprint_Hz"] == pytest.approx(6.7056 / s["checks"]["FL"]["simulated_SI"], rel=1e-9)
    tire = paths["tire"].read_text()
    assert "bias.non_tire_drag" in tire.split("[", 1)[0]  # named in the header comment only
    assert "non_tire_drag =" not in tire.split("\n[", 1)[1]


def test_a_config_without_a_bias_is_unchanged():
    # the fingerprint's space has no bias key, so an existing calibration folder still resumes, and
    # the responses are the tire's own
    spec = load_calibration(REPO / "configs" / "calibration" / "study_moduli_only.toml")
    d = spec.space.as_dict()
    assert set(d) == {"names", "lower", "upper", "default"} and not spec.space.has_bias
    assert spec.space.bias_matrix(spec.response_names).sum() == 0.0
    y = np.arange(8.0).reshape(2, 4)
    assert spec.space.add_bias(np.zeros((2, spec.space.d)), y, spec.response_names) is not None
    np.testing.assert_array_equal(spec.space.add_bias(np.ones((2, spec.space.d)), y, spec.response_names), y)


@pytest.mark.parametrize("entry, words", [
    ({**BIAS, "bounds": [-10.0, 3000.0]}, "0 <= lo < hi"),
    ({**BIAS, "bounds": [500.0, 100.0]}, "0 <= lo < hi"),
    ({**BIAS, "targets": ["FX9"]}, "'FX9' is not a target"),
    ({**BIAS, "targets": ["DZ", "FX1"]}, "one unit"),
    ({**BIAS, "targets": []}, "non-empty list"),
    ({k: v for k, v in BIAS.items() if k != "targets"}, "non-empty list"),
    ({**BIAS, "factor": [0.5, 2.0]}, "no tire value to scale"),
    ({"name": "tread.G", "factor": [0.5, 3], "targets": ["FX1"]}, "unknown field"),
])
def test_bad_bias_entries_are_one_line(study, entry, words):
    with pytest.raises(ConfigError, match=words.replace("(", r"\(").replace(")", r"\)")):
        ParamSpace.from_config([FREE[0], entry], study.base_params, targets=study.targets)
# the same from the command line (one line, exit 2): tests/test_bad_inputs_calibration.py calibrate-bias-*


def test_dynamic_modulus_is_the_prony_series():
    # `loss` is the band-averaged small-loss tan delta: over 1-100 Hz (log-spaced) the exact tan delta
    # of a small loss averages to it (1e-3 relative: the storage modulus is 1 + O(loss)); the storage
    # modulus climbs from ~1 well below the branches to 1 + loss sum(c_b) far above them
    from jtire.materials import dynamic_modulus, prony_weights

    tau = [1e-3, 6e-3, 40e-3]
    f = np.logspace(0, 2, 200)
    tan_d, storage = dynamic_modulus(1e-4, tau, f)
    assert np.mean(tan_d) == pytest.approx(1e-4, rel=1e-3)
    _, lo = dynamic_modulus(0.3, tau, 1e-4)
    _, hi = dynamic_modulus(0.3, tau, 1e6)
    assert lo == pytest.approx(1.0, abs=1e-5)
    assert hi == pytest.approx(1.0 + 0.3 * prony_weights(tau).sum(), rel=1e-5)


def test_nodal_damping_is_a_linear_tire_parameter(tmp_path, study):
    """model_form.nodal_damping (the study's model form): a tire parameter searched linearly from its
    default 0 (off), written to the calibrated tire's [model_form] table and read back."""
    from jtire.calibration.tire.tire_toml import write_calibrated_tire

    free = FREE[:1] + [{"name": "model_form.nodal_damping", "bounds": [0.0, 3.0]}]
    sp = ParamSpace.from_config(free, study.base_params, targets=study.targets)
    assert sp.is_linear(1) and not sp.is_bias(1) and sp.default[1] == 0.0 and sp.lower[1] == 0.0
    th = np.array([sp.default[0], 1.3])
    assert float(sp.to_params(th, study.base_params).nodal_damping) == 1.3
    assert sp.file_values(th)[1] == ("model_form", "nodal_damping_per_s", 1.3, "1/s")
    _, tire = write_calibrated_tire(tmp_path / "t.toml", study.tire_path.read_text(), sp, th)
    assert tire.nodal_damping == 1.3
    with pytest.raises(ConfigError, match="searched linearly"):
        ParamSpace.from_config(FREE[:1] + [{"name": "model_form.nodal_damping", "factor": [0.5, 2]}],
                               study.base_params)
    with pytest.raises(ConfigError, match="0 <= lo < hi"):
        ParamSpace.from_config(FREE[:1] + [{"name": "model_form.nodal_damping", "bounds": [-1.0, 2]}],
                               study.base_params)


def test_the_emulator_learns_the_tire_and_adds_the_bias(study):
    """With a bias free, the posterior's emulator is fitted to the tire's own responses (a run less its
    known b) and adds b back exactly, instead of learning the sum. On stand-in runs over the study box
    (21 parameters, 60 runs, linear and reduced surfaces, 40 held out): the FX totals' rms error in ln
    0.051 against 0.088 fitted to the totals (0.027 against 0.056 with 120 runs; with the GP 0.044
    against 0.114): asserted below 0.75 of it. The split is exact: ln(tire + b) of the tire's model."""
    import types

    from jtire.calibration.posterior.emulator import fit_emulator

    sp = study.space
    sim = StandinSimulator(sp, study.base_params, study.targets)
    rng = np.random.default_rng(0)
    train, test = sp.from_unit(rng.uniform(size=(60, sp.d))), sp.from_unit(rng.uniform(size=(40, sp.d)))
    y_train, y = sim.evaluate(train), sim.evaluate(test)
    emu = fit_emulator(sp, sim.response_names, train, y_train, ("linear", "reduced"))
    mu, var = emu.predict(test)
    mt, _ = emu.predict_tire(test)
    B = sp.bias_matrix(sim.response_names)
    np.testing.assert_allclose(mu, np.log(np.exp(mt) + test @ B.T), rtol=1e-12)
    assert np.all(var >= 0)
    # the same runs fitted as totals (a space that declares no bias)
    plain = types.SimpleNamespace(d=sp.d, to_unit=sp.to_unit, has_bias=False)
    m2, _ = fit_emulator(plain, sim.response_names, train, y_train, ("linear", "reduced")).predict(test)
    rms = lambda m: float(np.sqrt(np.mean((m[:, 2:] - np.log(y[:, 2:])) ** 2)))  # noqa: E731
    assert rms(mu) < 0.75 * rms(m2)


def test_sensitivities_of_a_linear_parameter_are_elasticities_too(study):
    """theta of a bias is b itself, so the sensitivity table scales its column by b: d ln FX / d ln b =
    b / FX exactly (FX = FX_tire + b), like every log-space parameter's column."""
    from jtire.calibration.tire.sensitivity import compute

    sim = StandinSimulator(study.space, study.base_params, study.targets)
    th = study.space.default.copy()
    j = study.space.names.index("bias.non_tire_drag")
    th[j] = 750.0
    sens = compute(sim, th)
    fx = sim.evaluate(th[None])[0]
    np.testing.assert_allclose(sens.elasticity[2:, j], 750.0 / fx[2:], rtol=1e-12)
    assert np.all(sens.elasticity[:2, j] == 0.0)
