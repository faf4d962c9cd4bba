"""Study Figure 5-10: in-plane rotation decay of the sidewalls, rigid belt (E05).

The rigid belt's rotation about the axle after the 15 kN circumferential force is released
(rim locked, no road), one curve per pressure, from the held pose to rest about the unloaded one; the stiffness and the
damping the experiment reduces (two peaks, or the damped-sine fit) in the legend.

    python paper_figures/fig5_10_inplane_rotation_decay.py --out runs/figures/fig5_10.png
    python paper_figures/fig5_10_inplane_rotation_decay.py --from runs/char --out fig5_10.png
    python paper_figures/fig5_10_inplane_rotation_decay.py --quick --out /tmp/fig5_10.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "inplane_rotation", "per_pressure"
TITLE = "Figure 5-10: in-plane rotation decay, rigid belt (E05)"


def plot(cases, out, source, quick):
    def legend(c):
        k, C = c.quantities.get("k_btheta_Nm_per_rad"), c.quantities.get("C_btheta_Nms_per_rad")
        if not (k and C):
            return ""
        return f"k_btheta = {k / 1e3:.0f} kN m/rad, C_btheta = {C:.1f} N m s/rad"

    return _style.time_curves(cases, "theta_rad", 1e3, _style.LABELS["theta_mrad"], TITLE, "pressure", out, source,
                              quick, legend)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_10_inplane_rotation_decay.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "free decay per pressure")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
