"""Study Figure 6-4: sidewall camber-wise rotation decay, rigid belt (E08).

The rigid belt's camber-wise rotation after the two opposed 5 kN lateral forces are released
(rim locked, no road), one curve per pressure, from the held pose to rest about the unloaded one; the stiffness and the
damping the experiment reduces (two peaks, or the damped-sine fit) in the legend.

    python paper_figures/fig6_4_sidewall_camber_decay.py --out runs/figures/fig6_4.png
    python paper_figures/fig6_4_sidewall_camber_decay.py --from runs/char --out fig6_4.png
    python paper_figures/fig6_4_sidewall_camber_decay.py --quick --out /tmp/fig6_4.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "sidewall_camber", "per_pressure"
TITLE = "Figure 6-4: sidewall camber decay, rigid belt (E08)"


def plot(cases, out, source, quick):
    def legend(c):
        k, C = c.quantities.get("k_bgamma_Nm_per_rad"), c.quantities.get("C_bgamma_Nms_per_rad")
        if not (k and C):
            return ""
        return f"k_bgamma = {k / 1e3:.0f} kN m/rad, C_bgamma = {C:.1f} N m s/rad"

    return _style.time_curves(cases, "gamma_rad", 1e3, _style.LABELS["gamma_mrad"], TITLE, "pressure", out, source,
                              quick, legend)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig6_4_sidewall_camber_decay.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "free decay per pressure")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
