"""Run the posterior end to end (what `jtire sample` calls): emulator, chain, reports, check.

Output folder: fingerprint.json (the posterior config, the calibration's fingerprint and a hash
of the emulator's training runs: a rerun with other settings refuses), chain.h5 (emcee's HDF5
layout, written whole when the chain stops; while it runs, chain.h5.chunks/ holds each finished
chunk: a killed run resumes from it when rerun; with sampler.coordinates = "logit" the chain holds
z = logit((theta - lower) / width), theta = ln p: posterior.UnboundedPosterior), emulator.json
(LOO errors of every candidate, the choice), diagnostics.json, predictive.csv/.md, widths.csv,
corner.png, check_runs.jsonl (the simulator check's runs, one line per draw, appended as each piece
of the batch returns: a killed check resumes without rerunning them), check.json (the check's
result; reused, not rerun, when the same draws are asked again).

Model discrepancy (discrepancy.kind = "best_miss"): a target no parameter set of the calibration
came near is not information about the parameters. Left in the likelihood with only its
measurement sd, it drags the posterior onto the bounds of whatever moves it most and reports a
precise, wrong tire (the study calibration: rolling resistance ~3x below its targets at every
run; without a discrepancy the crown and tread loss factors sat at their upper bounds with
posterior widths 3 % and 5 % of the prior's). Per target i the discrepancy sd is the smallest
miss |ln(y_i / t_i)| over every simulator run of the calibration: the model demonstrably comes
that close and no closer, so a residual of that size is put down to the model, not the
parameters. It adds to the measurement variance; for a reachable target it is ~0.

Refinement (check.refine, check.rounds): if the simulator check finds the emulator's 90 % intervals
covering fewer than 80 % or more than 97 % of the draws of some response, the check's runs (posterior
draws, where the emulator matters) join the training set, the emulator's predictive variance is
corrected per response by k-fold cross-validation over those draws (`calibrate_variance`, split-
conformal, so that a new run falls inside the 90 % interval with probability >= 90 %; the plain 90 %
quantile of 32 held-out scores falls short by ~1/32), the chain is rerun in refined/, and a fresh set
of draws (seed + 1) checks the refined emulator: the coverage it reports was not used to fit it.
If that coverage is still off, the next round (refined_2/, seed + 2) trains on and cross-validates
over every check run so far, up to check.rounds refined rounds. check.variance: "scale" multiplies
the emulator's own variance, "floor" adds one that more runs do not shrink, "wider" (default) takes
the wider of the two (`calibrate_variance`). Measured on the
default-mesh study calibration with "scale": DY stayed at 0.78 (25 of 32 fresh draws) in both refined
rounds, its errors at the fresh draws ~3x the refined GP's sd: the GP had just been trained on runs
among those draws, so its variance there had shrunk while its error (tied to parameters it treats as
inert) had not.
"""

import hashlib
import time
from pathlib import Path

import numpy as np

from .emulator import fit_emulator
from .posterior import LogPosterior, UnboundedPosterior, diagnostics, run_sampler
from .posterior_report import check_draws, coverage, plot_corner, predictive, widths
from .runlog import check_fingerprint, load_records, records_arrays
from .tire_calibration import HISTORY
from ..errors import ConfigError
from .simulator import check_batch, pieces
from ..io import append_jsonl, atomic_write_csv, atomic_write_json, atomic_write_text, read_jsonl

__all__ = ["run_posterior", "training_data", "start_walkers", "usable", "discrepancy_sd",
           "calibrate_variance", "held_out_residuals", "variance_correction", "conformal_scale",
           "conformal_floor", "band_chance", "COVERAGE_OK"]

COVERAGE_OK = (0.80, 0.97)  # the band a 90 % interval's observed coverage over 32 draws should hit


def training_data(spec):
    """(thetas (n, d), responses (n, m)) of every simulator run in the calibration's history."""
    path = Path(spec.history) / HISTORY
    records = load_records(path)
    if not records:
        raise ConfigError(f"history = {spec.history}: no {HISTORY} with simulator runs there (run "
                          "`jtire calibrate` on the calibration config first)")
    space = spec.calibration.space
    names = set(records[0].get("params", {}))
    if names != set(space.names):
        raise ConfigError(f"history = {spec.history}: its runs vary other parameters than the "
                          "calibration config's [[free]] list")
    return records_arrays(records, [t.name for t in spec.calibration.targets])


