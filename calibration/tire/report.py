"""What a calibration writes: the study's Table 4-4, Figure 4-6, the calibrated tire, a summary.

- table_4_4.csv / table_4_4.md: per target the measured value, the simulated value at the best
  evaluation and the error (%), in the target's unit, with the study's numbers beside ours when
  the config gives them ([anchor]); a total row.
- figure_4_6.png: each target's error (%) against evaluation number, and the total error with
  its running best (log scale).
- calibrated_tire.toml: the input tire TOML with the calibrated values (calibration.tire.tire_toml).
- summary.json: best parameters (SI and file units), responses, errors, stop reason, cost in
  evaluations, batches, forward-run equivalents and simulator wall time.
"""

from pathlib import Path

import numpy as np

from .tire_toml import write_calibrated_tire
from ...io import atomic_savefig, atomic_write_csv, atomic_write_json, atomic_write_text

__all__ = ["table_4_4", "format_markdown", "plot_errors", "write_outputs"]


def table_4_4(result, spec, checks=(None, "")) -> list:
    """Rows (dicts) of Table 4-4 for a CalibrationResult and its CalibrationSpec; `checks`:
    (values, note) of the config's [checks] at the calibrated point (`evaluate_checks`), rows
    after the total (reported, not fitted)."""
    rows = []
    theta = getattr(result, "theta", None)
    bias = (spec.space.bias_matrix(spec.response_names) @ np.asarray(theta, float)
            if spec.space.has_bias and theta is not None else np.zeros(len(spec.targets)))
    for t, v, e, b in zip(spec.targets, result.values, result.errors_pct, bias):
        a = spec.anchor.get(t.name, {})
        rows.append({"target": t.name, "experiment": t.experiment, "quantity": t.quantity,
                     "unit": t.unit, "measured": t.measured / t.unit_factor,
                     "simulated": float(v) / t.unit_factor, "error_pct": float(e),
                     "study_simulated": a.get("simulated"), "study_error_pct": a.get("error_percent")})
        if spec.space.has_bias:  # what the targets measure = the tire's response + the bias
            rows[-1].update(tire=(float(v) - b) / t.unit_factor, bias=float(b) / t.unit_factor)
    rows.append({"target": "total", "experiment": "", "quantity": "sum of |errors|", "unit": "%",
                 "measured": None, "simulated": None, "error_pct": result.total_error_pct,
                 "study_simulated": None,
                 "study_error_pct": spec.anchor.get("total", {}).get("error_percent")})
    if spec.space.has_bias:
        rows[-1].update(tire=None, bias=None)
    values, note = checks
    for k, t in enumerate(spec.checks):
        v = float("nan") if values is None else float(values[k])
        rows.append({"target": f"{t.name} (check)", "experiment": t.experiment, "quantity": t.quantity,
                     "unit": t.unit, "measured": t.measured / t.unit_factor,
                     "simulated": v / t.unit_factor, "error_pct": abs(v / t.measured - 1.0) * 100.0,
                     "study_simulated": None, "study_error_pct": None, "note": note})
        if spec.space.has_bias:
            rows[-1].update(tire=v / t.unit_factor, bias=0.0)
    return rows


def loss_rows(spec, theta, checks=(None, "")) -> list:
    """Beside each free loss parameter: the true tan delta and storage modulus E'/K its Prony series
    gives (`jtire.materials.dynamic_modulus`) at the wheel's rotation frequency V / (2 pi R) and at the
    footprint's passage frequency V / L, V the speed of the first rolling-resistance target, L the
    footprint length of the FL check (simulated, else measured). `loss` is a band average (1-100 Hz),
    not a DMA reading at one frequency. [] without a rolling target or a free loss."""
    from jtire.materials import dynamic_modulus

    rolling = [t for t in spec.targets if t.experiment == "rolling_resistance"]
    idx = [i for i, f in enumerate(spec.space.fields) if f in ("loss", "tread_loss")]
    if not rolling or not idx or not np.all(np.isfinite(theta)):
        return []
    v = float(rolling[0].table.get("speed_mph", np.nan))  # SI (m/s) inside
    freqs = {"rotation": v / (2 * np.pi * spec.tire.geometry.outer_radius)}
    fl = [k for k, c in enumerate(spec.checks) if c.quantity == "contact_length_m"]
    if fl:
        length = spec.checks[fl[0]].measured if checks[0] is None else float(checks[0][fl[0]])
        freqs["footprint"] = v / length
    rows = []
    for i in idx:
        loss = float(np.exp(theta[i]))
        row = {"parameter": spec.space.names[i], "loss": loss}
        for where, f in freqs.items():
            tan_d, storage = dynamic_modulus(loss, spec.tire.relaxation_times, f)
            row.update({f"{where}_Hz": float(f), f"tan_delta_{where}": float(tan_d),
                        f"storage_over_K_{where}": float(storage)})
        rows.append(row)
    return rows


def format_loss_rows(rows) -> str:
    if not rows:
        return ""
    keys = [k for k in rows[0] if k != "parameter"]
    head = "| parameter | " + " | ".join(keys) + " |\n|---|" + "---|" * len(keys) + "\n"
    return ("\nWhat each loss parameter means at the rolling frequencies (its Prony series, exact):\n\n"
            + head + "".join(f"| {r['parameter']} | " + " | ".join(_f(r[k], 4) for k in keys) + " |\n"
                             for r in rows))


def _f(v, digits=6):
    return "" if v is None or (isinstance(v, float) and not np.isfinite(v)) else f"{v:.{digits}g}"


