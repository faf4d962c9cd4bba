"""Rigid ring vs the detailed shell model on the same inputs (docs/rigid-ring.md §8): the metric
list with its tolerances, the comparison table, and the validation figure.

Tolerances, fixed before any comparison (relative, |ring / shell - 1|):
  static deflection 3 %; bounce (drop) frequency 5 %; damping ratios 20 %; peak F_z of the first
  impact 5 %; mode frequencies (belt vertical in the drop's F_z, drum-cleat vertical and fore-aft)
  3 %; lateral release frequency 5 %; steady F_y 3 %; steady M_z 10 % (not stated by the doc: the
  aligning moment is a small difference of large contact moments in the shell model); distance to
  63 % of steady F_y (~ sigma) 10 %; the drum-cleat peak-to-peak F_z and F_x 20 % (the doc's §8),
  judged only when the ring rolls over the cleat through E03's tandem cam (a point contact on the
  cleat's profile is no enveloping model: its peak-to-peak is listed, "not compared"). The slip
  step's steady values are read on both sides over one period of the shell's lateral mode rolled
  at the step's speed (`jtire.validate.step_tail`): both records still ring in it at their ends.

Both sides are dicts {metric name: value}; `ring_metrics(results)` builds the ring's from the
scenario results, and the shell side must use the same names (METRICS).
"""

import dataclasses
import math

import numpy as np

from ..io import atomic_savefig


@dataclasses.dataclass(frozen=True)
class Metric:
    name: str
    tolerance: float | None  # relative; None: listed, not judged
    meaning: str


METRICS = (
    Metric("drop.static_deflection_m", 0.03, "static deflection under the load (m)"),
    Metric("drop.bounce_f_Hz", 0.05, "damped bounce frequency of rim z from first contact (fit, Hz)"),
    Metric("drop.bounce_zeta", 0.20, "damping ratio of the rim's bounce (damped-sine fit)"),
    Metric("drop.peak_F_z_N", 0.05, "peak contact force of the first impact (N)"),
    Metric("drop.belt_mode_Hz", 0.03, "belt vertical mode in the contact force spectrum (Hz)"),
    Metric("drum.vertical_mode_Hz", 0.03, "spindle F_z mode after the cleat (modal fit f_n, Hz)"),
    Metric("drum.vertical_mode_zeta", 0.20, "its modal damping ratio"),
    Metric("drum.fore_aft_mode_Hz", 0.03, "spindle F_x (fore-aft / wind-up) mode (modal fit f_n, Hz)"),
    Metric("drum.fore_aft_mode_zeta", 0.20, "its modal damping ratio"),
    Metric("drum.F_z_peak_to_peak_N", 0.20, "spindle F_z peak to peak over the cleat and after (N)"),
    Metric("drum.F_x_peak_to_peak_N", 0.20, "spindle F_x peak to peak over the cleat and after (N)"),
    Metric("lateral.f_Hz", 0.05, "lateral release: damped frequency of rim y (Hz)"),
    Metric("lateral.zeta", 0.20, "lateral release: damping ratio"),
    *[m for v in (5, 15) for m in (
        Metric(f"step_{v}.F_y_steady_N", 0.03, f"slip step at {v} m/s: steady F_y, SAE (N)"),
        Metric(f"step_{v}.M_z_steady_Nm", 0.10, f"slip step at {v} m/s: steady M_z, SAE (N m)"),
        Metric(f"step_{v}.s63_m", 0.10, f"slip step at {v} m/s: distance to 63 % of steady F_y (m)"))],
)
BY_NAME = {m.name: m for m in METRICS}


def ring_metrics(results: dict) -> dict:
    """Metric values from scenario results: results maps "drop", "drum", "lateral", "step_5",
    "step_15" to ScenarioResult (any may be absent)."""
    out = {}
    if "drop" in results:
        q = results["drop"].quantities
        out |= {"drop.static_deflection_m": q["static_deflection_m"], "drop.bounce_f_Hz": q["bounce_f_d_Hz"],
                "drop.bounce_zeta": q["bounce_zeta_fit"], "drop.peak_F_z_N": q["peak_F_z_N"],
                "drop.belt_mode_Hz": q["F_z_spectrum_peak_Hz"]}
    if "drum" in results:
        q = results["drum"].quantities
        out |= {"drum.vertical_mode_Hz": q["F_z_f_n_fit_Hz"], "drum.vertical_mode_zeta": q["F_z_zeta_fit"],
                "drum.fore_aft_mode_Hz": q["F_x_f_n_fit_Hz"], "drum.fore_aft_mode_zeta": q["F_x_zeta_fit"]}
        if results["drum"].info.get("ellips") is not None:  # through the cam (a point contact: not comparable)
            out |= {"drum.F_z_peak_to_peak_N": q["F_z_peak_to_peak_N"], "drum.F_x_peak_to_peak_N": q["F_x_peak_to_peak_N"]}
    if "lateral" in results:
        q = results["lateral"].quantities
        out |= {"lateral.f_Hz": q["f_d_Hz"], "lateral.zeta": q["zeta_fit"]}
    for v in (5, 15):
        if f"step_{v}" in results:
            q = results[f"step_{v}"].quantities
            out |= {f"step_{v}.F_y_steady_N": q["F_y_steady_SAE_N"], f"step_{v}.M_z_steady_Nm": q["M_z_steady_SAE_Nm"],
                    f"step_{v}.s63_m": q["s63_m"]}
    return out


