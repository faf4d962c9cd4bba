"""The optimizer competition's results (`jtire compete`): per-method summary (final error, calls to
reach each threshold, over seeds), the text table, the progression figure (the study's Figure 4-2)
and the output files runs.csv, summary.csv and progression.png. Running the competition:
`competition.py`."""

import math
from pathlib import Path

import numpy as np

from .competition import LABELS, VARIABLES, CompetitionSpec
from ..history import best_so_far
from ...io import atomic_savefig, atomic_write_csv

__all__ = ["summarize", "calls_to_reach", "format_table", "plot_progression", "write_outputs"]

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
