"""Fits of rolling-resistance coefficient against vertical load, with confidence intervals.

Two trend models of RRC (dimensionless) against vertical load F_z (N):

* linear      RRC = a + b F_z                 ordinary least squares;
* power law   RRC = c F_z^d                   least squares on ln RRC = ln c + d ln F_z.

The power law is fitted in log space because the run-to-run scatter of a force ratio is
multiplicative (about the same *relative* spread at every load), which is what the log-space
error model assumes, and because it keeps the confidence intervals closed-form (Student t on an
ordinary least-squares fit) instead of relying on a nonlinear-least-squares linearization.
Its "mean prediction" is therefore exp(E[ln RRC]), the geometric-mean (median) trend.

Intervals: parameters use the t quantile with n - 2 degrees of freedom and the OLS covariance
sigma^2 (X^T X)^-1; the mean prediction at x0 has standard error sqrt(x0^T Cov x0); a new single
observation adds sigma^2 under the square root.

The study's rolling-resistance calibration targets live in configs/reference_xone_xda.toml
([calibration.targets.rolling_resistance_N]); `load_targets` reads them and `compare_target`
places them against a fit.
"""

import dataclasses
import math
from pathlib import Path

import numpy as np
from scipy import stats

from .errors import ConfigError
from .resources import configs_dir

DEFAULT_REFERENCE = configs_dir() / "reference_xone_xda.toml"


@dataclasses.dataclass(frozen=True)
class Prediction:
    """A fitted trend evaluated at loads `fz_n` (N), arrays of shape (m,).

    mean: the trend (RRC); lower/upper: confidence band of the mean trend; obs_lower/obs_upper:
    prediction band of one new run; se: standard error of the mean trend in the fit's own scale
    (RRC for the linear fit, ln RRC for the power law); se_obs likewise for one new run.
    """

    fz_n: np.ndarray
    mean: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    obs_lower: np.ndarray
    obs_upper: np.ndarray
    se: np.ndarray
    se_obs: np.ndarray


@dataclasses.dataclass(frozen=True)
class OLSLine:
    """y = p0 + p1 x fitted by ordinary least squares.

    params: (2,) [intercept, slope]; cov: (2, 2) parameter covariance; sigma: residual standard
    deviation; n: number of points; confidence: two-sided level of every interval (e.g. 0.95);
    exact: the points lie on the line to round-off (sigma ~ 0: the parameters are right, but
    every interval has zero width -- `jtire.data` refuses to report such a fit).
    """

    params: np.ndarray
    cov: np.ndarray
    sigma: float
    n: int
    confidence: float
    exact: bool = False

    @property
    def dof(self) -> int:
        return self.n - 2

    @property
    def t_quantile(self) -> float:
        return float(stats.t.ppf(0.5 + self.confidence / 2.0, self.dof))

    @property
    def stderr(self) -> np.ndarray:
        """(2,) standard errors of [intercept, slope]."""
        return np.sqrt(np.diag(self.cov))

    @property
    def ci(self) -> np.ndarray:
        """(2, 2) rows [intercept, slope], columns [lower, upper]."""
        half = self.t_quantile * self.stderr
        return np.stack([self.params - half, self.params + half], axis=1)

    def evaluate(self, x):
        """Mean line, its standard error and a new observation's standard error at x, shape (m,)."""
        x = np.atleast_1d(np.asarray(x, dtype=float))
        design = np.stack([np.ones_like(x), x], axis=1)
        mean = design @ self.params
        se = np.sqrt(np.einsum("mi,ij,mj->m", design, self.cov, design))
        se_obs = np.sqrt(se**2 + self.sigma**2)
        return mean, se, se_obs


def fit_ols_line(x, y, confidence: float = 0.95) -> OLSLine:
    """Ordinary least squares of y on [1, x]; x, y shape (n,), n >= 3 with two distinct x."""
    x = np.asarray(x, dtype=float).ravel()
    y = np.asarray(y, dtype=float).ravel()
    if not 0.0 < confidence < 1.0:
        raise ConfigError(f"confidence = {confidence}: must be in (0, 1), e.g. 0.95")
    if x.shape != y.shape:
        raise ConfigError(f"{x.size} x values and {y.size} y values: need one y per x")
    if x.size < 3:
        raise ConfigError(f"{x.size} points: a fit with confidence intervals needs at least 3")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ConfigError("fit points: must be finite (got NaN or inf)")
    if np.ptp(x) == 0.0:
        raise ConfigError("fit points: x must take at least two distinct values")
    # Centre x before the QR so the normal matrix stays well conditioned (loads are ~1e4 N).
    x0 = float(np.mean(x))
    design = np.stack([np.ones_like(x), x - x0], axis=1)
    q, r = np.linalg.qr(design)
    beta_c = np.linalg.solve(r, q.T @ y)
    resid = y - design @ beta_c
    ss = float(resid @ resid)
    # Points on the line to round-off (far below the 6 printed digits of measured data): the
    # parameters are right, but the residual sd estimate is 0, so every interval has zero width.
    exact = ss <= x.size * (1e-10 * float(np.max(np.abs(y)))) ** 2
    sigma2 = ss / (x.size - 2)
    r_inv = np.linalg.inv(r)
    cov_c = sigma2 * (r_inv @ r_inv.T)
    # Back to the uncentred parameters: [p0, p1] = T [b0, b1] with p0 = b0 - x0 b1.
    t = np.array([[1.0, -x0], [0.0, 1.0]])
    return OLSLine(params=t @ beta_c, cov=t @ cov_c @ t.T, sigma=math.sqrt(sigma2),
                   n=int(x.size), confidence=float(confidence), exact=bool(exact))


