"""Static solves side by side: the shell simulator's static targets, one device each, and a
static experiment's cases over several conditions, one per device at a time.

With several devices, `ShellSimulator.evaluate` runs its static experiments (E02, E09: Newton
solves, case by case) at the same time, each on its own device, before the transients take every
device. The numbers must not depend on it: the same arithmetic on another device of the same CPU
gives the same bits, so the tolerance is 1e-12 relative (no physics is involved, only scheduling).
Slow: three static programs compile on the coarse ring (75 s here).
"""

import dataclasses

import jax
import numpy as np
import pytest

from .conftest import COARSE_SET, REPO


@pytest.mark.slow
@pytest.mark.skipif(len(jax.devices()) < 2, reason="needs two JAX devices (one per core: 2 cores)")
def test_static_targets_side_by_side_equal_one_after_another():
    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration

    spec = load_calibration(REPO / "configs" / "calibration" / "study.toml", COARSE_SET)
    spec = dataclasses.replace(spec, targets=tuple(t for t in spec.targets if t.name in ("DZ", "DY")))
    theta = np.asarray(spec.space.from_params(spec.base_params))
    side = ShellSimulator(spec, spec.tire)
    assert [g["exp"].shardable for g in side.groups] == [False, False]
    y_side = side.evaluate(theta[None])
    y_one = ShellSimulator(spec, spec.tire, devices=1).evaluate(theta[None])
    assert np.all(np.isfinite(y_side)) and 0.02 < y_side[0, 0] < 0.06 and 0.003 < y_side[0, 1] < 0.02
    np.testing.assert_allclose(y_side, y_one, rtol=1e-12)


@pytest.mark.slow
@pytest.mark.skipif(len(jax.devices()) < 2, reason="needs two JAX devices (one per core: 2 cores)")
def test_static_cases_side_by_side_equal_one_device(coarse_tire, protocol, spec):
    """`batch.run` of a static experiment over three conditions: its cases run side by side on the
    devices (device=None) and give the results of the same cases on one device, in the same order.
    Slow: the static program compiles for both devices (65 s here beside another run)."""
    from jtire import batch

    from .conftest import LOAD_RATED, P_RATED, make_experiment

    exp = make_experiment("vertical_stiffness", protocol, spec)
    assert not exp.shardable
    conds = [{"load_N": f * LOAD_RATED, "pressure_Pa": P_RATED} for f in (0.6, 1.0, 0.8)]
    seen = []
    side = batch.run(exp, coarse_tire, conds, on_result=lambda i, r: seen.append(i))
    one = batch.run(exp, coarse_tire, conds, device=0)
    assert sorted(seen) == [0, 1, 2]
    for a, b in zip(side, one):
        assert not isinstance(a, batch.CaseFailure), a
        assert not isinstance(b, batch.CaseFailure), b
        for k, v in b.quantities.items():
            if isinstance(v, float):
                assert a.quantities[k] == pytest.approx(v, rel=1e-12, abs=1e-15), k
    k_sv = [r.quantities["k_sv_N_per_m"] for r in side]
    assert np.all(np.isfinite(k_sv)) and len(set(k_sv)) == 3  # three loads, three secants
