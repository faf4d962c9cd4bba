"""The study end to end (`jtire reproduce`): its stages, each a jtire command writing its own subfolder of one
output folder; a manifest (`reproduce.json`) that makes the chain resumable and refuses other settings; and one
report (`report.md`, and `report.html` with the figures inline) built from the files the stages wrote.

Stages, in order: the measured data and their fits (chapter 3), the optimizer competition on the soil block
(Table 4-3), the calibration to the study's four targets (Table 4-4), the characterization of the calibrated tire
over the 3 x 3 grid with its `.tir` and validation (chapters 5-6), the posterior with its check, and the study's
figures. `quick` runs the same chain small: the coarse ring (calibration `study_quick.toml`: 3 moduli and the drag
bias, 10 runs), the characterization at the rated condition alone with the test suite's short transients, a
posterior of 16 walkers with 4 check draws, the figures at low resolution.
"""

import base64
import csv
import dataclasses
import html
import json
import re
from pathlib import Path

from .errors import ConfigError
from .fingerprint import code_version
from .io import atomic_write_json, atomic_write_text
from .resources import config_path

MANIFEST = "reproduce.json"
# the transient experiments' protocol of the quick chain: the test suite's short settling (1 mJ, 0.3 s at most)
QUICK_SOLVER = ("solver.settle_damping_per_s=300.0", "solver.ke_tol_J=0.001", "solver.inflate_ramp_s=0.04",
                "solver.inflate_max_s=0.4", "solver.load_ramp_s=0.05", "solver.settle_max_s=0.3")
QUICK_MESH = ("tire.mesh.n_theta=32", "tire.mesh.n_crown=4")
QUICK_SAMPLE = ("calibration=study_quick.toml", "sampler.walkers=16", "sampler.max_steps=4000",
                "sampler.check_every=200", 'emulator.candidates=["linear", "reduced"]', "check.draws=4",
                "check.refine=false")


@dataclasses.dataclass(frozen=True)
class Stage:
    name: str
    title: str
    argv: tuple  # the jtire command (without "jtire"); () for the figures stage, which runs paper_figures/
    ok_codes: tuple = (0,)  # exit codes that let the chain go on (sample: 1 = ran, did not converge)


def _sets(items) -> list:
    return [a for s in items for a in ("--set", s)]


def stages(out: Path, quick: bool) -> list:
    """The chain's stages for output folder `out`."""
    cal = config_path("calibration", "study_quick.toml" if quick else "study.toml")
    char_small = _sets((*QUICK_MESH, *QUICK_SOLVER, "grid.loads_kg=[4625.0]", "grid.pressures_psi=[120.0]",
                        "validation.step_contact_subpoints=2"))  # a test of the chain: the tire's own contact
    return [
        Stage("data", "Measured test-track and sandbox data, their fits (chapter 3)", ("data", "--out", str(out / "data"))),
        Stage("compete", "Optimizer competition on the soil block (Table 4-3)",
              ("compete", str(config_path("calibration", "soil_competition.toml")), "--out", str(out / "compete"),
               *(["--quick"] if quick else []))),
        Stage("calibrate", "Calibration to the study's four targets (Table 4-4)",
              ("calibrate", str(cal), "--out", str(out / "calibrate"))),
        Stage("characterize", "Characterization of the calibrated tire (chapters 5-6), its .tir and validation",
              ("characterize", "--tire", str(out / "calibrate" / "calibrated_tire.toml"), "--out",
               str(out / "characterize"), *(char_small if quick else []))),
        Stage("sample", "Posterior of the calibrated parameters, checked against the shell model",
              ("sample", str(config_path("calibration", "posterior.toml")), "--history", str(out / "calibrate"),
               "--out", str(out / "sample"), "--check", *(_sets(QUICK_SAMPLE) if quick else [])), ok_codes=(0, 1)),
        Stage("figures", "The study's figures (paper_figures/)", ()),
    ]


# ---- the manifest --------------------------------------------------------------------------------------
def open_manifest(out: Path, quick: bool) -> dict:
    """The folder's manifest, new or resumed; another setting or another jtire build is refused."""
    settings = {"quick": bool(quick), "jtire": code_version()}
    path = out / MANIFEST
    if path.is_file():
        try:
            man = json.loads(path.read_text())
        except (OSError, ValueError) as e:
            raise ConfigError(f"--out {out}: {MANIFEST} is unreadable ({e}); use a new folder") from None
        if man.get("settings") != settings:
            raise ConfigError(f"--out {out}: made with other settings ({_diff(man.get('settings', {}), settings)}); "
                              "use a new folder, or the same settings and build to resume")
        return man
    if out.exists() and any(out.iterdir()):
        raise ConfigError(f"--out {out}: exists and is not a reproduce folder (no {MANIFEST}); use a new folder")
    out.mkdir(parents=True, exist_ok=True)
    man = {"settings": settings, "stages": {}}
    atomic_write_json(path, man)
    return man


def _diff(a: dict, b: dict) -> str:
    return ", ".join(f"{k}: {a.get(k)!r} there, {b.get(k)!r} now" for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k))