@dataclasses.dataclass(frozen=True)
class Comparison:
    metric: str
    shell: float | None
    ring: float | None
    rel_diff: float | None  # ring / shell - 1
    tolerance: float | None
    verdict: str  # "pass", "FAIL", "not compared", "SHELL RUN FAILED"
    meaning: str


def _num(v):
    return None if v is None or not math.isfinite(float(v)) else float(v)


def compare(shell_results: dict, ring_results: dict, failed=()) -> list:
    """Comparison rows for every metric of METRICS (plus unknown names, listed not judged). failed:
    name prefixes of metrics whose shell run failed (their verdict says so, not "not compared")."""
    rows = []
    names = list(BY_NAME) + [n for n in list(shell_results) + list(ring_results) if n not in BY_NAME]
    for n in dict.fromkeys(names):
        m = BY_NAME.get(n, Metric(n, None, "(not a validation metric)"))
        s, r = _num(shell_results.get(n)), _num(ring_results.get(n))
        rel = None if s is None or r is None or s == 0 else r / s - 1
        if s is None and n.startswith(tuple(failed)):
            verdict = "SHELL RUN FAILED"
        elif rel is None or m.tolerance is None:
            verdict = "not compared"
        else:
            verdict = "pass" if abs(rel) <= m.tolerance else "FAIL"
        rows.append(Comparison(n, s, r, rel, m.tolerance, verdict, m.meaning))
    return rows


def markdown(rows) -> str:
    lines = ["| metric | shell | ring | ring/shell - 1 | tolerance | verdict |", "|---|---|---|---|---|---|"]
    for c in rows:
        f = (lambda v: "—" if v is None else f"{v:.5g}")
        rel = "—" if c.rel_diff is None else f"{100 * c.rel_diff:+.1f} %"
        tol = "—" if c.tolerance is None else f"±{100 * c.tolerance:.0f} %"
        lines.append(f"| {c.metric} | {f(c.shell)} | {f(c.ring)} | {rel} | {tol} | {c.verdict} |")
    return "\n".join(lines) + "\n"


def ring_signals(results: dict) -> dict:
    """Figure signals {panel: (x, y)} from scenario results (see validation_figure)."""
    out = {}
    if "drop" in results:
        s = results["drop"].signals
        out["drop"] = (s["time_s"] - results["drop"].quantities["first_contact_s"], s["rim_z_from_rest_m"])
    if "drum" in results:
        s = results["drum"].signals
        info = results["drum"].info  # time from the cleat's crest under the rim centre
        out["drum"] = (s["time_s"] - info.get("t_centre_s", info.get("t_touch_s", 0.0)), s["spindle_F_z_N"])
        out["drum_contact"] = (out["drum"][0], s["contact_force_z_N"])  # the diagnosis's, not panels
        out["drum_contact_x"] = (out["drum"][0], s["contact_force_x_N"])
    if "lateral" in results:
        s = results["lateral"].signals
        out["lateral"] = (s["time_s"], s["rim_y_m"])
    for v in (5, 15):
        if f"step_{v}" in results:
            s = results[f"step_{v}"].signals
            out[f"step_{v}"] = (s["distance_m"], s["F_y_SAE_N"])
    return out


PANELS = (("drop", "drop test: rim height above where it rests under the load", "t from first contact (s)",
           "rim z - z_rest (m)"), ("drum", "drum-cleat", "t from the cleat under the rim centre (s)", "spindle F_z (N)"),
          ("lateral", "lateral release", "t (s)", "rim y (m)"),
          ("step_5", "slip step, 5 m/s", "distance s (m)", "F_y SAE (N)"),
          ("step_15", "slip step, 15 m/s", "distance s (m)", "F_y SAE (N)"))


def validation_figure(shell_signals: dict, ring_signals_: dict, path, title="Rigid ring vs shell model"):
    """One panel per scenario, shell and ring overlaid. Each dict maps a panel name of PANELS to
    (x (N,), y (N,)); a panel missing on both sides is left out. Written with atomic_savefig."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [p for p in PANELS if p[0] in shell_signals or p[0] in ring_signals_]
    fig, axes = plt.subplots(len(panels) or 1, 1, figsize=(7, 2.4 * max(len(panels), 1)), squeeze=False)
    for ax, (key, name, xl, yl) in zip(axes[:, 0], panels):
        for src, style, lab in ((shell_signals, "-", "shell"), (ring_signals_, "--", "rigid ring")):
            if key in src:
                x, y = (np.asarray(v) for v in src[key])
                ax.plot(x, y, style, label=lab, lw=1.2)
        if key.startswith("step_") and key in shell_signals:
            # the shell's force ripples at the segment pitch: a miss smaller than the ripple is within it
            x, y = (np.asarray(v, float) for v in shell_signals[key])
            tail = y[x >= x[0] + 0.7 * (x[-1] - x[0])]
            if tail.size > 3 and np.nanmean(np.abs(tail)) > 0:
                rip = 0.5 * np.ptp(tail) / abs(np.nanmean(tail))
                ax.text(0.98, 0.93, f"shell ripple over the last 30 %: ±{100 * rip:.1f} % of its mean "
                        "(segment pitch)", transform=ax.transAxes, ha="right", va="top", fontsize=7,
                        bbox={"fc": "white", "alpha": 0.8, "lw": 0})
        ax.set_title(name, fontsize=9)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return atomic_savefig(fig, path)
