"""The posterior of the calibration's free parameters: emcee on an emulator of the targets.

Model, in theta = ln(parameter) (the calibration's ParamSpace):

    prior:       "log_uniform": uniform in theta on the calibration's bounds (the default: the
                 tire's values are published-range defaults, not measurements, and the bounds are
                 those ranges, so nothing inside them is preferred; the posterior then shows
                 plainly which directions the four targets leave unconstrained), or
                 "log_normal": N(theta_tire, sigma_ln^2) truncated to the bounds (a belief that
                 the defaults are typical; it regularizes the unidentified directions).
    likelihood:  ln t_i ~ N(mu_i(theta), sigma_i^2 + v_i(theta)) for every target i, with mu_i,
                 v_i the emulator's mean and predictive variance of ln(response) and sigma_i the
                 target's relative measurement uncertainty (the config says where it comes from).

The log-probability is vectorized over walkers (emcee's vectorize=True): one emulator call per
step for the whole ensemble.

Chains are stored in emcee's HDF5 backend (chain.h5), seeded; the run proceeds in chunks of
`check_every` steps aligned to multiples of check_every, and after each chunk estimates the
integrated autocorrelation time tau; it stops when the chain is longer than n_tau x max(tau) (and
tau is finite), or at max_steps, and then says it did not converge. A killed run resumes from the
backend (emcee stores the last state and its random state with every step), and reaches the same
final state as an uninterrupted run with the same seed (tested).
"""

import dataclasses
from pathlib import Path

import numpy as np
from scipy import stats

from ..errors import ConfigError

__all__ = ["LogPosterior", "SamplerResult", "run_sampler", "diagnostics", "prior_interval"]


class LogPosterior:
    """Vectorized log-probability: thetas (n, d) -> (n,).

    emulator: anything with predict(thetas) -> (mean (n, m), var (n, m)) of ln(response);
    log_targets: (m,) ln measured values; sigma_rel: (m,) relative measurement sd;
    space: the ParamSpace (bounds, defaults); prior: "log_uniform" or "log_normal".
    """

    def __init__(self, emulator, log_targets, sigma_rel, space, prior="log_uniform", sigma_ln=0.5):
        self.emulator, self.space = emulator, space
        self.lt = np.asarray(log_targets, float)
        self.s2 = np.asarray(sigma_rel, float) ** 2
        self.prior, self.sigma_ln = prior, float(sigma_ln)

    def log_prior(self, thetas):
        thetas = np.atleast_2d(thetas)
        inside = np.all((thetas >= self.space.lower) & (thetas <= self.space.upper), axis=1)
        lp = np.zeros(thetas.shape[0])
        if self.prior == "log_normal":
            lp = -0.5 * np.sum(((thetas - self.space.default) / self.sigma_ln) ** 2, axis=1)
        return np.where(inside, lp, -np.inf)

    def __call__(self, thetas):
        thetas = np.atleast_2d(np.asarray(thetas, float))
        lp = self.log_prior(thetas)
        out = np.full(thetas.shape[0], -np.inf)
        ok = np.isfinite(lp)
        if ok.any():
            mu, var = self.emulator.predict(thetas[ok])
            v = self.s2 + np.maximum(var, 0.0)
            ll = -0.5 * np.sum((self.lt - mu) ** 2 / v + np.log(2 * np.pi * v), axis=1)
            out[ok] = lp[ok] + np.where(np.isfinite(ll), ll, -np.inf)
        return out


@dataclasses.dataclass(frozen=True)
class SamplerResult:
    """chain: (steps, walkers, d); log_prob: (steps, walkers); tau: (d,) at the end (nan if
    not estimable); converged: steps > n_tau * max(tau); acceptance: (walkers,); steps;
    n_new_steps: steps run by this call (the rest were on disk)."""

    chain: np.ndarray
    log_prob: np.ndarray
    tau: np.ndarray
    converged: bool
    acceptance: np.ndarray
    steps: int
    n_new_steps: int
    n_tau: float

    def samples(self, discard=None, thin=None) -> np.ndarray:
        """Flat (k, d) samples after a burn-in of 2 max(tau) and thinning by min(tau) / 2."""
        tau = self.tau if np.all(np.isfinite(self.tau)) else np.full_like(self.tau, self.steps / 50)
        discard = int(2 * np.max(tau)) if discard is None else int(discard)
        thin = max(1, int(0.5 * np.min(tau))) if thin is None else int(thin)
        discard = min(discard, self.steps - 1)
        return self.chain[discard::thin].reshape(-1, self.chain.shape[-1])


