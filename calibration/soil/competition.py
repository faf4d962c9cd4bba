"""`jtire compete CONFIG`: the study's optimizer competition on the soil block (section 4.2).

ARSM, a genetic algorithm and Monte Carlo search each tune soil density and Young's modulus so
that the simulated plate sinkage matches Bekker's law, over many seeds with the same bounds and
call budget. Outputs in --out: histories/ (one JSON-lines file per method and seed: a killed
competition resumes where it stopped), runs.csv (every call of every run, numbered from 1;
the history files number them from 0), summary.csv (per
method: final error, calls to reach each threshold), progression.png (the study's Figure 4-2:
best error so far against calls, median and quartiles over seeds).

The competition logic takes the objective as an argument (`run_competition`), so it runs just
as well on the closed-form stand-in used by the quick checks (`standin_objective`). The FE plate
test compiles once and is then cheap per call (its cost: docs/design-notes.md); stop the
competition at any time and run the same command again.
"""

import dataclasses
import inspect
import json
import math
import typing
from pathlib import Path

import numpy as np
from tqdm import tqdm

from .. import arsm
from . import baselines
from ...schema import Field, validate
from ...config import read_toml
from ...errors import ConfigError
from ...io import atomic_write_json, remove_stale_temps

__all__ = ["METHODS", "CompetitionSpec", "load_config", "soil_objective", "standin_objective",
           "fingerprint", "run_competition"]  # the results: competition_report.py

METHODS = {
    "arsm": arsm.minimize,
    "srsm": lambda *a, **k: arsm.minimize(*a, region_rule="srsm", **k),
    "ga": baselines.genetic_algorithm,
    "mc": baselines.monte_carlo,
    "mc_lhs": baselines.latin_hypercube_search,
}
LABELS = {"arsm": "ARSM", "srsm": "SRSM", "ga": "GA (pymoo)", "mc": "Monte Carlo",
          "mc_lhs": "Monte Carlo (LHS)"}
VARIABLES = ("density_kg_m3", "youngs_modulus_Pa")
QUICK_SEEDS, QUICK_BUDGET = 3, 20


TOP_KEYS = ("description", "soil", "bounds", "competition")
COMPETITION_SCHEMA = {
    "seeds": Field(int, 1, 1, 10000, 20, "seeds per method"),
    "budget": Field(int, 1, 5, 100000, 50, "calls per run"),
    "thresholds_percent": Field(list, 1, 1e-9, 1e4, [0.66, 0.18], "% sinkage error"),
}
COMPETITION_TABLES = ("methods", "options", "anchor")


class _Probe(BaseException):
    """Raised by the probe objective at its first call: the method got past its own checks (and,
    on a history, past every replayed call). BaseException so that no method swallows it."""


def _probe(x):
    raise _Probe


def _check_option_types(method, kw) -> None:
    """Option values against the types of the method's signature (booleans are not numbers)."""
    sig = inspect.signature(_target(method)).parameters
    allowed = set(sig) - {"fun", "lower", "upper", "budget", "seed", "history_path", "region_rule"}
    for k, v in kw.items():
        where = f"competition.options.{method}.{k}"
        if k not in allowed:
            raise ConfigError(f"{where}: unknown; allowed: {', '.join(sorted(allowed)) or 'none'}")
        ann = sig[k].annotation
        kinds = tuple(a for a in typing.get_args(ann) if a is not type(None)) or (ann,)
        if int in kinds and float not in kinds:
            ok, what = isinstance(v, int) and not isinstance(v, bool), "an integer"
        elif float in kinds:
            ok, what = _is_num(v), "a finite number"
        elif str in kinds:
            ok, what = isinstance(v, str), "a string"
        else:  # pragma: no cover (every option of the shipped methods is typed)
            ok, what = True, ""
        if not ok:
            raise ConfigError(f"{where} = {v!r}: must be {what}")


