"""An emulator of the target responses, trained on every simulator run of a calibration.

The posterior needs the four responses at hundreds of thousands of parameter sets; the shell
model gives tens. Each response gets its own model of ln(response) over the unit box of the
log-parameters, chosen by leave-one-out (LOO) error among:

- "linear", "reduced", "full": quadratic surfaces (surrogates.fit_quadratic), each only when the
  points fix it with at least one to spare. Predictive variance of a new run:
  sigma2 (1 + phi^T (A^T A)^+ phi), the residual variance plus the variance of the fitted mean.
- "gp": a linear surface plus a Gaussian process on its residuals (scikit-learn's
  GaussianProcessRegressor: constant x anisotropic RBF + white noise, hyperparameters by
  maximum likelihood, seeded restarts). LOO in closed form for the fitted hyperparameters
  (Rasmussen & Williams eq. 5.12; the hyperparameters and the linear part are not refitted per
  left-out point, so its LOO is slightly optimistic). Offered only if scikit-learn is installed.

`Emulator.predict(thetas)` returns the mean of ln(response) and its predictive variance,
shape (n, m) each; the posterior adds that variance to each target's measurement variance.
"""

import dataclasses

import numpy as np

from ...errors import ConfigError
from ...surrogates import fit_quadratic, n_terms

__all__ = ["Emulator", "fit_emulator", "gp_available", "usable", "CANDIDATES"]

CANDIDATES = ("linear", "reduced", "full", "gp")
GP_RESTARTS = 2  # seeded restarts of the maximum-likelihood fit of the GP hyperparameters


def usable(y) -> np.ndarray:
    """Rows (n,) of responses y (n, m) that a run gave in full: every value finite and > 0 (the
    emulator models ln(response))."""
    y = np.asarray(y, float)
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(y) & (y > 0), axis=1)


def gp_available() -> bool:
    try:
        import sklearn.gaussian_process  # noqa: F401
    except ImportError:
        return False
    return True


class _Quadratic:
    def __init__(self, surf):
        self.s, self.kind = surf, surf.kind
        self.loo = np.asarray(surf.loo_residuals, float)
        s2 = surf.sigma2
        # without residual freedom the LOO mean square stands in for the residual variance
        self.s2 = s2 if np.isfinite(s2) else float(np.mean(self.loo**2))

    def predict(self, u):
        mean = self.s.predict(u)
        var = self.s.variance(u)
        var = np.where(np.isfinite(var), var, 0.0)
        return mean, self.s2 + np.maximum(var, 0.0)



class _GP:
    kind = "gp"

    def __init__(self, u, y, seed):
        from sklearn.gaussian_process import GaussianProcessRegressor
        from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

        d = u.shape[1]
        self.lin = fit_quadratic(u, y, np.zeros(d), np.ones(d), kind="linear")
        r = y - self.lin.predict(u)
        self.mu, self.sd = float(np.mean(r)), float(np.std(r)) or 1.0
        rs = (r - self.mu) / self.sd
        kernel = (ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.full(d, 0.5), (1e-2, 1e2))
                  + WhiteKernel(1e-2, (1e-8, 1e1)))
        self.gp = GaussianProcessRegressor(kernel, n_restarts_optimizer=GP_RESTARTS, random_state=seed)
        import warnings

        from sklearn.exceptions import ConvergenceWarning

        # a length scale at its upper bound means the residual does not vary along that parameter
        # (most of the 20 do not, for a given response): an answer, not a failure. The fit's
        # quality is judged by its leave-one-out error (self.loo), which picks the emulator.
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.gp.fit(u, rs)
        k = self.gp.kernel_(u) + self.gp.alpha * np.eye(len(u))
        kinv = np.linalg.inv(k)
        self.loo = self.sd * (kinv @ rs) / np.diag(kinv)

    def predict(self, u):
        u = np.atleast_2d(u)
        m, s = self.gp.predict(u, return_std=True)
        return self.lin.predict(u) + self.mu + self.sd * m, (self.sd * s) ** 2


def _candidates(u, y, wanted, seed):
    n, d = u.shape
    out = {}
    for kind in ("linear", "reduced", "full"):
        if kind in wanted and n >= n_terms(d, kind) + 1:
            out[kind] = _Quadratic(fit_quadratic(u, y, np.zeros(d), np.ones(d), kind=kind))
    if "gp" in wanted and gp_available() and n >= d + 3:
        out["gp"] = _GP(u, y, seed)
    return out


