"""Study Figure 5-8: drop test, the rim's vertical motion against time (E04).

The wheel, held 20 mm above the road with the condition's load on the rim, is released with only
its vertical motion free: it falls, bounces and rings down. One curve per load at 120 psi, with
C_tot (two-peak or fitted, as E04 reports it) in the legend.

    python paper_figures/fig5_8_drop_test.py --out runs/figures/fig5_8.png
    python paper_figures/fig5_8_drop_test.py --from runs/char --out fig5_8.png
    python paper_figures/fig5_8_drop_test.py --quick --out /tmp/fig5_8.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "drop_test", "loads"


def plot(cases, out, source, quick):
    def legend(c):
        C = c.quantities.get("C_tot_Ns_per_m")
        return f"C_tot = {C:.0f} N s/m" if C else ""

    return _style.time_curves(cases, "rim_z_m", 1e3, _style.LABELS["rim_z_mm"] + ", from the inflated pose",
                              "Figure 5-8: drop test from 20 mm (E04, 120 psi)", "load", out, source, quick, legend)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_8_drop_test.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "rim height per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