def usable(y) -> np.ndarray:
    """Rows (n,) of responses y (n, m) that a run gave in full: every value finite and > 0 (the
    emulator models ln(response))."""
    y = np.asarray(y, float)
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(y) & (y > 0), axis=1)


def start_walkers(space, centre, walkers: int, spread: float, seed: int) -> np.ndarray:
    """(walkers, d) in a small box (spread, unit coordinates) about centre, inside the bounds."""
    rng = np.random.default_rng(seed)
    u = np.clip(space.to_unit(centre) + spread * rng.uniform(-1, 1, (walkers, space.d)), 0.0, 1.0)
    return space.from_unit(u)


def _fmt_rows(rows, keys) -> str:
    head = "| " + " | ".join(keys) + " |\n|" + "---|" * len(keys) + "\n"
    return head + "".join("| " + " | ".join(
        f"{r[k]:.5g}" if isinstance(r[k], float) else str(r[k]) for k in keys) + " |\n" for r in rows)


def discrepancy_sd(kind: str, targets, y) -> np.ndarray:
    """(m,) model-discrepancy sd of ln(response): 0 ("none"), or the smallest miss
    |ln(y_i / t_i)| over the runs y (n, m) ("best_miss", see the module docstring)."""
    m = len(targets)
    if kind == "none":
        return np.zeros(m)
    meas = np.array([t.measured for t in targets])
    with np.errstate(invalid="ignore", divide="ignore"):
        miss = np.abs(np.log(np.asarray(y, float) / meas))
    miss = np.where(np.isfinite(miss), miss, np.inf)
    out = np.min(miss, axis=0)
    return np.where(np.isfinite(out), out, 0.0)


def calibrate_variance(spec, thetas, y, extra_thetas, extra_y, level: float = 0.9,
                       form: str = "floor") -> tuple:
    """Per-response corrections of the predictive variance of an emulator trained on (thetas, y)
    plus the runs (extra_thetas, extra_y), by k-fold cross-validation over the extra runs only:
    each fold is predicted by an emulator trained on everything else, and the correction is split-
    conformal: a new run falls inside the corrected `level` interval with probability >= level.

    form "scale": variance v -> a v (`conformal_scale`). form "floor": v -> v + b, b >= 0
    (`conformal_floor`): an error that more runs do not shrink. form "wider": the wider of the two at
    each point, max(a v, v + b). Where the emulator is already wide enough (a <= 1) every form narrows
    it to a v. Why not the factor alone: each refined emulator trains on the runs it was checked on,
    so its own variance at the next draws (which land among them) is smaller than it was at the
    held-out runs, and a factor shrinks with it where the error (tied to parameters the emulator
    treats as inert) does not. Why not the floor alone: part of the held-out error is the
    emulator's own, which the added runs do remove. The held-out runs of one round cannot tell the
    two apart (measured on the default-mesh study: a maximum-likelihood fit of v -> a v + b to them
    put the error wholly in one part or the other from round to round), so "wider" keeps the split-
    conformal guarantee under either: it is the conservative choice.

    Returns (a (m,), b (m,), z (k, m) held-out residuals in units of the uncorrected sd)."""
    r, v = held_out_residuals(spec, thetas, y, extra_thetas, extra_y)
    a, b = variance_correction(r, v, level, form)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = r / np.sqrt(v)
    return a, b, z


def held_out_residuals(spec, thetas, y, extra_thetas, extra_y) -> tuple:
    """k-fold held-out ln residuals r (k, m) and predictive variances v (k, m) of the extra runs:
    each fold (spec.check folds, seeded) predicted by an emulator trained on (thetas, y) and the
    other folds."""
    cal = spec.calibration
    names = [t.name for t in cal.targets]
    k = len(extra_thetas)
    folds = np.array_split(np.random.default_rng(spec.check["seed"]).permutation(k),
                           min(spec.check["folds"], k))
    r = np.full((k, len(names)), np.nan)
    v = np.full((k, len(names)), np.nan)
    for f in folds:
        rest = np.setdiff1d(np.arange(k), f)
        emu = fit_emulator(cal.space, names, np.vstack([thetas, extra_thetas[rest]]),
                           np.vstack([y, extra_y[rest]]), spec.candidates, spec.emulator_seed)
        mu, var = emu.predict(extra_thetas[f])
        with np.errstate(invalid="ignore", divide="ignore"):
            r[f], v[f] = np.log(extra_y[f]) - mu, var
    return r, v