@dataclasses.dataclass(frozen=True)
class LinearFit:
    """RRC = a + b F_z, with F_z in N (b in 1/N). `line` holds the OLS details."""

    line: OLSLine

    @property
    def a(self) -> float:
        return float(self.line.params[0])

    @property
    def b(self) -> float:
        return float(self.line.params[1])

    @property
    def a_ci(self) -> tuple:
        return tuple(float(v) for v in self.line.ci[0])

    @property
    def b_ci(self) -> tuple:
        return tuple(float(v) for v in self.line.ci[1])

    def predict(self, fz_n) -> Prediction:
        fz = np.atleast_1d(np.asarray(fz_n, dtype=float))
        mean, se, se_obs = self.line.evaluate(fz)
        tq = self.line.t_quantile
        return Prediction(fz, mean, mean - tq * se, mean + tq * se,
                          mean - tq * se_obs, mean + tq * se_obs, se, se_obs)

    def as_dict(self) -> dict:
        return {"model": "RRC = a + b * Fz_N", "a": self.a, "a_ci": self.a_ci, "b_per_N": self.b,
                "b_ci": self.b_ci, "cov": self.line.cov, "sigma": self.line.sigma,
                "n": self.line.n, "dof": self.line.dof, "confidence": self.line.confidence}


@dataclasses.dataclass(frozen=True)
class PowerFit:
    """RRC = c F_z^d, F_z in N; fitted as ln RRC = ln c + d ln F_z (`log_line`)."""

    log_line: OLSLine

    @property
    def c(self) -> float:
        return math.exp(float(self.log_line.params[0]))

    @property
    def d(self) -> float:
        return float(self.log_line.params[1])

    @property
    def c_ci(self) -> tuple:
        # exp is monotone, so the interval of ln c maps to an (asymmetric) interval of c.
        return tuple(math.exp(float(v)) for v in self.log_line.ci[0])

    @property
    def d_ci(self) -> tuple:
        return tuple(float(v) for v in self.log_line.ci[1])

    def predict(self, fz_n) -> Prediction:
        fz = np.atleast_1d(np.asarray(fz_n, dtype=float))
        if np.any(fz <= 0.0):
            raise ConfigError("power-law prediction load Fz: must be > 0 N")
        mu, se, se_obs = self.log_line.evaluate(np.log(fz))
        tq = self.log_line.t_quantile
        return Prediction(fz, np.exp(mu), np.exp(mu - tq * se), np.exp(mu + tq * se),
                          np.exp(mu - tq * se_obs), np.exp(mu + tq * se_obs), se, se_obs)

    def as_dict(self) -> dict:
        return {"model": "RRC = c * Fz_N ** d (least squares in log space)", "c": self.c,
                "c_ci": self.c_ci, "d": self.d, "d_ci": self.d_ci, "ln_c": self.log_line.params[0],
                "cov_lnc_d": self.log_line.cov, "sigma_ln": self.log_line.sigma,
                "n": self.log_line.n, "dof": self.log_line.dof,
                "confidence": self.log_line.confidence}


def fit_linear(fz_n, rrc, confidence: float = 0.95) -> LinearFit:
    """Linear trend RRC = a + b F_z; fz_n (N) and rrc of shape (n,)."""
    return LinearFit(fit_ols_line(fz_n, rrc, confidence))


def fit_power(fz_n, rrc, confidence: float = 0.95) -> PowerFit:
    """Power-law trend RRC = c F_z^d; fz_n (N) and rrc of shape (n,), all > 0."""
    fz = np.asarray(fz_n, dtype=float)
    r = np.asarray(rrc, dtype=float)
    if np.any(fz <= 0.0) or np.any(r <= 0.0):
        raise ConfigError("power-law fit points: Fz and RRC must be > 0")
    return PowerFit(fit_ols_line(np.log(fz), np.log(r), confidence))