def record(out: Path, man: dict, stage: str, **fields) -> None:
    """A stage's status, written at once (a kill after it keeps it)."""
    man["stages"][stage] = {**man["stages"].get(stage, {}), **fields}
    atomic_write_json(out / MANIFEST, man)


# ---- the figures stage -----------------------------------------------------------------------------------
def figure_scripts() -> list:
    """paper_figures/fig*.py of the source checkout (a wheel does not carry them): [] when absent."""
    root = Path(__file__).resolve().parent.parent / "paper_figures"
    return sorted(root.glob("fig*.py")) if root.is_dir() else []


def figure_argv(script: Path, out: Path, quick: bool) -> list:
    """Each figure from the chain's own folders: chapters 5-6 from the characterization, Fig. 4-2 from the
    competition's runs (resumed, not rerun), chapter 3 from the shipped data."""
    png = str(out / "figures" / f"{script.stem}.png")
    q = ["--quick"] if quick else []
    if script.stem.startswith(("fig5_", "fig6_")):
        return ["--from", str(out / "characterize"), "--out", png, *q]
    if script.stem.startswith("fig4_2"):
        return ["--runs", str(out / "compete"), "--out", png, *q]
    return ["--out", png, *q]


# ---- the report ------------------------------------------------------------------------------------------
def _csv_table(path: Path, columns=None, fmt=None) -> str:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return "(empty)\n"
    columns = columns or list(rows[0])
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        lines.append("| " + " | ".join(_cell(r.get(c, ""), fmt) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def _cell(v: str, fmt=None) -> str:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return v or ""
    return f"{x:{fmt or '.4g'}}"


def _file(path: Path) -> str:
    return path.read_text() if path.is_file() else f"(not written: {path.name} is missing)\n"


def _competition_table(out: Path) -> str:
    """Table 4-3: the study's single runs beside jtire's medians over seeds."""
    import tomllib

    summary = out / "compete" / "soil" / "summary.csv"
    if not summary.is_file():
        return "(not written: the competition's summary.csv is missing)\n"
    anchor = tomllib.loads(config_path("calibration", "soil_competition.toml").read_text())
    anchor = anchor.get("competition", {}).get("anchor", {})
    with open(summary, newline="") as f:
        rows = list(csv.DictReader(f))
    lines = ["| method | study: error % | study: calls | jtire: seeds | jtire: final error %, median (IQR) | "
             "jtire: calls used, median |", "|---|---|---|---|---|---|"]
    for r in rows:
        a = anchor.get(r["method"], {})
        lines.append(f"| {r['method']} | {a.get('error_percent', '')} | {a.get('calls', '')} | {r['seeds']} | "
                     f"{_cell(r['final_error_median_pct'])} ({_cell(r['final_error_q25_pct'])}-"
                     f"{_cell(r['final_error_q75_pct'])}) | {_cell(r['calls_used_median'])} |")
    return "\n".join(lines) + "\n"


def _sample_rounds(out: Path) -> list:
    """The posterior's rounds, first to last: sample/, then its refined rounds (refined/, refined_2/, ...) where
    the check's coverage sent it to retrain the emulator on the check's runs."""
    d = out / "sample"
    refined = [p for p in d.glob("refined*") if p.is_dir() and (p / "diagnostics.json").is_file()]
    order = lambda p: int(p.name.split("_")[1]) if "_" in p.name else 1  # noqa: E731
    return [d] + sorted(refined, key=order)


def _coverage(folder: Path) -> str:
    c = json.loads((folder / "check.json").read_text())
    return ", ".join(f"{k} {v:.2f} ({c['inside'][k]}/{c['n']})" for k, v in c.get("coverage", {}).items())


def _posterior(out: Path) -> str:
    """The final round's sampler verdict, parameter and response intervals, and the check's coverage in every
    round (the first round's too: how far the unrefined emulator was off)."""
    rounds = _sample_rounds(out)
    d = rounds[-1]
    parts = []
    if len(rounds) > 1:
        parts.append(f"The check's coverage sent the posterior through {len(rounds) - 1} refined round(s): the "
                     f"check's runs joined the emulator's training set and its variance was rescaled. Below: the "
                     f"final round (sample/{d.name}/).\n")
    diag = d / "diagnostics.json"
    if diag.is_file():
        g = json.loads(diag.read_text())
        tau = max((t for t in g.get("tau", []) if isinstance(t, (int, float))), default=float("nan"))
        rhat = max((r for r in g.get("rhat", []) if isinstance(r, (int, float))), default=float("nan"))
        parts.append(f"Sampler: {'converged' if g.get('converged') else 'NOT CONVERGED'} after {g.get('steps')} steps "
                     f"(needs {g.get('n_tau_required', float('nan')):g} x max tau {tau:.3g}); acceptance "
                     f"{g.get('acceptance_mean', float('nan')):.3f}; R-hat max {rhat:.4f}.\n")
    if (d / "widths.csv").is_file():
        parts.append("Parameters: posterior median and central 90 % interval, and the interval's width against the "
                     "prior's (in ln p):\n\n" + _csv_table(d / "widths.csv", ["parameter", "median", "lower", "upper",
                                                                                "unit", "ratio"]))
    parts.append("Posterior predictive of the tire model (central 90 % intervals):\n\n" + _file(d / "predictive.md"))
    checked = [r for r in rounds if (r / "check.json").is_file()]
    if checked:
        parts.append("Check: posterior draws run through the shell model; the share of them inside the emulator's "
                     "90 % intervals (80-97 % is the band the check accepts):\n")
        parts += [f"- {'first round' if r == rounds[0] else r.name}: {_coverage(r)}" for r in checked]
    return "\n".join(parts) + "\n"


def _figures(out: Path) -> list:
    """Every PNG the chain wrote, figures stage first (path relative to out)."""
    pngs = sorted((out / "figures").glob("*.png")) if (out / "figures").is_dir() else []
    others = [p for p in sorted(out.rglob("*.png")) if p.parent != out / "figures"]
    return [p.relative_to(out).as_posix() for p in pngs + others]


def report_markdown(out: Path, man: dict, stage_list: list) -> str:
    """The report as markdown: every table the stages wrote, in the study's order, and each stage's time."""
    s = man["settings"]
    lines = ["# The study, reproduced by jtire", "",
             f"jtire {s['jtire']}; {'QUICK CHAIN: coarse ring, short runs (a test of the chain, not results)' if s['quick'] else 'full chain, default mesh'}.",
             "Every number below was computed by the stages listed here, into this folder.", "",
             "## Stages", "", "| stage | what | status | wall |", "|---|---|---|---|"]
    total = 0.0
    for st in stage_list:
        rec = man["stages"].get(st.name, {})
        wall = rec.get("wall_s")
        total += wall or 0.0
        lines.append(f"| {st.name} | {st.title} | {rec.get('status', 'not run')} | "
                     f"{'' if wall is None else _minutes(wall)} |")
    lines += [f"| total | | | {_minutes(total)} |", ""]
    lines += ["## Chapter 3: measured data", "", "Fits of RRC against load (95 % confidence):", "",
              _csv_table(out / "data" / "fits.csv", ["dataset", "model", "param", "value", "ci_low", "ci_high", "n"])
              if (out / "data" / "fits.csv").is_file() else "(not written)\n", "",
              "The study's rolling-resistance targets against the measured trends:", "",
              _csv_table(out / "data" / "target_comparison.csv",
                         ["dataset", "target", "load_N", "target_rrc", "model", "fit_rrc", "ci_low", "ci_high",
                          "percent", "inside_ci"])
              if (out / "data" / "target_comparison.csv").is_file() else "(not written)\n", ""]
    lines += ["## Table 4-3: optimizer competition on the soil block", "", _competition_table(out), ""]
    lines += ["## Table 4-4: calibration to the study's four targets", "", _file(out / "calibrate" / "table_4_4.md"), ""]
    c = out / "characterize"
    failed = man["stages"].get("characterize", {}).get("failures", [])
    lines += ["## Chapters 5-6: the calibrated tire's rigid-ring parameters", ""]
    if failed:
        lines += [f"**{len(failed)} cases failed** and are missing from the tables below (each is named with its "
                  "error; a rerun of the same command retries them):", ""] + [f"- {f}" for f in failed] + [""]
    lines += [_file(c / "in_plane.md"), "",
              _file(c / "out_of_plane.md"), "", "## Trends", "", _file(c / "trends.md"), "",
              "## The rigid ring against the shell model", "", _file(c / "validation.md"), "",
              "## The posterior", "", _posterior(out), "", "## Figures", ""]
    for rel in _figures(out):
        lines += [f"![{rel}]({rel})", ""]
    return "\n".join(lines) + "\n"


def _minutes(s: float) -> str:
    return f"{int(s // 60)} min {s % 60:04.1f} s" if s >= 60 else f"{s:.1f} s"


def report_html(markdown_text: str, out: Path) -> str:
    """The markdown as one self-contained HTML page: tables rendered, every figure inline (base64)."""
    import markdown

    body = markdown.markdown(markdown_text, extensions=["tables"])

    def inline(m):
        path = out / html.unescape(m.group(1))
        if not path.is_file():
            return m.group(0)
        return f'src="data:image/png;base64,{base64.b64encode(path.read_bytes()).decode()}"'

    body = re.sub(r'src="([^"]+\.png)"', inline, body)
    style = ("body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;line-height:1.4}"
             "table{border-collapse:collapse;font-size:0.85em;margin:0.5em 0}td,th{border:1px solid #ccc;"
             "padding:2px 6px;text-align:left}img{max-width:100%}code{background:#f4f4f4}")
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>jtire: the study, reproduced</title>"
            f"<style>{style}</style></head><body>\n{body}\n</body></html>\n")


def write_report(out: Path, man: dict, stage_list: list) -> tuple:
    md = report_markdown(out, man, stage_list)
    return (atomic_write_text(out / "report.md", md), atomic_write_text(out / "report.html", report_html(md, out)))


__all__ = ["Stage", "stages", "open_manifest", "record", "figure_scripts", "figure_argv", "write_report",
           "report_markdown", "report_html"]