def variance_correction(r, v, level: float = 0.9, form: str = "floor") -> tuple:
    """(a (m,), b (m,)) of `calibrate_variance`'s form from held-out residuals r and variances v (k, m)."""
    if form not in ("scale", "floor", "wider"):
        raise ValueError(f"form = {form!r}: 'scale', 'floor' or 'wider'")
    with np.errstate(invalid="ignore", divide="ignore"):
        z = r / np.sqrt(v)
    m = r.shape[1]
    a = np.clip([conformal_scale(z[:, j], level) for j in range(m)], 1e-4, 1e6)
    b = np.zeros(m)
    for j in range(m):
        if form != "scale" and a[j] > 1.0:
            b[j] = conformal_floor(r[:, j], v[:, j], level)
            a[j] = 1.0 if form == "floor" else a[j]
    return np.asarray(a, float), b


def conformal_floor(r, v, level: float = 0.9) -> float:
    """The smallest b >= 0 with which held-out residuals r (n,) of predictive variances v (n,) give
    split-conformal coverage: the k-th smallest |r_i| / sqrt(v_i + b), k = ceil((n + 1) level), equals
    the normal interval's half-width (each score falls as b grows, so bisection). With n < 1/(1 - level)
    - 1 runs the largest score is used; fewer than 2 finite runs, or scores already inside: 0."""
    from scipy import stats

    r, v = np.asarray(r, float), np.asarray(v, float)
    ok = np.isfinite(r) & np.isfinite(v) & (v >= 0)
    r, v = np.abs(r[ok]), v[ok]
    if len(r) < 2:
        return 0.0
    k = min(int(np.ceil((len(r) + 1) * level)), len(r))
    zq = float(stats.norm.ppf(0.5 + level / 2))

    def score(b):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.sort(np.where(r > 0, r / np.sqrt(v + b), 0.0))[k - 1]

    if score(0.0) <= zq:
        return 0.0
    lo, hi = 0.0, float(np.max(r) / zq) ** 2  # at hi every score is <= zq
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if score(mid) <= zq else (mid, hi)
    return hi


def band_chance(n_cal: int, n_test: int, level: float = 0.9, band=COVERAGE_OK) -> float:
    """Chance that an interval made exactly valid by split conformal on n_cal exchangeable held-out
    runs shows an observed coverage inside `band` on n_test fresh draws.

    Its true coverage is Beta(k, n_cal + 1 - k), k = ceil((n_cal + 1) level) (the k-th smallest of
    n_cal + 1 exchangeable scores; `conformal_scale`), so the count inside is beta-binomial. 32
    held-out runs, 32 draws, 80-97 %: 0.81 per response, ~0.42 for four independent responses.
    What the check's band can tell: a miss is not by itself proof of a bad correction."""
    from scipy import stats

    n_cal, n_test = int(n_cal), int(n_test)
    if n_cal < 1 or n_test < 1:
        return float("nan")
    k = min(int(np.ceil((n_cal + 1) * level)), n_cal)
    x = np.arange(n_test + 1)
    ok = (x / n_test >= band[0]) & (x / n_test <= band[1])
    return float(stats.betabinom.pmf(x[ok], n_test, k, n_cal + 1 - k).sum())


def conformal_scale(z, level: float = 0.9) -> float:
    """Factor on a predictive variance from held-out standardized residuals z (n,), by split
    conformal prediction: the interval +- q sd with q the k-th smallest |z|, k = ceil((n + 1) level),
    holds a new exchangeable run with probability >= level (exactly k / (n + 1) on average), where the
    plain `level` quantile of n scores falls short by ~1/n (32 runs: the 30th smallest |z| instead of
    the 28.9th). Returned as (q / z_level)^2, z_level the normal interval's half-width. With
    n < 1/(1 - level) - 1 runs the guarantee needs more runs than there are: the largest |z| is used.
    Fewer than 2 finite scores: 1 (no information)."""
    from scipy import stats

    a = np.sort(np.abs(np.asarray(z, float)[np.isfinite(z)]))
    if len(a) < 2:
        return 1.0
    k = int(np.ceil((len(a) + 1) * level))
    q = a[min(k, len(a)) - 1]
    return float(q / stats.norm.ppf(0.5 + level / 2)) ** 2


