"""The posterior machinery: emcee recovers a known linear-Gaussian posterior, a killed chain
resumes to the same final state, a short chain says it did not converge, the emulator picks by
leave-one-out, and the simulator check measures coverage."""

import numpy as np
import pytest

from jtire.calibration.posterior.emulator import fit_emulator
from jtire.calibration.posterior.model import LogPosterior, diagnostics, run_sampler
from jtire.calibration.posterior.report import simulator_check
from jtire.calibration.tire.space import ParamSpace

D, M = 3, 4
RNG = np.random.default_rng(7)
A = RNG.normal(size=(M, D))  # d ln(response) / d theta
B = RNG.normal(size=M)


def _space(half=20.0):
    z = np.zeros(D)
    return ParamSpace(tuple(f"p{i}" for i in range(D)), ("loss",) * D, tuple(range(D)),
                      z - half, z + half, z)


class _Linear:
    """Exact linear emulator of ln(response) with a given constant predictive variance."""

    names = tuple(f"y{i}" for i in range(M))

    def __init__(self, var=0.0):
        self.var = var

    def predict(self, thetas):
        mu = np.atleast_2d(thetas) @ A.T + B
        return mu, np.full_like(mu, self.var)


def _exact(lt, s, sigma_ln):
    """Posterior of theta ~ N(0, sigma_ln^2 I), lt ~ N(A theta + B, diag s^2): mean, covariance."""
    prec = np.eye(D) / sigma_ln**2 + A.T @ np.diag(1 / s**2) @ A
    cov = np.linalg.inv(prec)
    return cov @ (A.T @ ((lt - B) / s**2)), cov


def test_sampler_recovers_a_linear_gaussian_posterior(tmp_path):
    s = np.array([0.3, 0.5, 0.4, 0.6])
    theta_true = np.array([0.4, -0.3, 0.2])
    lt = A @ theta_true + B
    sigma_ln = 1.0
    space = _space()  # bounds +-20 sd: truncation is nil
    lp = LogPosterior(_Linear(), lt, s, space, "log_normal", sigma_ln)
    mean, cov = _exact(lt, s, sigma_ln)
    p0 = mean + 1e-3 * np.random.default_rng(0).normal(size=(32, D))
    # 100 tau (not the default 50) so that the bulk ESS is ~3000 and the tolerances below are
    # several Monte Carlo standard errors wide
    res = run_sampler(lp, p0, tmp_path / "c.h5", 32, 12000, 500, 100.0, seed=3)
    assert res.converged
    x = res.samples()
    sd = np.sqrt(np.diag(cov))
    diag = diagnostics(res)
    assert np.min(diag["ess_bulk"]) > 2000
    # mean: standard error sd / sqrt(ESS) < 0.022 sd, tolerance 0.1 sd (> 4.5 standard errors)
    np.testing.assert_allclose(x.mean(axis=0), mean, atol=0.1 * sd.min())
    # variances: relative standard error sqrt(2 / ESS) < 3.2 %, tolerance 12 %; correlations
    # (standard error < (1 - rho^2) / sqrt(ESS) < 0.023) to 0.08
    c = np.cov(x.T)
    np.testing.assert_allclose(np.diag(c), np.diag(cov), rtol=0.12)
    corr = lambda k: k / np.sqrt(np.outer(np.diag(k), np.diag(k)))  # noqa: E731
    np.testing.assert_allclose(corr(c), corr(cov), atol=0.08)
    assert 0.2 < diag["acceptance_mean"] < 0.9  # the stretch move's healthy range
    assert np.max(diag["rhat"]) < 1.05


def test_emulator_variance_widens_the_posterior(tmp_path):
    """The emulator's predictive variance adds to the measurement variance (exact here)."""
    s = np.full(M, 0.3)
    lt = B.copy()
    lp1 = LogPosterior(_Linear(0.0), lt, s, _space(), "log_normal", 1.0)
    lp2 = LogPosterior(_Linear(0.4**2), lt, np.full(M, np.sqrt(0.3**2 - 0.0)), _space(), "log_normal", 1.0)
    th = np.array([[0.1, 0.2, -0.1]])
    lp_direct = LogPosterior(_Linear(0.0), lt, np.full(M, 0.5), _space(), "log_normal", 1.0)
    assert lp2(th)[0] == pytest.approx(lp_direct(th)[0], rel=1e-12)  # 0.3^2 + 0.4^2 = 0.5^2
    assert lp1(th)[0] != pytest.approx(lp2(th)[0])
    assert lp1(np.array([[25.0, 0, 0]]))[0] == -np.inf  # outside the bounds


def _chain(tmp_path, name, max_steps, log_prob=None, seed=11):
    lt = A @ np.array([0.2, 0.1, -0.2]) + B
    lp = log_prob or LogPosterior(_Linear(), lt, np.full(M, 0.4), _space(), "log_normal", 1.0)
    p0 = 0.01 * np.random.default_rng(1).normal(size=(16, D))
    return run_sampler(lp, p0, tmp_path / name, 16, max_steps, 100, 50.0, seed=seed)


