"""Run the posterior end to end (what `jtire sample` calls): emulator, chain, reports, check.

Output folder: fingerprint.json (the posterior config, the calibration's fingerprint and a hash
of the emulator's training runs: a rerun with other settings refuses), chain.h5 (emcee's HDF5
layout, written whole when the chain stops; while it runs, chain.h5.chunks/ holds each finished
chunk: a killed run resumes from it when rerun), emulator.json (LOO errors of every candidate, the choice),
diagnostics.json, predictive.csv/.md, widths.csv, corner.png, check.json (simulator check).
"""

import hashlib
from pathlib import Path

import numpy as np

from .emulator import fit_emulator
from .posterior import LogPosterior, diagnostics, run_sampler
from .posterior_report import plot_corner, predictive, simulator_check, widths
from .runlog import check_fingerprint, load_records, records_arrays
from .tire_calibration import HISTORY
from ..errors import ConfigError
from ..io import atomic_write_csv, atomic_write_json, atomic_write_text

__all__ = ["run_posterior", "training_data", "start_walkers"]


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


def run_posterior(spec, out_dir, sim=None, progress=None) -> dict:
    """Fit the emulator, run or resume the chain, write every output; returns a summary dict."""
    out_dir = Path(out_dir)
    cal = spec.calibration
    space, targets = cal.space, cal.targets
    thetas, y = training_data(spec)
    digest = hashlib.sha256(np.ascontiguousarray(np.nan_to_num(np.concatenate(
        [thetas, y], axis=1), nan=-1.0)).tobytes()).hexdigest()[:16]
    check_fingerprint(out_dir, {**spec.fingerprint(), "training_runs": int(len(thetas)),
                                "training_hash": digest})
    emu = fit_emulator(space, [t.name for t in targets], thetas, y, spec.candidates,
                       spec.emulator_seed)
    atomic_write_json(out_dir / "emulator.json", emu.summary())
    logp = LogPosterior(emu, np.log([t.measured for t in targets]), spec.sigma_rel, space,
                        spec.prior, spec.sigma_ln)
    ok = np.all(np.isfinite(y) & (y > 0), axis=1)
    tot = np.sum(np.abs(y[ok] / np.array([t.measured for t in targets]) - 1), axis=1)
    centre = thetas[ok][int(np.argmin(tot))]
    s = spec.sampler
    p0 = start_walkers(space, centre, s["walkers"], s["init_spread"], s["seed"])
    res = run_sampler(logp, p0, out_dir / "chain.h5", s["walkers"], s["max_steps"],
                      s["check_every"], s["n_tau"], s["seed"], progress)
    diag = diagnostics(res)
    samples = res.samples()
    pred = predictive(emu, samples, targets, s["seed"])
    wid = widths(samples, space, spec.prior, spec.sigma_ln)
    atomic_write_json(out_dir / "diagnostics.json", {**diag, "parameters": list(space.names),
                                                     "n_samples": int(len(samples))})
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
           "emulator": emu, "samples": samples, "sigma_sources": spec.sigma_sources}
    if sim is not None:
        chk = simulator_check(sim, emu, samples, spec.check["draws"], spec.check["seed"])
        atomic_write_json(out_dir / "check.json", chk)
        out["check"] = chk
    return out
