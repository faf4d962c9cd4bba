"""The shared look of the chapter 5-6 figures: size, fonts, a colour per pressure and per load,
axis labels with units, a footnote naming the data source, the command-line options, saving."""

import argparse
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from jtire.errors import JtireError  # noqa: E402
from jtire.io import atomic_savefig  # noqa: E402

FIGSIZE = (7.0, 4.6)
WIDE = (10.0, 4.6)
RC = {"font.size": 9, "axes.titlesize": 10, "axes.labelsize": 9, "legend.fontsize": 8, "xtick.labelsize": 8,
      "ytick.labelsize": 8, "axes.grid": True, "grid.alpha": 0.3, "lines.linewidth": 1.4}
# one colour per grid pressure and per grid load (study grid); other values get the nearest's
PRESSURE_COLORS = {70.0: "#1f77b4", 120.0: "#2ca02c", 150.0: "#d62728"}
LOAD_COLORS = {2312.5: "#9467bd", 4625.0: "#ff7f0e", 6937.5: "#8c564b"}
MEASURED = dict(marker="*", ms=13, color="gold", mec="k", ls="none", zorder=5)

LABELS = {
    "time_ms": "time (ms)", "time_s": "time (s)", "deflection_mm": "deflection from first contact (mm)",
    "load_kN": "vertical load (kN)", "axle_force_kN": "vertical axle force (kN)",
    "frequency_Hz": "frequency (Hz)", "amplitude": "amplitude of the axle-force spectrum (kN s, Hann)",
    "rim_z_mm": "rim vertical position (mm)", "theta_mrad": "belt rotation theta (mrad)",
    "y_mm": "belt lateral displacement y (mm)", "gamma_mrad": "belt camber rotation gamma (mrad)",
    "rim_y_mm": "rim lateral displacement (mm)", "slip_percent": "longitudinal slip (%)",
    "force_x_kN": "longitudinal force F_x (kN)", "slip_angle_deg": "slip angle alpha (deg, SAE)",
    "lateral_force_kN": "lateral force in road axes (kN, SAE sign)",
    "aligning_moment_Nm": "aligning moment M_z (N m, SAE)",
    "x_mm": "x, forward (mm)", "y_left_mm": "y, left (mm)", "pressure_kPa": "contact pressure (kPa)",
}


def _nearest(table: dict, v: float) -> str:
    return table[min(table, key=lambda k: abs(k - v))]


def pressure_color(psi: float) -> str:
    return _nearest(PRESSURE_COLORS, psi)


def load_color(kg: float) -> str:
    return _nearest(LOAD_COLORS, kg)


def pressure_label(psi: float) -> str:
    return f"{psi:.0f} psi ({psi * 6.894757:.0f} kPa)"


def load_label(kg: float) -> str:
    return f"{kg:g} kg ({kg * 9.81e-3:.1f} kN)"


def case_style(case, by: str) -> dict:
    """Line colour and label of a case, by "pressure" or "load"."""
    if by == "pressure":
        return {"color": pressure_color(case.pressure_psi), "label": pressure_label(case.pressure_psi)}
    return {"color": load_color(case.load_kg), "label": load_label(case.load_kg)}


def figure(size=FIGSIZE, ncols=1, nrows=1, **kw):
    plt.rcParams.update(RC)
    return plt.subplots(nrows, ncols, figsize=size, **kw)


def footnote(fig, source: str, quick: bool) -> None:
    text = f"data: {source}"
    if quick:
        text += "  |  QUICK CHECK: coarse mesh and short runs, not the study's numbers"
    fig.text(0.005, 0.005, text, fontsize=6, color="0.35", ha="left", va="bottom")


def save(fig, out, quick: bool):
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return atomic_savefig(fig, out, dpi=80 if quick else 200)


def parser(doc: str, default_out: str) -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--out", default=default_out, help="output image (.png, .pdf, .svg)")
    ap.add_argument("--from", dest="from_dir", default=None, metavar="DIR",
                    help="read results from a characterization or sweep folder instead of simulating")
    ap.add_argument("--quick", action="store_true",
                    help="simulate small (coarse ring, short runs, two conditions); low-resolution image")
    return ap


def done(out, curves: int, what: str) -> None:
    """The one line every script prints (tests read the curve count from it)."""
    print(f"wrote {out}: curves={curves} ({what})")


def guard(main) -> int:
    """Run a script's main; a user-fixable error (a missing folder, a bad config) is one line, exit 2."""
    try:
        return int(main() or 0)
    except JtireError as e:
        print(f"{sys.argv[0]}: error: {e}", file=sys.stderr)
        return 2


def time_curves(cases, signal: str, scale: float, ylabel: str, title: str, by: str, out, source, quick,
                legend=None, t_scale: float = 1e3, xlabel: str = LABELS["time_ms"]) -> int:
    """One curve per case of a recorded signal against time_s (decays, drops); legend(case) adds
    text after the case's label. Returns the number of curves."""
    fig, ax = figure()
    for c in cases:
        if signal not in c.signals:
            raise KeyError(f"{c.name}: no signal {signal!r} in its signals.csv (has {', '.join(c.signals)})")
        st = case_style(c, by)
        extra = legend(c) if legend else ""
        ax.plot(c.signals["time_s"] * t_scale, c.signals[signal] * scale, color=st["color"],
                label=st["label"] + (f": {extra}" if extra else ""))
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc="upper right")
    footnote(fig, source, quick)
    save(fig, out, quick)
    return len(cases)
