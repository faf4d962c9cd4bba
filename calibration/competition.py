"""`jtire compete CONFIG`: the study's optimizer competition on the soil block (section 4.2).

ARSM, a genetic algorithm and Monte Carlo search each tune soil density and Young's modulus so
that the simulated plate sinkage matches Bekker's law, over many seeds with the same bounds and
call budget. Outputs in --out: histories/ (one JSON-lines file per method and seed: a killed
competition resumes where it stopped), runs.csv (every call of every run, numbered from 1;
the history files number them from 0), summary.csv (per
method: final error, calls to reach each threshold), progression.png (the study's Figure 4-2:
best error so far against calls, median and quartiles over seeds).

The competition logic takes the objective as an argument (`run_competition`), so it runs just
as well on the closed-form stand-in used by the quick checks (`standin_objective`). Cost: the
FE plate test takes about 30 ms per call after a ~2 s compile, so the full competition (3 methods
x 20 seeds x 50 calls) takes about 100 s on a quiet 2-core machine; stop it at any time and run
the same command again.
"""

import dataclasses
import inspect
import json
import math
import typing
from pathlib import Path

import numpy as np
from tqdm import tqdm

from . import arsm, baselines
from .history import best_so_far
from ..schema import Field, validate
from ..config import read_toml
from ..errors import ConfigError
from ..io import atomic_savefig, atomic_write_csv, atomic_write_json

__all__ = ["METHODS", "CompetitionSpec", "load_config", "soil_objective", "standin_objective",
           "fingerprint",
           "run_competition", "summarize", "calls_to_reach", "format_table", "plot_progression",
           "write_outputs"]

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
    from . import soil  # the soil model's spec (its checks); the FE solve is built only when run

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
    from . import soil  # the finite-element model; imported only when used

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


def _padded_best(res, budget):
    """Best error so far after calls 1..budget; a run that stopped early keeps its best."""
    b = best_so_far(res.history)
    return np.concatenate([b, np.full(budget - b.size, b[-1] if b.size else np.inf)])


def calls_to_reach(res, threshold: float) -> float:
    """Calls a run needed for an error <= threshold (percent); inf if it never got there."""
    b = best_so_far(res.history)
    hit = np.flatnonzero(b <= threshold)
    return float(hit[0] + 1) if hit.size else math.inf


def _q(a, p):
    """Percentile p of a; with inf entries ("never reached") it is an observed value (inf if
    the seed at that rank never got there), interpolated otherwise."""
    a = np.asarray(a, dtype=float)
    if a.size == 0:
        return math.nan
    if np.all(np.isfinite(a)):
        return float(np.percentile(a, p))
    return float(np.percentile(a, p, method="inverted_cdf"))


def summarize(results: dict, spec: CompetitionSpec) -> list:
    """One row per method: final error median and quartiles, calls to each threshold."""
    rows = []
    for method, runs in results.items():
        final = [_padded_best(r, spec.budget)[-1] for r in runs]
        row = {"method": method, "seeds": len(runs),
               "final_error_median_pct": _q(final, 50), "final_error_q25_pct": _q(final, 25),
               "final_error_q75_pct": _q(final, 75),
               "calls_used_median": _q([r.n_calls for r in runs], 50)}
        for t in spec.thresholds:
            c = [calls_to_reach(r, t) for r in runs]
            for name, p in (("median", 50), ("q25", 25), ("q75", 75)):
                row[f"calls_to_{t:g}pct_{name}"] = _q(c, p)
            row[f"reached_{t:g}pct_fraction"] = float(np.mean(np.isfinite(c)))
        rows.append(row)
    return rows


def _fmt(v, budget):
    return f">{budget}" if math.isinf(v) else f"{v:.3g}"


def format_table(summary: list, spec: CompetitionSpec) -> str:
    """The median table (quartiles in brackets, share of seeds that got there in parentheses),
    with the study's single runs beside ours."""
    cols = ["method", "final error % median [q25, q75]"]
    cols += [f"calls to {t:g} %: median [q25, q75] (hit)" for t in spec.thresholds]
    cols += ["study, one run"]
    table = [cols]
    for row in summary:
        m, b = row["method"], spec.budget
        cells = [LABELS.get(m, m), f"{row['final_error_median_pct']:.3g} "
                 f"[{row['final_error_q25_pct']:.3g}, {row['final_error_q75_pct']:.3g}]"]
        for t in spec.thresholds:
            k = f"calls_to_{t:g}pct"
            cells.append(f"{_fmt(row[k + '_median'], b)} [{_fmt(row[k + '_q25'], b)}, "
                         f"{_fmt(row[k + '_q75'], b)}] ({row[f'reached_{t:g}pct_fraction']:.0%})")
        a = spec.anchors.get(m)
        cells.append(f"{a['error_percent']:g} % in {a.get('note', a['calls'])} calls" if a else "")
        table.append(cells)
    widths = [max(len(r[i]) for r in table) for i in range(len(cols))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in table)


def plot_progression(results: dict, spec: CompetitionSpec, path, title: str) -> Path:
    """The study's Figure 4-2: best error so far vs calls, median line and quartile band."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.0, 4.6))
    calls = np.arange(1, spec.budget + 1)
    for i, (method, runs) in enumerate(results.items()):
        curves = np.array([_padded_best(r, spec.budget) for r in runs])
        color = f"C{i}"
        lo, med, hi = np.percentile(curves, [25, 50, 75], axis=0)
        ax.plot(calls, med, color=color, lw=2, label=f"{LABELS.get(method, method)}: median "
                f"of {len(runs)} seeds")
        ax.fill_between(calls, lo, hi, color=color, alpha=0.2, lw=0)
        a = spec.anchors.get(method)
        if a:
            ax.plot(a["calls"], a["error_percent"], marker="*", ms=13, color=color, mec="k",
                    ls="none", label=f"study, one run: {a['error_percent']:g} % in "
                    f"{a.get('note', a['calls'])} calls")
    for t in spec.thresholds:
        ax.axhline(t, color="0.4", ls="--", lw=0.8)
        ax.annotate(f"{t:g} %", (spec.budget, t), textcoords="offset points", xytext=(-28, 3),
                    fontsize=8, color="0.3")
    ax.set_yscale("log")
    ax.set_xlim(0.5, spec.budget + 1.5)  # room for an anchor star at the budget
    ax.set_xlabel("number of function calls")
    ax.set_ylabel("best sinkage error so far (%)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return atomic_savefig(fig, path, dpi=120)


def write_outputs(results: dict, spec: CompetitionSpec, out_dir, title: str) -> dict:
    """runs.csv, summary.csv and progression.png in out_dir; returns their paths and the rows."""
    out_dir = Path(out_dir)
    rows = []
    for method, runs in results.items():
        for r in runs:
            best = best_so_far(r.history)
            for h, b in zip(r.history, best):
                rows.append([method, r.seed, h["call"] + 1, *h["x"], h["f"], b,
                             h.get("phase", ""), r.stop_reason])
    runs_csv = atomic_write_csv(out_dir / "runs.csv", ["method", "seed", "call", *VARIABLES,
                                "error_pct", "best_error_pct", "phase", "stop_reason"], rows)
    summary = summarize(results, spec)
    summary_csv = atomic_write_csv(out_dir / "summary.csv", None,
                                   {k: [r[k] for r in summary] for k in summary[0]})
    fig = plot_progression(results, spec, out_dir / "progression.png", title)
    return {"runs_csv": runs_csv, "summary_csv": summary_csv, "figure": fig, "summary": summary}