def _round(spec, out_dir, thetas, y, disc, sim, progress, check_seed, var_scale=None, var_floor=None,
           on_check=None) -> dict:
    """One emulator + chain + reports (+ check) in out_dir."""
    cal = spec.calibration
    space, targets = cal.space, cal.targets
    digest = hashlib.sha256(np.ascontiguousarray(np.nan_to_num(np.concatenate(
        [thetas, y], axis=1), nan=-1.0)).tobytes()).hexdigest()[:16]
    fp = {**spec.fingerprint(), "training_runs": int(len(thetas)), "training_hash": digest}
    if var_scale is not None:
        fp["variance_scale"] = [float(v) for v in var_scale]
    if var_floor is not None:
        fp["variance_floor"] = [float(v) for v in var_floor]
    check_fingerprint(out_dir, fp)
    wall = {}
    t0 = time.perf_counter()
    emu = fit_emulator(space, [t.name for t in targets], thetas, y, spec.candidates,
                       spec.emulator_seed)
    if var_scale is not None:
        emu.var_scale = np.asarray(var_scale, float)
    if var_floor is not None:
        emu.var_floor = np.asarray(var_floor, float)
    atomic_write_json(out_dir / "emulator.json", emu.summary())
    wall["emulator_s"] = time.perf_counter() - t0
    sd = np.sqrt(np.asarray(spec.sigma_rel, float) ** 2 + disc**2)
    logp = LogPosterior(emu, np.log([t.measured for t in targets]), sd, space,
                        spec.prior, spec.sigma_ln)
    ok = usable(y)
    tot = np.sum(np.abs(y[ok] / np.array([t.measured for t in targets]) - 1), axis=1)
    centre = thetas[ok][int(np.argmin(tot))]
    s = spec.sampler
    p0 = start_walkers(space, centre, s["walkers"], s["init_spread"], s["seed"])
    post = logp
    if s["coordinates"] == "logit":
        post = UnboundedPosterior(logp, space)
        p0 = post.to_z(p0)
    t0 = time.perf_counter()
    res = run_sampler(post, p0, out_dir / "chain.h5", s["walkers"], s["max_steps"],
                      s["check_every"], s["n_tau"], s["seed"], progress, moves=s["moves"])
    wall["chain_s"] = time.perf_counter() - t0
    diag = diagnostics(res)
    samples = res.samples()
    if s["coordinates"] == "logit":
        samples = post.to_theta(samples)
    pred = predictive(emu, samples, targets, s["seed"])
    wid = widths(samples, space, spec.prior, spec.sigma_ln)
    atomic_write_json(out_dir / "diagnostics.json", {
        **diag, "parameters": list(space.names), "n_samples": int(len(samples)),
        "chain_coordinates": s["coordinates"], "moves": s["moves"],
        "discrepancy_sd_ln": dict(zip([t.name for t in targets], disc.tolist()))})
    keys = ["target", "what", "unit", "measured", "median", "lower", "upper"]
    atomic_write_csv(out_dir / "predictive.csv", None, {k: [r[k] for r in pred] for k in keys})
    atomic_write_text(out_dir / "predictive.md", _fmt_rows(pred, keys))
    wkeys = ["parameter", "prior_width_ln", "posterior_width_ln", "ratio", "median", "unit"]
    atomic_write_csv(out_dir / "widths.csv", None, {k: [r[k] for r in wid] for k in wkeys})
    order = list(np.argsort([r["ratio"] for r in wid]))
    plot_corner(samples, space.names, out_dir / "corner.png", order=order,
                title=f"{spec.path.name}: posterior, the {min(8, space.d)} most constrained "
                f"parameters (ln of SI values)")
    out = {"result": res, "diagnostics": diag, "predictive": pred, "widths": wid,
           "emulator": emu, "samples": samples, "sigma_sources": spec.sigma_sources,
           "discrepancy": disc, "out": out_dir, "wall": wall}
    if sim is not None:
        draws = check_draws(samples, spec.check["draws"], check_seed)
        old = _stored_check(out_dir / "check.json", draws)
        t0 = time.perf_counter()
        if old is not None:
            simulated, n_reused = old, len(draws)
        else:
            simulated, n_reused = simulate_draws(sim, draws, out_dir / "check_runs.jsonl", on_check)
        wall["check_s"] = time.perf_counter() - t0
        chk = coverage(emu, draws, simulated)
        # the file holds results only (a resumed run writes the same bytes); how this run got them
        # (stored or simulated, and how long it took) is in the returned dict and printed
        atomic_write_json(out_dir / "check.json", chk)
        out["check"] = {**chk, "reused": n_reused}
    return out


