"""What `jtire sample` reports: predictive intervals beside the targets, parameter widths, a
corner plot, and the check of the emulator against the simulator.

- predictive(): posterior-predictive median and 90 % interval of each target's response and of
  what an engineer reads off it (k_sv, k_l, RRC; calibration.targets.derived_quantity), from
  posterior samples pushed through the emulator with its predictive noise (what the tire model
  would give; the measurement noise is not added).
- widths(): each parameter's 90 % posterior interval in ln p against its 90 % prior interval.
- plot_corner(): pairwise scatter / histograms (matplotlib) of the most constrained parameters.
- simulator_check(): >= 32 posterior draws through the simulator as ONE batch; the fraction of
  draws whose simulated ln(response) falls inside the emulator's 90 % predictive interval, per
  response (a calibrated emulator gives ~0.9).
"""

from pathlib import Path

import numpy as np
from scipy import stats

from .model import prior_interval
from ..tire.targets import derived_quantity
from ...io import atomic_savefig

__all__ = ["predictive", "widths", "plot_corner", "simulator_check", "check_draws", "coverage",
           "coverage_interval"]

_Z90 = float(stats.norm.ppf(0.95))


def predictive(emulator, samples, targets, seed: int = 0, level: float = 0.9, space=None) -> list:
    """Rows: target, quantity, measured, median, lower, upper (target unit and derived). With a
    bias in `space`, a biased target gets rows for the tire alone (draw minus its bias) and the
    bias."""
    rng = np.random.default_rng(seed)
    mu, var = emulator.predict(samples)
    ly = mu + np.sqrt(np.maximum(var, 0)) * rng.standard_normal(mu.shape)
    y = np.exp(ly)
    q = [50, 50 * (1 - level), 50 * (1 + level)]
    B = space.bias_matrix([t.name for t in targets]) if space is not None and space.has_bias else None
    mt, vt = emulator.predict_tire(samples) if B is not None else (None, None)
    rows = []
    for i, t in enumerate(targets):
        med, lo, hi = np.percentile(y[:, i], q)
        rows.append({"target": t.name, "what": t.quantity, "unit": t.unit,
                     "measured": t.measured / t.unit_factor, "median": med / t.unit_factor,
                     "lower": lo / t.unit_factor, "upper": hi / t.unit_factor})
        label, dv, unit = derived_quantity(t, y[:, i])
        _, dm, _ = derived_quantity(t, t.measured)
        dmed, dlo, dhi = np.percentile(dv, q)
        if label != t.name:
            rows.append({"target": t.name, "what": label, "unit": unit, "measured": float(dm),
                         "median": dmed, "lower": min(dlo, dhi), "upper": max(dlo, dhi)})
        if B is not None and np.any(B[i]):
            b = samples @ B[i]
            # the tire's own response from the emulator of the tire (not draw minus bias: the two
            # draws' noises would not cancel)
            tire = np.exp(mt[:, i] + np.sqrt(np.maximum(vt[:, i], 0)) * rng.standard_normal(len(samples)))
            for what, v in (("tire alone", tire), ("bias", b)):
                med, lo, hi = np.percentile(v, q)
                rows.append({"target": t.name, "what": f"{t.quantity}: {what}", "unit": t.unit,
                             "measured": float("nan"), "median": med / t.unit_factor,
                             "lower": lo / t.unit_factor, "upper": hi / t.unit_factor})
            label, dv, unit = derived_quantity(t, tire)
            if label != t.name:
                med, lo, hi = np.percentile(dv, q)
                rows.append({"target": t.name, "what": f"{label}: tire alone", "unit": unit,
                             "measured": float("nan"), "median": med, "lower": lo, "upper": hi})
    return rows


def widths(samples, space, prior: str, sigma_ln: float, level: float = 0.9) -> list:
    """Rows: parameter, prior and posterior `level` interval widths in ln p (a bias: in its SI
    unit), their ratio, the posterior median and `level` interval in the tire file's unit."""
    a = 50 * (1 - level)
    post = np.percentile(samples, [a, 100 - a], axis=0).T
    pri = prior_interval(space, prior, sigma_ln, level)
    med = np.median(samples, axis=0)
    rows = []
    for i, n in enumerate(space.names):
        factor, unit = space.file_unit(i)
        pw, qw = float(pri[i, 1] - pri[i, 0]), float(post[i, 1] - post[i, 0])
        rows.append({"parameter": n, "prior_width_ln": pw, "posterior_width_ln": qw,
                     "ratio": qw / pw, "median": float(space.value(i, med[i]) / factor),
                     "lower": float(space.value(i, post[i, 0]) / factor),
                     "upper": float(space.value(i, post[i, 1]) / factor), "unit": unit})
    return rows