@dataclasses.dataclass(frozen=True)
class Target:
    """One rolling-resistance calibration target: force (N) at vertical load (N)."""

    name: str
    load_n: float
    force_n: float

    @property
    def rrc(self) -> float:
        return self.force_n / self.load_n


def _positive(table: dict, key: str, where: str, hi: float) -> float:
    v = table.get(key)
    if not (isinstance(v, (int, float)) and not isinstance(v, bool)):
        raise ConfigError(f"{where}.{key} = {v!r}: must be a number in (0, {hi:g}]")
    if not 0.0 < v <= hi:  # NaN fails here too
        raise ConfigError(f"{where}.{key} = {v!r}: must be in (0, {hi:g}]")
    return float(v)


def load_targets(reference=None) -> list:
    """Read [calibration.targets.rolling_resistance_*] from the reference TOML.

    The load is taken from `vertical_load_kN` (the study's 38.7 / 41.4 kN, from which it quotes
    RRC 0.0395 / 0.0411), not from the rounder `vertical_load_lbs` (9300 lbf is 41.37 kN).
    Each table needs vertical_load_kN in (0, 500] and force_N > 0 below the load (RRC < 1);
    anything else is one ConfigError naming the file and the field.
    """
    from .config import read_toml

    path = Path(reference) if reference is not None else DEFAULT_REFERENCE
    doc = read_toml(path, "reference file")
    cal = doc.get("calibration", {})
    tables = cal.get("targets", {}) if isinstance(cal, dict) else None
    if not isinstance(tables, dict):
        raise ConfigError(f"{path}: calibration.targets must be a table of "
                          "[calibration.targets.rolling_resistance_*] tables")
    out = []
    for name in sorted(k for k in tables if k.startswith("rolling_resistance")):
        t, where = tables[name], f"{path.name}: calibration.targets.{name}"
        if not isinstance(t, dict):
            raise ConfigError(f"{where}: must be a table with vertical_load_kN and force_N")
        load_n = _positive(t, "vertical_load_kN", where, 500.0) * 1e3
        force_n = _positive(t, "force_N", where, 1e6)
        if force_n >= load_n:
            raise ConfigError(f"{where}.force_N = {force_n:g}: must be below the vertical load "
                              f"{load_n:g} N (a rolling-resistance coefficient below 1)")
        if "vertical_load_lbs" in t:
            _positive(t, "vertical_load_lbs", where, 1.2e5)
        out.append(Target(name, load_n, force_n))
    if not out:
        raise ConfigError(f"{path}: no [calibration.targets.rolling_resistance_*] tables")
    return out


@dataclasses.dataclass(frozen=True)
class TargetComparison:
    """A target RRC against a fit's trend at the target's load.

    pred/lower/upper: trend and its confidence band; obs_lower/obs_upper: prediction band of one
    new point of the kind fitted (a run, or a configuration mean for a fit to means); z_mean:
    (target - trend) in standard errors of the trend; z_obs: the same in standard errors of one new
    point (both in the fit's own scale: RRC for linear, ln RRC for power law);
    percent: (target / trend - 1) * 100.
    """

    target: str
    dataset: str
    model: str
    load_n: float
    target_rrc: float
    pred: float
    lower: float
    upper: float
    obs_lower: float
    obs_upper: float
    z_mean: float
    z_obs: float
    percent: float

    @property
    def inside_ci(self) -> bool:
        return self.lower <= self.target_rrc <= self.upper


def compare_target(fit, target: Target, dataset: str = "") -> TargetComparison:
    """Place one target against a LinearFit or PowerFit (`dataset` only labels the result)."""
    line = fit.log_line if isinstance(fit, PowerFit) else fit.line
    if line.exact:
        raise ConfigError(f"{dataset or 'fit'}: its {line.n} points lie exactly on the trend (residual "
                          "sd 0): no band to compare a target with; measured runs scatter, check the data")
    p = fit.predict(target.load_n)
    pred = float(p.mean[0])
    if isinstance(fit, PowerFit):
        model, dev = "power", math.log(target.rrc) - math.log(pred)
    else:
        model, dev = "linear", target.rrc - pred
    return TargetComparison(
        target=target.name, dataset=dataset, model=model, load_n=target.load_n,
        target_rrc=target.rrc, pred=pred,
        lower=float(p.lower[0]), upper=float(p.upper[0]), obs_lower=float(p.obs_lower[0]),
        obs_upper=float(p.obs_upper[0]), z_mean=dev / float(p.se[0]),
        z_obs=dev / float(p.se_obs[0]), percent=(target.rrc / pred - 1.0) * 100.0)