def _tau(chain):
    import emcee

    return emcee.autocorr.integrated_time(chain, tol=0, quiet=True)


def run_sampler(log_prob, p0, path, walkers: int, max_steps: int, check_every: int = 500,
                n_tau: float = 50.0, seed: int = 0, progress=None) -> SamplerResult:
    """Run (or resume) an emcee EnsembleSampler stored in the HDF5 file `path`.

    log_prob: vectorized, thetas (walkers, d) -> (walkers,); p0: (walkers, d) start (used only
    for a new chain). Steps run in chunks ending on multiples of check_every, so a resumed run
    checks convergence at the same steps as an uninterrupted one.
    progress: optional callable(steps, tau) after each chunk.
    """
    import emcee

    p0 = np.asarray(p0, float)
    d = p0.shape[1]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    backend = emcee.backends.HDFBackend(str(path))
    fresh = not path.exists() or backend.iteration == 0
    if fresh:
        backend.reset(walkers, d)
    elif backend.shape != (walkers, d):
        raise ConfigError(f"chain {path}: holds {backend.shape[0]} walkers x {backend.shape[1]} "
                          f"parameters, not {walkers} x {d}; use another --out folder")
    sampler = emcee.EnsembleSampler(walkers, d, log_prob, vectorize=True, backend=backend)
    state = None
    if fresh:
        sampler.random_state = np.random.RandomState(int(seed)).get_state()
        state = p0
        lp0 = log_prob(p0)
        if not np.all(np.isfinite(lp0)):
            raise ConfigError(f"sampler start: {int(np.sum(~np.isfinite(lp0)))} walkers start "
                              "where the posterior is zero (outside the bounds?)")
    start = backend.iteration
    tau = np.full(d, np.nan)
    converged = False
    it = start
    if it >= check_every and it % check_every == 0:  # resumed exactly on a check: redo it
        tau = _tau(backend.get_chain())
        converged = bool(np.all(np.isfinite(tau)) and it > n_tau * np.max(tau))
    while it < max_steps and not converged:
        n = min(check_every - it % check_every, max_steps - it)
        sampler.run_mcmc(state, n, progress=False)
        state = None
        it = backend.iteration
        tau = _tau(backend.get_chain())
        converged = bool(np.all(np.isfinite(tau)) and it > n_tau * np.max(tau))
        if progress is not None:
            progress(it, tau)
    chain = backend.get_chain()
    if not np.all(np.isfinite(tau)) and chain.shape[0] > 0:
        tau = _tau(chain)
    acc = backend.accepted / max(backend.iteration, 1)
    return SamplerResult(chain, backend.get_log_prob(), tau, converged, acc, int(backend.iteration),
                         int(backend.iteration - start), float(n_tau))


def diagnostics(res: SamplerResult) -> dict:
    """Acceptance, tau, and arviz's R-hat and bulk ESS over the walkers (after burn-in).

    Note: the walkers of an ensemble sampler are not independent chains (each move uses the
    others), so R-hat across walkers is a rough check, not the textbook test.
    """
    import arviz as az

    tau = res.tau if np.all(np.isfinite(res.tau)) else np.full_like(res.tau, res.steps / 50)
    discard = min(int(2 * np.max(tau)), res.steps - 2)
    post = np.swapaxes(res.chain[discard:], 0, 1)  # (chains = walkers, draws, d)
    ds = az.convert_to_dataset(post)  # variable "x", dims (chain, draw, x_dim_0)
    rhat = np.asarray(az.rhat(ds)["x"].values, float).reshape(-1)
    ess = np.asarray(az.ess(ds, method="bulk")["x"].values, float).reshape(-1)
    return {"acceptance_mean": float(np.mean(res.acceptance)),
            "acceptance_min": float(np.min(res.acceptance)), "tau": res.tau, "steps": res.steps,
            "n_tau_required": res.n_tau, "converged": res.converged, "burn_in": discard,
            "rhat": rhat, "ess_bulk": ess}


def prior_interval(space, prior: str, sigma_ln: float, level: float = 0.9) -> np.ndarray:
    """(d, 2) central `level` interval of each theta under the prior."""
    a = 0.5 * (1 - level)
    if prior == "log_uniform":
        return np.stack([space.lower + a * space.width, space.upper - a * space.width], axis=1)
    lo = (space.lower - space.default) / sigma_ln
    hi = (space.upper - space.default) / sigma_ln
    tn = stats.truncnorm(lo, hi, loc=space.default, scale=sigma_ln)
    return np.stack([tn.ppf(a), tn.ppf(1 - a)], axis=1)