class _Killed(Exception):
    pass


def test_killed_chain_resumes_to_the_same_state(tmp_path):
    whole = _chain(tmp_path, "a.h5", 700)
    lt = A @ np.array([0.2, 0.1, -0.2]) + B
    inner = LogPosterior(_Linear(), lt, np.full(M, 0.4), _space(), "log_normal", 1.0)
    calls = {"n": 0}

    def dies(th):
        calls["n"] += 1
        if calls["n"] > 250:  # mid-chunk: not on a multiple of check_every
            raise _Killed
        return inner(th)

    with pytest.raises(_Killed):
        _chain(tmp_path, "b.h5", 700, dies)
    resumed = _chain(tmp_path, "b.h5", 700)
    assert 0 < resumed.steps - resumed.n_new_steps < 700  # it did resume, not restart
    assert resumed.steps == whole.steps and resumed.converged == whole.converged
    np.testing.assert_array_equal(resumed.chain, whole.chain)
    np.testing.assert_array_equal(resumed.log_prob, whole.log_prob)


def test_short_chain_is_not_converged(tmp_path):
    res = _chain(tmp_path, "c.h5", 100)
    assert not res.converged and res.steps == 100
    assert diagnostics(res)["converged"] is False


def test_emulator_chooses_by_leave_one_out():
    space = _space(1.0)
    rng = np.random.default_rng(0)
    th = rng.uniform(-1, 1, size=(40, D))
    u = space.to_unit(th)
    y = np.exp(np.stack([1 + u @ A[0], 1 + u @ A[1] + 2.0 * u[:, 0] ** 2], axis=1))
    emu = fit_emulator(space, ("lin", "quad"), th, y, ("linear", "reduced", "full"))
    # a plane is fitted exactly by every kind: any choice has LOO ~ 0; the curved one needs squares
    assert emu.loo["lin"][emu.kinds[0]] < 1e-10
    assert emu.kinds[1] in ("reduced", "full") and emu.loo["quad"]["linear"] > 1e-2
    assert emu.loo["quad"][emu.kinds[1]] < 1e-10
    mu, var = emu.predict(th[:5])
    np.testing.assert_allclose(mu, np.log(y[:5]), atol=1e-8)


def test_simulator_check_measures_coverage():
    """A 'simulator' whose ln(response) is the emulator mean plus N(0, v) noise: the emulator's
    90 % intervals should cover 90 % of 400 draws (binomial sd 1.5 %; tolerance 5 %)."""
    v = 0.2**2

    class _Noisy:
        response_names = _Linear.names

        def __init__(self):
            self.rng = np.random.default_rng(5)
            self.batches = []

        def evaluate(self, thetas):
            self.batches.append(len(thetas))
            mu, _ = _Linear().predict(thetas)
            return np.exp(mu + np.sqrt(v) * self.rng.standard_normal(mu.shape))

    sim = _Noisy()
    samples = np.random.default_rng(2).normal(size=(1000, D))
    chk = simulator_check(sim, _Linear(v), samples, n_draws=400, seed=0)
    assert sim.batches == [400]  # one batch
    for cov in chk["coverage"].values():
        assert abs(cov - 0.9) < 0.05
    too_sure = simulator_check(_Noisy(), _Linear(v / 100), samples, n_draws=400, seed=0)
    assert max(too_sure["coverage"].values()) < 0.3  # an overconfident emulator is caught


def test_unbounded_coordinates_keep_the_posterior():
    """In z = logit(u) a flat density on the box must come back flat: the Jacobian u (1 - u) is
    what makes the z-chain's theta uniform. DE moves, 32 walkers, 6000 steps (tau ~20: ESS ~9000);
    mean to 0.03 width (> 10 standard errors of 0.003), variance width^2/12 to 10 %."""
    import emcee

    from jtire.calibration.posterior.model import UnboundedPosterior

    space = _space(1.0)

    def flat(th):
        th = np.atleast_2d(th)
        inside = np.all((th >= space.lower) & (th <= space.upper), axis=1)
        return np.where(inside, 0.0, -np.inf)

    post = UnboundedPosterior(flat, space)
    th0 = np.random.default_rng(0).uniform(-0.01, 0.01, (32, D))
    np.testing.assert_allclose(post.to_theta(post.to_z(th0)), th0, atol=1e-12)
    s = emcee.EnsembleSampler(32, D, post, vectorize=True,
                              moves=[(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)])
    s.random_state = np.random.RandomState(1).get_state()
    s.run_mcmc(post.to_z(th0), 6000, progress=False)
    th = post.to_theta(s.get_chain(discard=500, flat=True))
    np.testing.assert_allclose(th.mean(axis=0), 0.0, atol=0.03 * 2.0)
    np.testing.assert_allclose(th.var(axis=0), 2.0**2 / 12, rtol=0.10)