def format_markdown(rows) -> str:
    """Table 4-4 as markdown; with a bias in the calibration, `simulated` is tire + bias and the
    tire's own value and the bias get columns of their own."""
    biased = any("bias" in r for r in rows)
    head = ("| target | experiment | measured | simulated | " + ("tire | bias | " if biased else "")
            + "error % | study simulated | study error % |\n|---|---|---|---|"
            + ("---|---|" if biased else "") + "---|---|---|\n")
    body = "".join(
        f"| {r['target']} | {r['experiment']} | {_f(r['measured'])} {r['unit'] if r['measured'] is not None else ''} | "
        f"{_f(r['simulated'])} | " + (f"{_f(r['tire'])} | {_f(r['bias'])} | " if biased else "")
        + f"{_f(r['error_pct'], 4)} | {_f(r['study_simulated'])} | "
        f"{_f(r['study_error_pct'], 4)} |\n" for r in rows)
    notes = "".join(f"\n{n}\n" for n in dict.fromkeys(r.get("note") for r in rows) if n)
    checked = any(r["target"].endswith("(check)") for r in rows)
    return head + body + ("\n(check): measured, reported at the calibrated point, not fitted "
                          "(not in the total)\n" if checked else "") + notes


def plot_errors(records, targets, path, title: str = "") -> Path:
    """Figure 4-6: every target's error and the total against evaluation number."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = np.arange(1, len(records) + 1)
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    for i, t in enumerate(targets):
        e = np.array([np.nan if r["errors_pct"][t.name] is None else r["errors_pct"][t.name]
                      for r in records], float)
        ax.plot(n, e, ls="none", marker="o", ms=3.5, color=f"C{i}", label=f"{t.name} error")
    tot = np.array([np.nan if r["total_error_pct"] is None else r["total_error_pct"]
                    for r in records], float)
    ax.plot(n, tot, ls="none", marker="x", ms=4, color="k", label="total error")
    best = np.fmin.accumulate(np.where(np.isfinite(tot), tot, np.inf))
    ax.step(n, np.where(np.isfinite(best), best, np.nan), where="post", color="k", lw=1.5,
            label="best total so far")
    batches = [r["batch"] for r in records]
    for k in range(1, len(records)):
        if batches[k] != batches[k - 1]:
            ax.axvline(k + 0.5, color="0.85", lw=0.6, zorder=0)
    ax.set_yscale("log")
    ax.set_xlabel("evaluation number (grey lines: batches)")
    ax.set_ylabel("error (%)")
    ax.set_title(title, fontsize=9)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    return atomic_savefig(fig, path, dpi=120)


def write_outputs(result, spec, out_dir, title: str = "", sim=None, checks=(None, "")) -> dict:
    """Write every output of a calibration into out_dir; returns {name: path}."""
    out_dir = Path(out_dir)
    rows = table_4_4(result, spec, checks)
    keys = list(dict.fromkeys(k for r in rows for k in r))
    losses = loss_rows(spec, result.theta, checks)
    paths = {"table_csv": atomic_write_csv(out_dir / "table_4_4.csv", None,
                                           {k: [r.get(k) for r in rows] for k in keys}),
             "table_md": atomic_write_text(out_dir / "table_4_4.md",
                                           format_markdown(rows) + format_loss_rows(losses))}
    if result.records:
        paths["figure"] = plot_errors(result.records, spec.targets, out_dir / "figure_4_6.png", title)
    space = spec.space
    if np.all(np.isfinite(result.theta)):
        header = (f"Calibrated by `jtire calibrate {spec.path.name}` ({result.method}, "
                  f"{result.n_evaluations} evaluations, stop: {result.stop_reason}); total error "
                  f"{result.total_error_pct:.4g} %.\nStarting tire: {spec.tire_path}")
        for name, (b, unit, tn) in space.biases(result.theta).items():
            header += (f"\n{name} = {b:.6g} {unit} added to {', '.join(tn)}: not part of this tire "
                       "(its responses are the tire's own)")
        paths["tire"], _ = write_calibrated_tire(out_dir / "calibrated_tire.toml",
                                                 spec.tire_path.read_text(), space, result.theta,
                                                 header)
    summary = {
        "config": str(spec.path), "method": result.method, "stop_reason": result.stop_reason,
        "n_evaluations": result.n_evaluations, "n_jacobians": result.n_jacobians,
        "n_batches": result.n_batches,
        "cost_forward_equivalents": result.cost_forward, "simulator_wall_s": result.wall_s,
        "total_error_pct": result.total_error_pct,
        "errors_pct": dict(zip(spec.response_names, result.errors_pct.tolist())),
        "responses_SI": dict(zip(spec.response_names, result.values.tolist())),
        "theta": result.theta.tolist(),
        "parameters_SI": space.values(result.theta) if np.all(np.isfinite(result.theta)) else {},
        "parameters_file_units": [{"table": t, "key": k, "value": v, "unit": u}
                                  for t, k, v, u in space.file_values(result.theta)]
        if np.all(np.isfinite(result.theta)) else [],
        "simulator": None if sim is None else sim.fingerprint(),
    }
    if losses:
        summary["loss_factors"] = losses
    if spec.checks:  # measured responses reported at the calibrated point, not fitted
        summary["checks"] = {t.name: {"measured_SI": t.measured, "simulated_SI": (
            None if checks[0] is None else float(checks[0][k]))} for k, t in enumerate(spec.checks)}
        if checks[1]:
            summary["checks_note"] = checks[1]
    if space.has_bias and np.all(np.isfinite(result.theta)):
        # the bias is not part of the tire: the calibrated tire's own responses are these
        summary["bias_SI"] = space.biases(result.theta)
        summary["tire_responses_SI"] = dict(zip(spec.response_names, (
            result.values - space.bias_matrix(spec.response_names) @ result.theta).tolist()))
    paths["summary"] = atomic_write_json(out_dir / "summary.json", summary)
    return paths