@dataclasses.dataclass(frozen=True)
class CompetitionSpec:
    """The [bounds] and [competition] tables (SI).

    lower, upper: (2,) bounds of [density kg/m^3, Young's modulus Pa]; thresholds: errors in
    percent; options: method -> keyword arguments of its minimize; anchors: method -> the
    study's single run {"error_percent", "calls"}.
    """

    methods: tuple
    seeds: int
    budget: int
    thresholds: tuple
    lower: np.ndarray
    upper: np.ndarray
    options: dict
    anchors: dict

    @classmethod
    def from_config(cls, cfg: dict) -> "CompetitionSpec":
        """Validate the whole config (every table and key, the [soil] table too) and build the
        spec. Each method is then started once on a probe objective that stops at its first
        call, so an option value the method refuses (e.g. a GA population above the budget) is
        refused here, before any run, not after the other methods have run."""
        if not isinstance(cfg, dict):
            raise ConfigError("config: must be a table")
        for key in cfg:
            if key not in TOP_KEYS:
                raise ConfigError(f"{key}: unknown field (allowed: {', '.join(TOP_KEYS)})")
        if not isinstance(cfg.get("description", ""), str):
            raise ConfigError("description: must be a string")
        for key in ("soil", "bounds", "competition"):
            if not isinstance(cfg.get(key, {}), dict):
                raise ConfigError(f"{key}: must be a table")
        _soil_spec(cfg)
        comp, bounds = cfg.get("competition", {}), cfg.get("bounds", {})
        for key in bounds:
            if key not in VARIABLES:
                raise ConfigError(f"bounds.{key}: unknown field (allowed: {', '.join(VARIABLES)})")
        for name in VARIABLES:
            b = bounds.get(name)
            if not (isinstance(b, list) and len(b) == 2 and all(_is_num(v) for v in b)
                    and 0 < b[0] < b[1]):
                raise ConfigError(f"bounds.{name} = {b!r}: must be [lower, upper] with 0 < lower "
                                  "< upper (SI)")
        for key in comp:
            if key not in COMPETITION_SCHEMA and key not in COMPETITION_TABLES:
                raise ConfigError(f"competition.{key}: unknown field (allowed: "
                                  f"{', '.join([*COMPETITION_SCHEMA, *COMPETITION_TABLES])})")
        v = validate({k: comp[k] for k in COMPETITION_SCHEMA if k in comp}, COMPETITION_SCHEMA,
                     "competition.")
        methods = comp.get("methods", ["arsm", "ga", "mc"])
        if not (isinstance(methods, list) and methods and all(isinstance(m, str) for m in methods)):
            raise ConfigError(f"competition.methods = {methods!r}: must be a non-empty list of "
                              f"names from {sorted(METHODS)}")
        for m in methods:
            if m not in METHODS:
                raise ConfigError(f"competition.methods: {m!r} unknown; allowed: {sorted(METHODS)}")
        if len(set(methods)) != len(methods):
            raise ConfigError(f"competition.methods = {methods!r}: each method at most once")
        options = comp.get("options", {})
        if not isinstance(options, dict):
            raise ConfigError("competition.options: must be a table of [competition.options.METHOD] tables")
        for m, kw in options.items():
            if m not in METHODS or not isinstance(kw, dict):
                raise ConfigError(f"competition.options.{m}: must be a table for a method in "
                                  f"{sorted(METHODS)}")
            _check_option_types(m, kw)
        anchors = comp.get("anchor", {})
        if not isinstance(anchors, dict):
            raise ConfigError("competition.anchor: must be a table of METHOD = { error_percent, calls }")
        for m, a in anchors.items():
            if m not in METHODS:
                raise ConfigError(f"competition.anchor.{m}: unknown method; allowed: {sorted(METHODS)}")
            if not (isinstance(a, dict) and set(a) <= {"error_percent", "calls", "note"}
                    and _is_num(a.get("error_percent")) and a["error_percent"] >= 0
                    and _is_num(a.get("calls")) and a["calls"] >= 1
                    and isinstance(a.get("note", ""), str)):
                raise ConfigError(f"competition.anchor.{m} = {a!r}: must be a table with numbers "
                                  "error_percent >= 0 and calls >= 1 (and an optional note string)")
        thr = v["thresholds_percent"]
        if len(set(thr)) != len(thr):
            raise ConfigError(f"competition.thresholds_percent = {list(thr)}: lists a value twice")
        spec = cls(methods=tuple(methods), seeds=v["seeds"], budget=v["budget"],
                   thresholds=tuple(sorted(thr, reverse=True)),
                   lower=np.array([float(bounds[n][0]) for n in VARIABLES]),
                   upper=np.array([float(bounds[n][1]) for n in VARIABLES]),
                   options={m: dict(kw) for m, kw in options.items()}, anchors=dict(anchors))
        for m in spec.methods:  # the method's own checks of its options, before anything runs
            try:
                METHODS[m](_probe, spec.lower, spec.upper, spec.budget, 0, history_path=None,
                           **spec.options.get(m, {}))
            except _Probe:
                pass
            except ConfigError as e:
                raise ConfigError(f"competition.options.{m}: {e}") from None
        return spec


def _is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _target(method):
    return arsm.minimize if method == "srsm" else METHODS[method]


def _soil_spec(cfg: dict):
    from . import block as soil  # the soil model's spec (its checks); the FE solve is built only when run

    table = cfg.get("soil", {})
    if not isinstance(table, dict):
        raise ConfigError("soil: must be a table")
    return soil.SoilSpec.from_config(table)