def test_de_moves_in_logit_coordinates_recover_the_linear_gaussian(tmp_path):
    """The jtire sample default (DE moves, logit coordinates) on the known posterior of the first
    test, with bounds at +-4 prior sd (truncation changes the moments by < 0.1 %)."""
    from jtire.calibration.posterior.model import UnboundedPosterior

    s = np.array([0.3, 0.5, 0.4, 0.6])
    lt = A @ np.array([0.4, -0.3, 0.2]) + B
    space = _space(4.0)
    post = UnboundedPosterior(LogPosterior(_Linear(), lt, s, space, "log_normal", 1.0), space)
    mean, cov = _exact(lt, s, 1.0)
    p0 = post.to_z(mean + 1e-3 * np.random.default_rng(0).normal(size=(32, D)))
    res = run_sampler(post, p0, tmp_path / "c.h5", 32, 12000, 500, 100.0, seed=3, moves="de")
    assert res.converged
    x = post.to_theta(res.samples())
    sd = np.sqrt(np.diag(cov))
    np.testing.assert_allclose(x.mean(axis=0), mean, atol=0.1 * sd.min())  # as the first test
    np.testing.assert_allclose(np.diag(np.cov(x.T)), np.diag(cov), rtol=0.12)


def test_killed_de_chain_resumes_to_the_same_state(tmp_path):
    """DE moves draw from the sampler's random state too: a killed run still resumes exactly."""
    lt = A @ np.array([0.2, 0.1, -0.2]) + B
    inner = LogPosterior(_Linear(), lt, np.full(M, 0.4), _space(), "log_normal", 1.0)
    p0 = 0.01 * np.random.default_rng(1).normal(size=(16, D))
    whole = run_sampler(inner, p0, tmp_path / "a.h5", 16, 700, 100, 50.0, seed=11, moves="de")
    calls = {"n": 0}

    def dies(th):
        calls["n"] += 1
        if calls["n"] > 250:
            raise _Killed
        return inner(th)

    with pytest.raises(_Killed):
        run_sampler(dies, p0, tmp_path / "b.h5", 16, 700, 100, 50.0, seed=11, moves="de")
    resumed = run_sampler(inner, p0, tmp_path / "b.h5", 16, 700, 100, 50.0, seed=11, moves="de")
    assert 0 < resumed.steps - resumed.n_new_steps < 700
    np.testing.assert_array_equal(resumed.chain, whole.chain)


def test_discrepancy_is_the_smallest_miss():
    from types import SimpleNamespace

    from jtire.calibration.posterior.run import discrepancy_sd

    targets = [SimpleNamespace(measured=2.0), SimpleNamespace(measured=10.0)]
    y = np.array([[2.2, 5.0], [1.9, 4.0], [np.nan, 30.0]])
    np.testing.assert_allclose(discrepancy_sd("best_miss", targets, y),
                               [abs(np.log(1.9 / 2.0)), abs(np.log(5.0 / 10.0))])
    np.testing.assert_array_equal(discrepancy_sd("none", targets, y), [0.0, 0.0])


def test_killed_check_resumes_without_rerunning_its_draws(tmp_path):
    """The simulator check in pieces of points_per_call, each row appended as it returns: a check
    killed after 3 pieces (and torn mid-line) keeps those 6 draws; the rerun simulates only the
    other 4 and gives the same responses as an uninterrupted check."""
    from jtire.calibration.posterior.run import simulate_draws

    class _Killed(Exception):
        pass

    class _Exact:
        response_names = _Linear.names
        points_per_call = 2

        def __init__(self, die_after=None):
            self.die_after, self.batches = die_after, []

        def evaluate(self, thetas):
            if self.die_after is not None and len(self.batches) >= self.die_after:
                raise _Killed
            self.batches.append(len(thetas))
            return np.exp(_Linear().predict(thetas)[0])

    draws = np.random.default_rng(3).normal(size=(10, D))
    whole, reused = simulate_draws(_Exact(), draws, tmp_path / "a.jsonl")
    assert reused == 0
    np.testing.assert_array_equal(whole, np.exp(_Linear().predict(draws)[0]))
    dies = _Exact(die_after=3)
    with pytest.raises(_Killed):
        simulate_draws(dies, draws, tmp_path / "b.jsonl")
    path = tmp_path / "b.jsonl"
    assert dies.batches == [2, 2, 2] and len(path.read_text().splitlines()) == 6
    path.write_text(path.read_text() + '{"i": 6, "theta": [0.1')  # torn by the kill
    fresh, seen = _Exact(), []
    again, reused = simulate_draws(fresh, draws, path, on_check=lambda d, n, r: seen.append((d, n, r)))
    assert reused == 6 and fresh.batches == [2, 2]
    np.testing.assert_array_equal(again, whole)
    assert seen == [(6, 10, 6), (8, 10, 6), (10, 10, 6)]
    # other draws (another chain) reuse nothing from the file
    _, reused = simulate_draws(_Exact(), draws + 1.0, path)
    assert reused == 0