@dataclasses.dataclass
class Emulator:
    """Per-response models of ln(response) over the unit box of a ParamSpace.

    names: (m,) responses; kinds: (m,) the chosen model per response; loo: {response: {kind:
    LOO RMSE of ln(response)}} for every candidate tried; n_points: training points;
    var_scale a, var_floor b: (m,) the predictive variance v becomes max(a v, v + b) where b > 0, and
    a v where b = 0 (a = 1, b = 0 unless calibrated on held-out simulator runs:
    `calibration.posterior.conformal.calibrate_variance`).
    bias: (m, d) or None: the calibration's bias entries (`ParamSpace.bias_matrix`). The models are
    then fitted to the tire's own responses (a run's response less its bias, known exactly) and
    `predict` returns ln(tire + b), its variance mapped through the sum; `predict_tire` the tire's.
    """

    space: object
    names: tuple
    models: list
    kinds: tuple
    loo: dict
    n_points: int
    var_scale: np.ndarray = None
    var_floor: np.ndarray = None
    bias: np.ndarray = None

    def predict_tire(self, thetas):
        """thetas (n, d) -> (mean, variance) of ln(the tire's own response), (n, m) each."""
        u = self.space.to_unit(np.atleast_2d(np.asarray(thetas, float)))
        out = [m.predict(u) for m in self.models]
        return np.stack([o[0] for o in out], axis=-1), np.stack([o[1] for o in out], axis=-1)

    def predict(self, thetas):
        """thetas (n, d) -> (mean of ln response (n, m), predictive variance (n, m)); with a bias,
        the response is what the targets measure: tire + b (delta method for the variance)."""
        thetas = np.atleast_2d(np.asarray(thetas, float))
        mean, var = self.predict_tire(thetas)
        if self.bias is not None:
            tire = np.exp(mean)
            total = tire + thetas @ self.bias.T
            mean, var = np.log(total), var * (tire / total) ** 2
        a = 1.0 if self.var_scale is None else np.asarray(self.var_scale, float)
        if self.var_floor is not None:
            b = np.asarray(self.var_floor, float)
            var = np.where(b > 0, np.maximum(a * var, var + b), a * var)
        else:
            var = a * var
        return mean, var

    def summary(self) -> dict:
        out = {"n_points": self.n_points, "chosen": dict(zip(self.names, self.kinds)),
               "loo_rmse_ln": self.loo, "gp_available": gp_available()}
        if self.var_scale is not None:
            out["variance_scale"] = dict(zip(self.names, np.asarray(self.var_scale, float).tolist()))
        if self.var_floor is not None:
            out["variance_floor_sd_ln"] = dict(zip(self.names, np.sqrt(self.var_floor).tolist()))
        return out

    def calibration_text(self) -> str:
        """How held-out runs changed each response's predictive variance, in one line."""
        if self.var_scale is None and self.var_floor is None:
            return "not calibrated"
        n = len(self.names)
        a = np.ones(n) if self.var_scale is None else np.asarray(self.var_scale, float)
        b = np.zeros(n) if self.var_floor is None else np.asarray(self.var_floor, float)
        parts = []
        for name, ai, bi in zip(self.names, a, b):
            if bi == 0.0:
                parts.append(f"{name} x {ai:.3g}")
            elif ai == 1.0:
                parts.append(f"{name} + ({np.sqrt(bi):.3g})^2")
            else:
                parts.append(f"{name} the wider of x {ai:.3g} and + ({np.sqrt(bi):.3g})^2")
        return ", ".join(parts)


def fit_emulator(space, names, thetas, responses, candidates=CANDIDATES, seed: int = 0) -> Emulator:
    """Fit every candidate to each response and keep the smallest LOO RMSE.

    thetas: (n, d) log-parameters of the simulator runs; responses: (n, m) SI (rows with a
    non-finite or non-positive value are left out).
    """
    thetas = np.atleast_2d(np.asarray(thetas, float))
    y = np.asarray(responses, float).reshape(thetas.shape[0], -1)
    bias = space.bias_matrix(names) if getattr(space, "has_bias", False) else None
    if bias is not None:  # the tire's own responses: what the runs measured less their (known) bias
        y = y - thetas @ bias.T
    ok = usable(y) & np.all(np.isfinite(thetas), axis=1)
    u, ly = space.to_unit(thetas[ok]), np.log(y[ok])
    if u.shape[0] < space.d + 2:
        raise ConfigError(f"emulator: {u.shape[0]} usable simulator runs for {space.d} parameters; "
                          f"needs at least d + 2 = {space.d + 2} (run the calibration first)")
    bad = [c for c in candidates if c not in CANDIDATES]
    if bad or not candidates:
        raise ConfigError(f"emulator.candidates = {list(candidates)!r}: allowed {CANDIDATES}")
    models, kinds, loo = [], [], {}
    for j, name in enumerate(names):
        cands = _candidates(u, ly[:, j], candidates, seed)
        scores = {k: float(np.sqrt(np.mean(c.loo**2))) for k, c in cands.items()}
        finite = {k: v for k, v in scores.items() if np.isfinite(v)}
        best = min(finite, key=finite.get) if finite else min(scores, key=scores.get)
        models.append(cands[best]), kinds.append(best)
        loo[name] = scores
    return Emulator(space, tuple(names), models, tuple(kinds), loo, int(u.shape[0]), bias=bias)
