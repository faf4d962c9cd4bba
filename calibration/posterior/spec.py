"""Posterior configs (configs/calibration/posterior.toml) -> a validated `PosteriorSpec`.

    calibration = "study.toml"        # calibration config (relative to this file): free parameters,
                                      # bounds, targets
    history = "runs/calibrate/study"  # that calibration's output folder (relative to the current
                                      # folder, like --out): its history.jsonl trains the emulator
    [prior]      kind = "log_uniform" | "log_normal", sigma_ln = 0.5 (log_normal only), why
    [uncertainty.NAME]  relative = 0.05 | from = "track_scatter" | "track_trend";  why = "..."
    [discrepancy] kind = "best_miss" | "none";  why = "..."
    [emulator]   candidates = ["linear", "reduced", "full", "gp"], seed
    [sampler]    walkers, max_steps, check_every, n_tau, seed, init_spread,
                 moves = "de" | "stretch", coordinates = "logit" | "log"
    [check]      draws, seed, refine = true | false, folds, rounds (refined rounds at most),
                 variance = "wider" | "floor" | "scale" (how the held-out runs correct the predictive variance:
                 calibration.posterior.conformal.calibrate_variance)
"""

import dataclasses
import math
from pathlib import Path

from ...schema import Field as F
from ...config import apply_overrides, load_toml, validate_table
from ...errors import ConfigError
from .emulator import CANDIDATES
from .model import MOVES
from ..tire.spec import load_calibration

__all__ = ["PosteriorSpec", "load_posterior", "PRIORS", "SAMPLER_SCHEMA"]

PRIORS = ("log_uniform", "log_normal")
DISCREPANCY = ("best_miss", "none")
COORDINATES = ("logit", "log")
VARIANCE_FORMS = ("wider", "floor", "scale")
UNCERTAINTY_FROM = ("track_scatter", "track_trend")
TOP_KEYS = {"calibration", "history", "description", "prior", "uncertainty", "discrepancy",
            "emulator", "sampler", "check"}
SAMPLER_SCHEMA = {
    "walkers": F(int, 1, 4, 100000, 64),
    "max_steps": F(int, 1, 10, 10**8, 20000, "steps"),
    "check_every": F(int, 1, 10, 10**7, 500, "steps"),
    "n_tau": F(float, 1, 1, 1e4, 50.0, "autocorrelation times"),
    "seed": F(int, 1, 0, 2**31 - 1, 0),
    "init_spread": F(float, 1, 1e-8, 1, 1e-3, "(unit box)"),
}
CHECK_SCHEMA = {"draws": F(int, 1, 1, 100000, 32), "seed": F(int, 1, 0, 2**31 - 1, 0),
                "folds": F(int, 1, 2, 1000, 4), "rounds": F(int, 1, 1, 10, 2, "refined rounds at most")}


@dataclasses.dataclass(frozen=True)
class PosteriorSpec:
    """path; calibration: CalibrationSpec; history: folder; prior: "log_uniform"/"log_normal";
    sigma_ln: sd of ln p of the log-normal prior; sigma_rel: (m,) measurement sd relative to each
    target; sigma_sources: (m,) where each comes from; discrepancy: "best_miss" or "none";
    candidates; emulator_seed; sampler, check: option dicts (sampler["moves"],
    sampler["coordinates"], check["refine"] and check["variance"] included); raw: the config after overrides."""

    path: Path
    calibration: object
    history: Path
    prior: str
    sigma_ln: float
    sigma_rel: tuple
    sigma_sources: tuple
    candidates: tuple
    emulator_seed: int
    discrepancy: str
    sampler: dict
    check: dict
    raw: dict

    def fingerprint(self) -> dict:
        """What fixes the chain (max_steps excluded: a budget may grow)."""
        return {"calibration": self.calibration.fingerprint(), "prior": self.prior,
                "sigma_ln": self.sigma_ln, "sigma_rel": list(self.sigma_rel),
                "discrepancy": self.discrepancy,
                "candidates": list(self.candidates), "emulator_seed": self.emulator_seed,
                "sampler": {k: v for k, v in self.sampler.items() if k != "max_steps"}}


def _num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _pop_choices(table, name: str, choices: dict):
    """(the table without them, {key: value}) for the non-numeric fields {key: (allowed, default)}
    of a table whose numeric fields a schema checks."""
    if not isinstance(table, dict):
        return table, {}  # validate_table says what is wrong with it
    table, out = dict(table), {}
    for key, (allowed, default) in choices.items():
        v = table.pop(key, default)
        if type(v) is not type(default) or v not in allowed:
            what = "true or false" if isinstance(default, bool) else f"one of {allowed}"
            raise ConfigError(f"{name}.{key} = {v!r}: must be {what}")
        out[key] = v
    return table, out


def _track_sigma(target, kind: str) -> tuple:
    from ...data import analyze

    load = target.condition.get("load_N")
    if target.quantity != "rolling_resistance_N" or load is None:
        raise ConfigError(f"uncertainty.{target.name}.from = {kind!r}: only for a rolling-"
                          "resistance force at a stated load")
    p = analyze().fits["track_120psi"].linear.predict(load)
    se = float(p.se_obs[0] if kind == "track_scatter" else p.se[0]) * load
    what = "one run about" if kind == "track_scatter" else "the mean of"
    return se / target.measured, (f"{kind}: sd of {what} the 120 psi linear track trend at "
                                  f"{load / 1e3:g} kN = {se:.4g} N (jtire data)")


