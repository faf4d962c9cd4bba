"""Study Figure 5-12: longitudinal (traction) force against longitudinal slip on the drum (E06).

The tire, loaded against a 3.4 m drum, driven through the slip range; the steady longitudinal force
against slip per load at 120 psi, with the longitudinal-stiffness line k_k * slip over the fitted
range. Reads E06's signals `slip` (fraction) and `force_x_N` and its quantities k_k_N_per_slip,
k_cx_N_per_m (E06 is being rebuilt with a free drum: these names follow its specification).

    python paper_figures/fig5_12_traction_force_slip.py --out runs/figures/fig5_12.png
    python paper_figures/fig5_12_traction_force_slip.py --from runs/char --out fig5_12.png
    python paper_figures/fig5_12_traction_force_slip.py --quick --out /tmp/fig5_12.png
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "traction", "loads"
SLIP, FORCE = "slip", "force_x_N"


def plot(cases, out, source, quick):
    fig, ax = _style.figure()
    for c in cases:
        st = _style.case_style(c, "load")
        s, f = c.signals[SLIP], c.signals[FORCE]
        k, kcx = c.quantities.get("k_k_N_per_slip"), c.quantities.get("k_cx_N_per_m")
        text = (f": k_k = {k / 1e3:.0f} kN/unit slip" if k else "") + (f", k_cx = {kcx / 1e6:.2f} MN/m" if kcx else "")
        ax.plot(s * 100, f * 1e-3, marker="o", ms=3, color=st["color"], label=st["label"] + text)
        if k:
            ss = np.linspace(0.0, min(0.1, float(np.nanmax(s))), 10)
            ax.plot(ss * 100, k * ss * 1e-3, color=st["color"], ls="--", lw=1)
    ax.axhline(0.0, color="0.5", lw=0.8)
    ax.set_xlabel(_style.LABELS["slip_percent"])
    ax.set_ylabel(_style.LABELS["force_x_kN"])
    ax.set_title("Figure 5-12: traction force vs slip on a 3.4 m drum (E06, 120 psi; dashed: k_k slip)")
    ax.legend(loc="best")
    _style.footnote(fig, source, quick)
    _style.save(fig, out, quick)
    return len(cases)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_12_traction_force_slip.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "traction curve per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
