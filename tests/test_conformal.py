"""The check's variance correction (calibration.posterior.conformal) and what its coverage can tell: the
k-fold correction restores the stated coverage, the floor and the factor behave as designed, split
conformal keeps its guarantee with 32 runs, band_chance and the exact coverage interval match the
procedure and the closed forms."""

import numpy as np

from jtire.calibration.posterior.emulator import fit_emulator
from jtire.calibration.tire.space import ParamSpace

D = 3


def _space(half=1.0):
    z = np.zeros(D)
    return ParamSpace(tuple(f"p{i}" for i in range(D)), ("loss",) * D, tuple(range(D)),
                      z - half, z + half, z)


def test_variance_calibration_gives_the_stated_coverage():
    """400 training runs with ln-noise sd 0.01 and 100 posterior-region runs with sd 0.04: an
    emulator fit to both (residual sd ~0.02) is overconfident where the posterior lives. The
    k-fold factor over the 100 runs must bring the coverage of 2000 fresh ones to 90 %
    (tolerance 8 %: the 90 % quantile of 100 |z| has a sampling sd that moves the coverage by
    ~3 %, the 2000 fresh draws a binomial 0.7 %: ~2.5 sd)."""
    from types import SimpleNamespace

    from jtire.calibration.posterior.report import coverage
    from jtire.calibration.posterior.conformal import calibrate_variance

    rng = np.random.default_rng(3)
    space = _space(1.0)
    names = ("a", "b")
    w = np.array([[0.5, -0.2, 0.3], [0.1, 0.4, -0.6]])

    def runs(n, sd, lo, hi):
        th = rng.uniform(lo, hi, (n, D))
        return th, np.exp(th @ w.T + 1.0 + sd * rng.standard_normal((n, 2)))

    spec = SimpleNamespace(calibration=SimpleNamespace(space=space, targets=[SimpleNamespace(name=n) for n in names]),
                           check={"seed": 0, "folds": 4}, candidates=("linear",), emulator_seed=0)
    th, y = runs(400, 0.01, -1, 1)
    ex_t, ex_y = runs(100, 0.04, 0.2, 0.6)
    fresh_t, fresh_y = runs(2000, 0.04, 0.2, 0.6)
    emu = fit_emulator(space, names, np.vstack([th, ex_t]), np.vstack([y, ex_y]), ("linear",))
    for form in ("scale", "floor", "wider"):
        a, b, z = calibrate_variance(spec, th, y, ex_t, ex_y, form=form)
        # the uncalibrated intervals were too narrow: a factor > 2, and/or a floor sd of at least 0.02
        assert np.all(a > 2.0) if form != "floor" else np.all(a == 1.0), (form, a)
        assert np.all(b == 0) if form == "scale" else np.all(b > 0.02**2), (form, b)
        emu.var_scale, emu.var_floor = a, b
        cov = coverage(emu, fresh_t, fresh_y)["coverage"]
        for name in names:
            assert abs(cov[name] - 0.9) < 0.08, (form, cov)


def test_conformal_floor_holds_where_the_emulator_variance_shrinks():
    """Held-out runs with emulator variance v ~ U(0.5, 2) and true residual variance v + 1; new runs
    where more training has cut the emulator's variance to 0.1 (their residual variance 1.1, the
    floor's part unchanged). The new runs are not exchangeable with the held-out ones, so no exact
    guarantee: over 3000 replications of 32 held-out runs the floor keeps the new runs' mean coverage
    within 0.02 of 0.9 (measured 0.889: the floor, estimated from 32 runs, is nearly all of the new
    runs' interval, and coverage is concave in it), while the factor, which shrinks with v, falls
    below 0.80. The replication means have sd ~0.002."""
    from scipy import stats

    from jtire.calibration.posterior.conformal import conformal_floor, conformal_scale

    rng = np.random.default_rng(5)
    zq = stats.norm.ppf(0.95)
    hit_floor, hit_scale = [], []
    for _ in range(3000):
        v = rng.uniform(0.5, 2.0, 32)
        r = np.sqrt(v + 1.0) * rng.standard_normal(32)
        b, a = conformal_floor(r, v), conformal_scale(r / np.sqrt(v))
        new = np.sqrt(1.1) * rng.standard_normal(50)
        hit_floor.append(np.mean(np.abs(new) <= zq * np.sqrt(0.1 + b)))
        hit_scale.append(np.mean(np.abs(new) <= zq * np.sqrt(0.1 * a)))
    assert abs(np.mean(hit_floor) - 0.9) < 0.02, np.mean(hit_floor)
    assert np.mean(hit_scale) < 0.80, np.mean(hit_scale)
    # the floor is the conformal one: the 30th smallest of 32 scores sits on the interval's edge
    v = rng.uniform(0.5, 2.0, 32)
    r = 3.0 * rng.standard_normal(32)
    b = conformal_floor(r, v)
    assert np.isclose(np.sort(np.abs(r) / np.sqrt(v + b))[29], zq, rtol=1e-9)
    assert conformal_floor(0.1 * r, v) == 0.0  # already inside: no floor
    assert conformal_floor([np.nan, 0.3], [1.0, 1.0]) == 0.0  # one finite run says nothing


