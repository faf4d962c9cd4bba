"""Study Figure 6-2: sidewall lateral translation decay, rigid belt (E07).

The rigid belt's lateral translation after the 2 x 2 kN lateral forces are released (rim
locked, no road), one curve per pressure, from the held pose to rest about the unloaded one; the stiffness and the
damping the experiment reduces (two peaks, or the damped-sine fit) in the legend.

    python paper_figures/fig6_2_sidewall_translation_decay.py --out runs/figures/fig6_2.png
    python paper_figures/fig6_2_sidewall_translation_decay.py --from runs/char --out fig6_2.png
    python paper_figures/fig6_2_sidewall_translation_decay.py --quick --out /tmp/fig6_2.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "sidewall_translation", "per_pressure"
TITLE = "Figure 6-2: sidewall translation decay, rigid belt (E07)"


def plot(cases, out, source, quick):
    def legend(c):
        k, C = c.quantities.get("k_by_N_per_m"), c.quantities.get("C_by_Ns_per_m")
        if not (k and C):
            return ""
        return f"k_by = {k / 1e3:.0f} kN/m, C_by = {C:.0f} N s/m"

    return _style.time_curves(cases, "y_m", 1e3, _style.LABELS["y_mm"], TITLE, "pressure", out, source,
                              quick, legend)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig6_2_sidewall_translation_decay.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "free decay per pressure")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
