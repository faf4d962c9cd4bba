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
precise, wrong tire (the study calibration did: docs/design-notes.md). Per target i the discrepancy
sd is the smallest miss |ln(y_i / t_i)| over every simulator run of the calibration: the model
demonstrably comes that close and no closer, so a residual of that size is put down to the model,
not the parameters. It adds to the measurement variance; for a reachable target it is ~0.

Refinement (check.refine, check.rounds): if the simulator check finds the emulator's 90 % intervals
covering fewer than 80 % or more than 97 % of the draws of some response, the check's runs (posterior
draws, where the emulator matters) join the training set, the emulator's predictive variance is
corrected per response by k-fold cross-validation over those draws (`conformal.calibrate_variance`, split-
conformal, so that a new run falls inside the 90 % interval with probability >= 90 %; the plain 90 %
quantile of 32 held-out scores falls short by ~1/32), the chain is rerun in refined/, and a fresh set
of draws (seed + 1) checks the refined emulator: the coverage it reports was not used to fit it.
If that coverage is still off, the next round (refined_2/, seed + 2) trains on and cross-validates
over every check run so far, up to check.rounds refined rounds. check.variance: "scale" multiplies
the emulator's own variance, "floor" adds one that more runs do not shrink, "wider" (default) takes
the wider of the two (`conformal.calibrate_variance`). "scale" alone can stay off round after round:
a refined GP has just been trained on runs among the next draws, so its variance there shrinks while
its error (tied to parameters it treats as inert) does not (docs/design-notes.md).
"""

import hashlib
import time
from pathlib import Path

import numpy as np

from .conformal import COVERAGE_OK, calibrate_variance
from .emulator import fit_emulator, usable
from .model import LogPosterior, UnboundedPosterior, diagnostics, run_sampler
from .report import check_draws, coverage, plot_corner, predictive, widths
from ..tire.runlog import check_fingerprint, load_records, records_arrays
from ..tire.run import HISTORY
from ...errors import ConfigError
from ..tire.simulator import check_batch, pieces
from ...io import append_jsonl, atomic_write_csv, atomic_write_json, atomic_write_text, read_jsonl

__all__ = ["run_posterior", "training_data", "start_walkers", "discrepancy_sd", "simulate_draws",
           "refined_dir"]


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
    pred = predictive(emu, samples, targets, s["seed"], space=space)
    wid = widths(samples, space, spec.prior, spec.sigma_ln)
    atomic_write_json(out_dir / "diagnostics.json", {
        **diag, "parameters": list(space.names), "n_samples": int(len(samples)),
        "chain_coordinates": s["coordinates"], "moves": s["moves"],
        "discrepancy_sd_ln": dict(zip([t.name for t in targets], disc.tolist()))})
    keys = ["target", "what", "unit", "measured", "median", "lower", "upper"]
    atomic_write_csv(out_dir / "predictive.csv", None, {k: [r[k] for r in pred] for k in keys})
    atomic_write_text(out_dir / "predictive.md", _fmt_rows(pred, keys))
    wkeys = ["parameter", "prior_width_ln", "posterior_width_ln", "ratio", "median", "lower", "upper", "unit"]
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