def test_calibrated_variance_is_the_wider_of_factor_and_floor():
    """Emulator.predict with var_scale a and var_floor b: max(a v, v + b) where b > 0, a v where
    b = 0 (a narrowing factor); the one-line text says which."""
    space = _space(1.0)
    th = np.zeros((1, D))
    e = fit_emulator(space, ("a", "b"), np.random.default_rng(0).uniform(-1, 1, (40, D)),
                     np.exp(np.random.default_rng(1).normal(size=(40, 2))), ("linear",))
    v = e.predict(th)[1][0]
    e.var_scale, e.var_floor = np.array([3.0, 0.5]), np.array([10 * v[0], 0.0])
    np.testing.assert_allclose(e.predict(th)[1][0], [v[0] + 10 * v[0], 0.5 * v[1]])
    e.var_floor = np.array([0.1 * v[0], 0.0])
    np.testing.assert_allclose(e.predict(th)[1][0], [3.0 * v[0], 0.5 * v[1]])
    assert "the wider of x 3" in e.calibration_text() and "b x 0.5" in e.calibration_text()


def test_conformal_scale_keeps_its_coverage_with_few_runs():
    """With 32 held-out scores the split-conformal factor puts a new run inside the rescaled 90 %
    interval with probability 30/33 = 0.909 on average (the plain 90 % quantile: ~0.89). Over 4000
    replications of scores with sd 1.7 (an emulator 1.7x overconfident): mean coverage 0.909 +- 0.005
    (binomial-mixture sd ~0.002; tolerance 2.5 sd), and it is the 30th smallest |z|."""
    from scipy import stats

    from jtire.calibration.posterior.conformal import conformal_scale

    rng = np.random.default_rng(11)
    zq = stats.norm.ppf(0.95)
    hits = []
    for _ in range(4000):
        cal, new = 1.7 * rng.standard_normal(32), 1.7 * rng.standard_normal(50)
        q = zq * np.sqrt(conformal_scale(cal))
        hits.append(np.mean(np.abs(new) <= q))
    assert abs(np.mean(hits) - 30 / 33) < 0.005, np.mean(hits)
    z = rng.standard_normal(32)
    assert np.isclose(conformal_scale(z), (np.sort(np.abs(z))[29] / zq) ** 2)
    assert conformal_scale([np.nan, 0.3]) == 1.0  # one finite score says nothing
    assert np.isclose(conformal_scale(np.arange(1.0, 6.0)), (5.0 / zq) ** 2)  # 5 runs: the largest


def test_band_chance_is_what_split_conformal_gives():
    """`band_chance` (beta-binomial, closed form) against the procedure itself: 20000 replications
    of 32 held-out scores -> `conformal_scale` -> the count of 32 fresh runs inside the rescaled 90 %
    interval. The fraction of replications with 26-31 inside (80-97 %) matches within 4 Monte-Carlo
    sd (sd 0.0028, tolerance 0.011). A wrong k (the plain 90 % quantile, the 29th of 32) would give
    0.792 against 0.807: outside that tolerance."""
    from scipy import stats

    from jtire.calibration.posterior.conformal import COVERAGE_OK, band_chance, conformal_scale

    rng = np.random.default_rng(12)
    zq = stats.norm.ppf(0.95)
    reps = 20000
    cal, new = 2.0 * rng.standard_normal((reps, 32)), 2.0 * rng.standard_normal((reps, 32))
    q = zq * np.sqrt([conformal_scale(c) for c in cal])
    ins = np.sum(np.abs(new) <= q[:, None], axis=1)
    p_sim = np.mean((ins >= 26) & (ins <= 31))
    p = band_chance(32, 32)
    assert abs(p_sim - p) < 4 * np.sqrt(p * (1 - p) / reps), (p_sim, p)
    assert 0.78 < p < 0.84  # the figure the docstring and the CLI quote
    # more held-out runs make the correction's own scatter smaller: the chance rises towards the
    # binomial chance of an exact 90 % interval
    exact = stats.binom.pmf(np.arange(26, 32), 32, 0.9).sum()
    assert band_chance(32, 32) < band_chance(64, 32) < band_chance(1000, 32) < exact + 1e-3
    assert abs(band_chance(20000, 32) - exact) < 0.01
    assert COVERAGE_OK == (0.80, 0.97)


def test_coverage_interval_is_the_exact_binomial_one():
    """Clopper-Pearson closed forms: all n inside -> lower bound 0.05^(1/n); none -> upper
    1 - 0.05^(1/n); the interval holds k/n."""
    from jtire.calibration.posterior.report import coverage_interval

    assert np.allclose(coverage_interval(32, 32), [0.05 ** (1 / 32), 1.0])
    assert np.allclose(coverage_interval(0, 32), [0.0, 1 - 0.05 ** (1 / 32)])
    for k in (5, 26, 29, 31):
        lo, hi = coverage_interval(k, 32)
        assert lo < k / 32 < hi
    assert np.all(np.isnan(coverage_interval(0, 0)))
