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
                 target's relative measurement uncertainty (the config says where it comes from),
                 combined with a model-discrepancy sd where the config asks for one
                 (sigma_i^2 = measurement^2 + discrepancy^2; calibration/posterior/run.py says how
                 it is set).

The log-probability is vectorized over walkers (emcee's vectorize=True): one emulator call per
step for the whole ensemble.

Where the walkers move: a uniform prior on a box puts hard walls in every direction the four
targets leave free, and emcee's stretch move, proposing along lines through other walkers, is
mostly thrown out at those walls (low acceptance, a long autocorrelation time). The chain therefore
runs in unbounded coordinates z = logit(u), u = (theta - lower) / width (the bounds map to +-infinity;
the density carries the Jacobian u (1 - u), so the posterior in theta is unchanged:
`UnboundedPosterior`), with emcee's differential-evolution moves (80 % DEMove, 20 % DESnookerMove,
emcee's documented mix for many dimensions), which mix far better there (docs/design-notes.md).

Chains are seeded and stored in chain.h5 (emcee's HDF5 layout); the run proceeds in chunks of
`check_every` steps aligned to multiples of check_every, and after each chunk estimates the
integrated autocorrelation time tau; it stops when the chain is longer than n_tau x max(tau) (and
tau is finite), or at max_steps, and then says it did not converge. Each finished chunk is stored
at once, atomically (chain.h5.chunks/), chain.h5 atomically at the end: a run killed at any moment
resumes from its last finished chunk and reaches the same final state, byte for byte in every
array, as an uninterrupted run with the same seed (tested, including a 10-kill soak).
"""

import dataclasses
from pathlib import Path

import numpy as np
from scipy import stats

from ...errors import ConfigError

__all__ = ["LogPosterior", "UnboundedPosterior", "SamplerResult", "run_sampler", "diagnostics",
           "prior_interval", "MOVES"]

MOVES = ("de", "stretch")


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
        if self.prior == "log_normal":  # on the tire's parameters; a bias stays uniform
            z = (thetas - self.space.default) / self.sigma_ln
            lp = -0.5 * np.sum(z[:, self.space.tire_indices] ** 2, axis=1)
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


class UnboundedPosterior:
    """`log_post` (over theta in a bounded box) seen in z = logit((theta - lower) / width).

    ln p(z) = ln p(theta(z)) + sum ln(u (1 - u)) (+ const): the same posterior, with no walls.
    """

    def __init__(self, log_post, space):
        self.log_post, self.space = log_post, space

    def to_theta(self, z):
        from scipy.special import expit

        u = expit(np.asarray(z, float))
        return np.clip(self.space.lower + self.space.width * u, self.space.lower, self.space.upper)

    def to_z(self, theta, eps: float = 1e-9):
        from scipy.special import logit

        return logit(np.clip(self.space.to_unit(np.asarray(theta, float)), eps, 1.0 - eps))

    def __call__(self, z):
        z = np.atleast_2d(np.asarray(z, float))
        # ln u + ln(1 - u) = -ln(1 + e^-z) - ln(1 + e^z), without overflow
        jac = -np.sum(np.logaddexp(0.0, -z) + np.logaddexp(0.0, z), axis=1)
        return self.log_post(self.to_theta(z)) + jac


def _moves(kind: str):
    import emcee

    if kind == "stretch":
        return None  # emcee's default StretchMove
    if kind == "de":
        return [(emcee.moves.DEMove(), 0.8), (emcee.moves.DESnookerMove(), 0.2)]
    raise ValueError(f"moves = {kind!r}: one of {MOVES}")


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


# ---- storage: atomic chunk files while running, one atomic chain.h5 when the run ends ----------
# emcee's own HDF5 backend writes each step in place (chain row, acceptance counts, random state,
# then the step counter) and is not safe to kill: a SIGKILL between those writes can leave acceptance
# counts one step ahead of the counter (docs/design-notes.md), so the step is redone and counted
# twice, and a kill during HDF5's metadata flush can leave the file unreadable. Here each
# chunk of steps is its own file written atomically (jtire.io), and chain.h5 (emcee's layout, so
# emcee.backends.HDFBackend(path, read_only=True) reads it) is written atomically at the end and
# is then the resume point; a kill loses at most the chunk in progress, which reruns identically.
_COMPLETE = "jtire_complete"  # attribute of a chain.h5 written whole by this module


def _chunks_dir(path: Path) -> Path:
    return path.with_name(path.name + ".chunks")


def _rs_arrays(random_state) -> dict:
    name, keys, pos, has_gauss, cached = random_state
    assert name == "MT19937"
    return {"rs_keys": np.asarray(keys, np.uint32), "rs_pos": np.int64(pos),
            "rs_has_gauss": np.int64(has_gauss), "rs_cached": np.float64(cached)}


def _rs_tuple(d) -> tuple:
    return ("MT19937", np.asarray(d["rs_keys"], np.uint32), int(d["rs_pos"]), int(d["rs_has_gauss"]),
            float(d["rs_cached"]))


def _read_h5(path: Path, walkers: int, d: int):
    """(chain, log_prob, accepted, random_state) of a chain.h5 written by _write_h5."""
    import h5py

    try:
        with h5py.File(path, "r") as f:
            g = f["mcmc"]
            if not g.attrs.get(_COMPLETE, False):
                raise ConfigError(f"chain {path}: written by an earlier jtire whose chain files were not safe "
                                  "to kill; use another --out folder (or delete it to start again)")
            shape = (int(g.attrs["nwalkers"]), int(g.attrs["ndim"]))
            if shape != (walkers, d):
                raise ConfigError(f"chain {path}: holds {shape[0]} walkers x {shape[1]} parameters, not "
                                  f"{walkers} x {d}; use another --out folder")
            rs = [v for k, v in sorted(g.attrs.items()) if k.startswith("random_state_")]
            return g["chain"][...], g["log_prob"][...], g["accepted"][...], tuple(rs)
    except OSError as e:
        raise ConfigError(f"chain {path}: unreadable ({e}); use another --out folder") from None


def _write_h5(path: Path, chain, log_prob, accepted, random_state) -> None:
    """chain.h5 in emcee's HDFBackend layout, built in memory and written atomically."""
    import io

    import emcee
    import h5py

    from ...io import atomic_write_bytes

    buf = io.BytesIO()
    with h5py.File(buf, "w") as f:
        g = f.create_group("mcmc")
        g.attrs["version"] = emcee.__version__
        g.attrs["nwalkers"], g.attrs["ndim"] = chain.shape[1], chain.shape[2]
        g.attrs["has_blobs"] = False
        g.attrs["iteration"] = chain.shape[0]
        for i, v in enumerate(random_state):
            g.attrs[f"random_state_{i}"] = v
        g.create_dataset("accepted", data=accepted)
        g.create_dataset("chain", data=chain, maxshape=(None, *chain.shape[1:]))
        g.create_dataset("log_prob", data=log_prob, maxshape=(None, chain.shape[1]))
        g.attrs[_COMPLETE] = True
    atomic_write_bytes(path, buf.getvalue())


def _write_chunk(folder: Path, start: int, chain, log_prob, accepted, random_state) -> None:
    import io

    from ...io import atomic_write_bytes

    buf = io.BytesIO()
    np.savez(buf, start=np.int64(start), chain=chain, log_prob=log_prob, accepted=accepted,
             **_rs_arrays(random_state))
    atomic_write_bytes(folder / f"{start:010d}.npz", buf.getvalue())


def _load(path: Path, walkers: int, d: int):
    """The stored chain: chain.h5 (if any) then the chunks that continue it, in order.
    Returns (chain (n, walkers, d), log_prob (n, walkers), accepted (walkers,), random state or
    None for an empty chain)."""
    chain = np.zeros((0, walkers, d))
    log_prob = np.zeros((0, walkers))
    accepted = np.zeros(walkers)
    rs = None
    if path.exists():
        chain, log_prob, accepted, rs = _read_h5(path, walkers, d)
    folder = _chunks_dir(path)
    for f in sorted(folder.glob("*.npz")) if folder.is_dir() else ():
        try:
            with np.load(f) as z:
                c = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError) as e:
            raise ConfigError(f"chain chunk {f}: unreadable ({e}); use another --out folder") from None
        start = int(c["start"])
        if start < chain.shape[0]:
            continue  # already in chain.h5 (killed after writing it, before removing the chunks)
        if start != chain.shape[0] or c["chain"].shape[1:] != (walkers, d):
            raise ConfigError(f"chain chunk {f}: does not continue the stored chain of {chain.shape[0]} steps "
                              f"x {walkers} walkers x {d} parameters; use another --out folder")
        chain = np.concatenate([chain, c["chain"]])
        log_prob = np.concatenate([log_prob, c["log_prob"]])
        accepted = accepted + c["accepted"]
        rs = _rs_tuple(c)
    return chain, log_prob, accepted, rs


def run_sampler(log_prob, p0, path, walkers: int, max_steps: int, check_every: int = 500,
                n_tau: float = 50.0, seed: int = 0, progress=None, moves: str = "stretch") -> SamplerResult:
    """Run (or resume) an emcee EnsembleSampler whose chain is stored at `path` (chain.h5).

    log_prob: vectorized, thetas (walkers, d) -> (walkers,); p0: (walkers, d) start (used only
    for a new chain). Steps run in chunks ending on multiples of check_every; each chunk starts a
    sampler from the stored state (positions, log-probabilities, random state), in a fresh run and
    a resumed one alike, so a resumed chain is the uninterrupted one. Each finished chunk is stored
    at once (atomically) in path + ".chunks/"; at the end chain.h5 is written whole and the chunks
    removed. progress: optional callable(steps, tau) after each chunk. moves: "stretch" (emcee's
    default) or "de" (differential evolution, see the module docstring).
    """
    import shutil

    import emcee
    from emcee.state import State

    p0 = np.asarray(p0, float)
    d = p0.shape[1]
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    chain, lp, accepted, rs = _load(path, walkers, d)
    start = it = chain.shape[0]
    if rs is None:  # a new chain
        lp0 = log_prob(p0)
        if not np.all(np.isfinite(lp0)):
            raise ConfigError(f"sampler start: {int(np.sum(~np.isfinite(lp0)))} walkers start "
                              "where the posterior is zero (outside the bounds?)")
        state = State(p0, random_state=np.random.RandomState(int(seed)).get_state())
    else:
        state = State(chain[-1], log_prob=lp[-1], random_state=rs)
    tau = np.full(d, np.nan)
    converged = False
    if it >= check_every and it % check_every == 0:  # resumed exactly on a check: redo it
        tau = _tau(chain)
        converged = bool(np.all(np.isfinite(tau)) and it > n_tau * np.max(tau))
    folder = _chunks_dir(path)
    while it < max_steps and not converged:
        n = min(check_every - it % check_every, max_steps - it)
        sampler = emcee.EnsembleSampler(walkers, d, log_prob, vectorize=True, moves=_moves(moves))
        state = sampler.run_mcmc(state, n, progress=False)
        c, l, a = sampler.get_chain(), sampler.get_log_prob(), sampler.backend.accepted
        _write_chunk(folder, it, c, l, a, state.random_state)
        chain, lp, accepted = np.concatenate([chain, c]), np.concatenate([lp, l]), accepted + a
        it = chain.shape[0]
        tau = _tau(chain)
        converged = bool(np.all(np.isfinite(tau)) and it > n_tau * np.max(tau))
        if progress is not None:
            progress(it, tau)
    if it > start or not path.exists():
        _write_h5(path, chain, lp, accepted, state.random_state)
    shutil.rmtree(folder, ignore_errors=True)
    if not np.all(np.isfinite(tau)) and chain.shape[0] > 0:
        tau = _tau(chain)
    acc = accepted / max(it, 1)
    return SamplerResult(chain, lp, tau, converged, acc, int(it), int(it - start), float(n_tau))


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
    uniform = np.stack([space.lower + a * space.width, space.upper - a * space.width], axis=1)
    if prior == "log_uniform":
        return uniform
    lo = (space.lower - space.default) / sigma_ln
    hi = (space.upper - space.default) / sigma_ln
    tn = stats.truncnorm(lo, hi, loc=space.default, scale=sigma_ln)
    out = np.stack([tn.ppf(a), tn.ppf(1 - a)], axis=1)
    bias = [j for j in range(space.d) if space.is_bias(j)]  # a bias's prior is uniform always
    out[bias] = uniform[bias]
    return out
