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


@pytest.mark.skipif(len(jax.devices()) < 2, reason="needs two JAX devices (one per core: 2 cores)")
def test_side_by_side_runs_one_job_per_device_in_order():
    """`batch.side_by_side` (the default runner's scheduler): never two jobs on one device at once,
    both devices used, every job run once and its result handed on in the calling thread, and a job's
    error raised there with the jobs not yet started left unrun."""
    import threading
    import time

    from jtire import batch

    lock, busy, started, seen = threading.Lock(), set(), [], []

    def job(k):
        def run(d):
            with lock:
                assert d not in busy  # one job per device at a time
                busy.add(d)
                started.append((k, d))
            time.sleep(0.02 * (1 + k % 3))
            with lock:
                busy.discard(d)
            return k * k
        return run

    caller = threading.current_thread()
    batch.side_by_side([job(k) for k in range(7)],
                       lambda k, v: seen.append((k, v, threading.current_thread() is caller)))
    assert sorted(k for k, _ in started) == list(range(7)) and {d for _, d in started} == {0, 1}
    assert sorted(seen) == [(k, k * k, True) for k in range(7)]

    def bad(d):
        raise RuntimeError("case 2 went unstable")
    ran = []
    with pytest.raises(RuntimeError, match="case 2 went unstable"):
        batch.side_by_side([lambda d: time.sleep(0.05), bad] + [lambda d, k=k: ran.append(k) or time.sleep(0.2)
                                                                 for k in range(6)], lambda k, v: None)
    assert len(ran) < 6  # the jobs after the error were cancelled, not all run
