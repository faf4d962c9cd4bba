"""Study Figure 6-8: steady lateral force against slip angle at three loads (E10).

The free-rolling tire dragged at each slip angle (SAE: positive alpha, the road pushes the wheel
to its left, F_y,SAE < 0); lateral force in road axes F_y cos(alpha) - F_x sin(alpha) with its
standard error over the measuring window, and the cornering-stiffness line -k_f alpha over the
fitted range, per load at 120 psi.

    python paper_figures/fig6_8_lateral_force_slip.py --out runs/figures/fig6_8.png
    python paper_figures/fig6_8_lateral_force_slip.py --from runs/char --out fig6_8.png
    python paper_figures/fig6_8_lateral_force_slip.py --quick --out /tmp/fig6_8.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "cornering", "loads"


def slip_curves(cases, y_name, err_name, scale, slope_name, line, ylabel, title, range_name, slope_text, out,
                source, quick):
    """Shared by Figures 6-8 and 6-9: a steady quantity (times `scale`) against slip angle per load,
    with its standard error, and the experiment's fitted slope line(k, alpha_rad) over its range."""
    import numpy as np

    fig, ax = _style.figure()
    for c in cases:
        st = _style.case_style(c, "load")
        a, y = c.signals["slip_angle_deg"], c.signals[y_name]
        err = c.signals.get(err_name)
        k = c.quantities[slope_name]
        ax.errorbar(a, y * scale, yerr=None if err is None else err * scale, marker="o", ms=4, color=st["color"],
                    capsize=2, label=f"{st['label']}: {slope_text(k)}")
        lo, hi = c.quantities[range_name]
        aa = np.linspace(lo, hi, 10)
        ax.plot(aa, line(k, np.radians(aa)), color=st["color"], ls="--", lw=2, alpha=0.7)
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel(_style.LABELS["slip_angle_deg"])
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(loc="best")
    _style.footnote(fig, source, quick)
    _style.save(fig, out, quick)
    return len(cases)


def plot(cases, out, source, quick):
    # lateral_force_N is in SAE signs (negative for positive alpha) and k_f is positive: the line is -k_f alpha
    return slip_curves(cases, "lateral_force_N", "lateral_force_stderr_N", 1e-3, "k_f_N_per_rad",
                       lambda k, a: -k * a * 1e-3, _style.LABELS["lateral_force_kN"],
                       "Figure 6-8: lateral force vs slip angle (E10, 120 psi)", "k_f_range_deg",
                       lambda k: f"k_f = {k / 1e3:.0f} kN/rad (dashed: its fit range)", out, source, quick)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig6_8_lateral_force_slip.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "lateral force curve per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