def plot_corner(samples, names, path, max_params: int = 8, order=None, title: str = "") -> Path:
    """Corner plot (ln p) of up to max_params parameters (order: indices, most constrained
    first); histograms on the diagonal, 2-D histograms below."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    idx = list(range(len(names)) if order is None else order)[:max_params]
    k = len(idx)
    fig, axes = plt.subplots(k, k, figsize=(1.6 * k + 1, 1.6 * k + 1), squeeze=False)
    for r in range(k):
        for c in range(k):
            ax = axes[r][c]
            if c > r:
                ax.axis("off")
                continue
            x = samples[:, idx[c]]
            if r == c:
                ax.hist(x, bins=30, color="C0", histtype="stepfilled", alpha=0.7)
                ax.set_yticks([])
            else:
                ax.hist2d(x, samples[:, idx[r]], bins=30, cmap="Blues")
            if r == k - 1:
                ax.set_xlabel(f"ln {names[idx[c]].replace('parts.', '')}", fontsize=6)
            if c == 0 and r > 0:
                ax.set_ylabel(f"ln {names[idx[r]].replace('parts.', '')}", fontsize=6)
            ax.tick_params(labelsize=5)
    fig.suptitle(title, fontsize=8)
    fig.tight_layout()
    return atomic_savefig(fig, path, dpi=100)


def check_draws(samples, n_draws: int = 32, seed: int = 0) -> np.ndarray:
    """The (n, d) posterior samples the simulator check runs (seeded, without replacement)."""
    rng = np.random.default_rng(seed)
    n = min(int(n_draws), samples.shape[0])
    return samples[rng.choice(samples.shape[0], size=n, replace=False)]


def coverage(emulator, thetas, y, level: float = 0.9) -> dict:
    """Coverage of the emulator's `level` predictive intervals by simulated responses y (n, m)."""
    y = np.asarray(y, float)
    mu, var = emulator.predict(thetas)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = (np.log(y) - mu) / np.sqrt(var)
    zq = float(stats.norm.ppf(0.5 + level / 2))
    ok = np.all(np.isfinite(z), axis=1)
    n = int(ok.sum())
    inside = {name: int(np.sum(np.abs(z[ok, i]) <= zq)) for i, name in enumerate(emulator.names)}
    cover = {name: k / n if n else float("nan") for name, k in inside.items()}
    return {"coverage": cover, "inside": inside,
            "coverage_interval": {k: coverage_interval(v, n) for k, v in inside.items()},
            "level": level, "n": n, "n_requested": len(thetas),
            "z": z, "thetas": np.asarray(thetas), "simulated": y}


def coverage_interval(inside: int, n: int, confidence: float = 0.9) -> list:
    """[lower, upper]: exact (Clopper-Pearson) `confidence` interval of an interval's true coverage
    from `inside` of n draws falling in it. 32 of 32 gives [0.911, 1], 29 of 32 [0.775, 0.974]:
    32 draws pin a coverage down to about +-0.1. No draws: [nan, nan]."""
    if n <= 0:
        return [float("nan"), float("nan")]
    ci = stats.binomtest(int(inside), int(n)).proportion_ci(confidence_level=confidence, method="exact")
    return [float(ci.low), float(ci.high)]


def simulator_check(sim, emulator, samples, n_draws: int = 32, seed: int = 0,
                    level: float = 0.9) -> dict:
    """Push n_draws posterior samples through the simulator as one batch; coverage of the
    emulator's `level` predictive interval per response.

    Returns {"coverage": {name: fraction}, "n": draws used (finite runs), "z": (n, m)
    standardized residuals (ln sim - mean) / sd, "thetas", "simulated"}.
    """
    thetas = check_draws(samples, n_draws, seed)
    return coverage(emulator, thetas, np.asarray(sim.evaluate(thetas), float), level)