def simulate_draws(sim, draws, path: Path, on_check=None) -> tuple:
    """Responses (n, m) of the draws (n, d), and how many of them came from `path`.

    The draws go to the simulator in pieces of its points_per_call; each returned row is appended
    to `path` at once (JSON lines {"i", "theta", "y"}), so a killed check loses at most the piece in
    flight. Rows already in `path` for the same draw (same index, bit-identical theta: JSON keeps
    a float exactly) are reused. on_check(done, total, n_reused) reports progress.
    """
    draws = np.asarray(draws, float)
    n, m = len(draws), len(sim.response_names)
    y = np.full((n, m), np.nan)
    have = np.zeros(n, bool)
    for rec in read_jsonl(path):
        try:
            i, th = int(rec["i"]), np.asarray(rec["theta"], float)
            row = np.array([np.nan if v is None else v for v in rec["y"]], float)
        except (KeyError, TypeError, ValueError):
            continue
        if 0 <= i < n and th.shape == draws[i].shape and np.array_equal(th, draws[i]) and row.shape == (m,):
            y[i], have[i] = row, True
    n_reused = int(have.sum())
    todo = np.flatnonzero(~have)
    if on_check is not None:
        on_check(n_reused, n, n_reused)
    for a, b in pieces(sim, len(todo)):
        idx = todo[a:b]
        vals = check_batch(sim, draws[idx], sim.evaluate(draws[idx]))
        for j, i in enumerate(idx):
            y[i] = vals[j]
            append_jsonl(path, {"i": int(i), "theta": draws[i].tolist(),
                                "y": [float(v) if np.isfinite(v) else None for v in vals[j]]})
        if on_check is not None:
            on_check(n_reused + b, n, n_reused)
    return y, n_reused


def _stored_check(path: Path, draws):
    """The simulated responses of a stored check.json made on exactly these draws, else None."""
    import json

    try:
        old = json.loads(path.read_text())
        th, ys = np.asarray(old["thetas"], float), np.asarray(old["simulated"], float)
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if th.shape == draws.shape and np.array_equal(th, draws) and ys.shape[0] == len(draws):
        return ys
    return None


def _off(chk) -> bool:
    lo, hi = COVERAGE_OK
    return any(not (lo <= v <= hi) for v in chk["coverage"].values())


def refined_dir(out_dir: Path, k: int) -> Path:
    """Folder of refined round k (1, 2, ...): OUT/refined, OUT/refined_2, ..."""
    return Path(out_dir) / ("refined" if k == 1 else f"refined_{k}")


def run_posterior(spec, out_dir, sim=None, progress=None, on_check=None) -> dict:
    """Fit the emulator, run or resume the chain, write every output (and with a simulator, the
    check; while the check's coverage is off, up to check.rounds refined rounds, each in its own
    folder: `refined_dir`). Returns the first round's summary dict with "rounds" (every round's,
    first included) and "refined" (the last refined round's, if any)."""
    out_dir = Path(out_dir)
    cal = spec.calibration
    thetas, y = training_data(spec)
    disc = discrepancy_sd(spec.discrepancy, cal.targets, y)
    out = _round(spec, out_dir, thetas, y, disc, sim, progress, spec.check["seed"], on_check=on_check)
    rounds = [out]
    ex_t, ex_y = np.empty((0, thetas.shape[1])), np.empty((0, y.shape[1]))
    n_rounds = spec.check["rounds"] if spec.check["refine"] else 0
    for k in range(1, n_rounds + 1):
        chk = rounds[-1].get("check")
        if chk is None or not _off(chk):
            break
        # every check run so far joins the training set and the cross-validation: the runs a
        # round's check added are where the previous emulator was wrong
        good = usable(chk["simulated"])
        ex_t, ex_y = np.vstack([ex_t, chk["thetas"][good]]), np.vstack([ex_y, chk["simulated"][good]])
        if len(ex_t) < 2:
            break
        scale, floor, z = calibrate_variance(spec, thetas, y, ex_t, ex_y, form=spec.check["variance"])
        ref = _round(spec, refined_dir(out_dir, k), np.vstack([thetas, ex_t]), np.vstack([y, ex_y]), disc,
                     sim, progress, spec.check["seed"] + k, var_scale=scale, var_floor=floor,
                     on_check=on_check)
        ref["kfold_z"] = z
        ref["n_check_runs"] = len(ex_t)
        rounds.append(ref)
    out["rounds"] = rounds
    if len(rounds) > 1:
        out["refined"] = rounds[-1]
    return out