def load_config(path) -> dict:
    """The competition TOML as a dict (one-line ConfigError if missing, a folder, not UTF-8 or
    not TOML; the tables are validated by `CompetitionSpec.from_config`)."""
    return read_toml(path, "competition config")


def soil_objective(cfg: dict):
    """The study's objective: |simulated - Bekker sinkage| / Bekker sinkage * 100 (percent)."""
    from . import block as soil  # the finite-element model; imported only when used

    return soil.sinkage_objective(_soil_spec(cfg))


def standin_objective(cfg: dict):
    """Closed-form STAND-IN for the soil model, for quick checks only (not physics).

    It keeps the structure of the finite-element model's answer: sinkage exactly proportional
    to 1/E (perfect plasticity, E-independent pre-stress) and weakly decreasing with density,
    z = S0 (rho / 1200)^-0.25 / E with S0 = 44.5 kN/m (the FE model's value at 1200 kg/m^3
    within a few percent), so the error surface has the same valley E*(rho).
    """
    target = _soil_spec(cfg).target_sinkage_m  # the Bekker target (closed form)

    def objective(x) -> float:
        z = 44.5e3 * (x[0] / 1200.0) ** -0.25 / x[1]
        return abs(z - target) / target * 100.0

    return objective


def fingerprint(cfg: dict, objective: str) -> dict:
    """What makes two competitions the same problem (seeds and budget may grow on resume)."""
    comp = cfg.get("competition", {})
    return {"objective": objective, "soil": cfg.get("soil", {}), "bounds": cfg.get("bounds", {}),
            "options": comp.get("options", {})}


def _history_path(out_dir, method, seed):
    return Path(out_dir) / "histories" / f"{method}_seed{seed:03d}.jsonl"


def _check_out_dir(out_dir, fingerprint):
    """A resumed competition must be the same problem: histories hold values, not the settings
    that produced them (Monte Carlo asks for the same x whatever the objective)."""
    path = Path(out_dir) / "competition.json"
    fingerprint = json.loads(json.dumps(fingerprint))  # the form it has once read back
    if path.exists():
        old = json.loads(path.read_text())
        if old != fingerprint:
            keys = sorted(k for k in set(old) | set(fingerprint)
                          if old.get(k) != fingerprint.get(k))
            raise ConfigError(f"--out {out_dir}: holds a competition with other {', '.join(keys)}; "
                              "use another folder")
        remove_stale_temps(out_dir)  # a resume: drop the temporary files of a write a kill interrupted
    else:
        atomic_write_json(path, fingerprint)


def _from_history(method, seed, spec, out_dir):
    """Replay a run's history through its method without calling the objective: the finished
    OptimizeResult if the history completes the run, None if the run needs more calls (or has no
    history yet). A history that does not replay (other settings) is a ConfigError here."""
    path = _history_path(out_dir, method, seed)
    if not path.exists():
        return None
    try:
        return METHODS[method](_probe, spec.lower, spec.upper, spec.budget, seed, history_path=path,
                               **spec.options.get(method, {}))
    except _Probe:
        return None


def run_competition(objective, spec: CompetitionSpec, out_dir, progress: bool = True,
                    fingerprint: dict | None = None) -> dict:
    """Run every method over seeds 0 .. spec.seeds - 1; returns {method: [OptimizeResult]}.

    Each run appends to its own history file under out_dir/histories, so calling this again
    after a kill replays the finished calls and completes the rest. Every history is replayed
    first, before any new call, so a folder whose histories belong to other settings (a budget
    that changes a method's path, edited files) is refused at once, not after other runs.
    fingerprint: JSON-able description of the objective; stored in out_dir/competition.json and
    checked on resume.
    """
    if fingerprint is not None:
        _check_out_dir(out_dir, fingerprint)
    jobs = [(m, s) for m in spec.methods for s in range(spec.seeds)]
    done = {job: _from_history(*job, spec, out_dir) for job in jobs}
    # one tick per call of the budget: fresh calls tick as they return; replayed calls and the
    # calls a run left unused (it stopped early) tick when the run ends
    bar = tqdm(total=len(jobs) * spec.budget, desc="compete", unit="call", disable=not progress,
               initial=spec.budget * sum(r is not None for r in done.values()))

    def counted(x):
        value = objective(x)
        bar.update(1)
        return value

    for (method, seed), res in done.items():
        if res is not None:
            continue
        bar.set_postfix_str(f"{method} seed {seed}")
        start = bar.n
        done[method, seed] = METHODS[method](counted, spec.lower, spec.upper, spec.budget, seed,
                                             history_path=_history_path(out_dir, method, seed),
                                             **spec.options.get(method, {}))
        bar.update(spec.budget - (bar.n - start))
    bar.close()
    return {m: [done[m, s] for s in range(spec.seeds)] for m in spec.methods}