def load_posterior(path, overrides=()) -> PosteriorSpec:
    """Read and validate a posterior config (+ `--set` overrides; `calibration.` ones are not
    supported: edit the calibration config)."""
    path = Path(path)
    raw = apply_overrides(load_toml(path), overrides)
    for key in raw:
        if key not in TOP_KEYS:
            raise ConfigError(f"{key}: unknown field (allowed: {', '.join(sorted(TOP_KEYS))})")
    if not isinstance(raw.get("calibration"), str):
        raise ConfigError("calibration: missing (the calibration config, relative to this file)")
    cal = load_calibration((path.parent / raw["calibration"]).resolve())
    if not isinstance(raw.get("history"), str):
        raise ConfigError("history: missing (the calibration's output folder holding history.jsonl)")
    prior = raw.get("prior", {})
    if not isinstance(prior, dict):
        raise ConfigError("prior: must be a table")
    kind = prior.get("kind", "log_uniform")
    if kind not in PRIORS:
        raise ConfigError(f"prior.kind = {kind!r}: must be one of {PRIORS}")
    sigma_ln = prior.get("sigma_ln", 0.5)
    if not (_num(sigma_ln) and 0 < sigma_ln <= 10):
        raise ConfigError(f"prior.sigma_ln = {sigma_ln!r}: must be in (0, 10] (sd of ln p)")
    unc = raw.get("uncertainty", {})
    if not isinstance(unc, dict):
        raise ConfigError("uncertainty: must be a table of [uncertainty.TARGET] tables")
    names = [t.name for t in cal.targets]
    for k in unc:
        if k not in names:
            raise ConfigError(f"uncertainty.{k}: no such target (targets: {', '.join(names)})")
    sig, src = [], []
    for t in cal.targets:
        u = unc.get(t.name)
        at = f"uncertainty.{t.name}"
        if not isinstance(u, dict) or ("relative" in u) == ("from" in u):
            raise ConfigError(f"{at}: give exactly one of relative = number in (0, 1] or from = "
                              f"one of {UNCERTAINTY_FROM}")
        for key in u:
            if key not in ("relative", "from", "why"):
                raise ConfigError(f"{at}.{key}: unknown field (allowed: relative, from, why)")
        if "relative" in u:
            if not (_num(u["relative"]) and 0 < u["relative"] <= 1):
                raise ConfigError(f"{at}.relative = {u['relative']!r}: must be in (0, 1]")
            sig.append(float(u["relative"])), src.append(f"relative {u['relative']:g} (config)")
        else:
            if u["from"] not in UNCERTAINTY_FROM:
                raise ConfigError(f"{at}.from = {u['from']!r}: must be one of {UNCERTAINTY_FROM}")
            s, what = _track_sigma(t, u["from"])
            sig.append(s), src.append(what)
    em = raw.get("emulator", {})
    if not isinstance(em, dict) or any(k not in ("candidates", "seed") for k in em):
        raise ConfigError("emulator: allowed fields candidates, seed")
    cands = em.get("candidates", list(CANDIDATES))
    if not (isinstance(cands, list) and cands and all(c in CANDIDATES for c in cands)):
        raise ConfigError(f"emulator.candidates = {cands!r}: a non-empty list from {CANDIDATES}")
    eseed = em.get("seed", 0)
    if not (isinstance(eseed, int) and not isinstance(eseed, bool) and eseed >= 0):
        raise ConfigError(f"emulator.seed = {eseed!r}: must be an integer >= 0")
    disc = raw.get("discrepancy", {})
    if not isinstance(disc, dict) or any(k not in ("kind", "why") for k in disc):
        raise ConfigError("discrepancy: a table with fields kind, why")
    dkind = disc.get("kind", "none")
    if dkind not in DISCREPANCY:
        raise ConfigError(f"discrepancy.kind = {dkind!r}: must be one of {DISCREPANCY}")
    sraw, choices = _pop_choices(raw.get("sampler", {}), "sampler",
                                 {"moves": (MOVES, "de"), "coordinates": (COORDINATES, "logit")})
    sampler = {**validate_table(sraw, SAMPLER_SCHEMA, "sampler"), **choices}
    d = cal.space.d
    if sampler["walkers"] < 2 * d or sampler["walkers"] % 2:
        raise ConfigError(f"sampler.walkers = {sampler['walkers']}: must be even and >= 2 x the "
                          f"{d} free parameters = {2 * d} (emcee's stretch move)")
    if sampler["check_every"] > sampler["max_steps"]:
        raise ConfigError(f"sampler.check_every = {sampler['check_every']}: must be <= "
                          f"sampler.max_steps = {sampler['max_steps']}")
    craw, refine = _pop_choices(raw.get("check", {}), "check", {"refine": ((True, False), True),
                                                               "variance": (VARIANCE_FORMS, "wider")})
    check = {**validate_table(craw, CHECK_SCHEMA, "check"), **refine}
    if check["refine"] and check["folds"] > check["draws"]:
        raise ConfigError(f"check.folds = {check['folds']}: must be <= check.draws = {check['draws']}")
    return PosteriorSpec(path=path, calibration=cal, history=Path(raw["history"]), prior=kind,
                         sigma_ln=float(sigma_ln), sigma_rel=tuple(sig), sigma_sources=tuple(src),
                         candidates=tuple(cands), emulator_seed=int(eseed), discrepancy=dkind,
                         sampler=sampler,
                         check=check, raw=raw)
