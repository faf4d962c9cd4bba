"""Study Figure 6-9: steady aligning moment against slip angle at three loads (E10).

M_z (SAE) of the free-rolling tire at each slip angle with its standard error over the measuring
window, and the aligning-stiffness line k_m alpha over its fitted range (0-3 deg), per load at
120 psi. The same runs as Figure 6-8.

    python paper_figures/fig6_9_aligning_moment_slip.py --out runs/figures/fig6_9.png
    python paper_figures/fig6_9_aligning_moment_slip.py --from runs/char --out fig6_9.png
    python paper_figures/fig6_9_aligning_moment_slip.py --quick --out /tmp/fig6_9.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402
from fig6_8_lateral_force_slip import EXPERIMENT, KIND, slip_curves  # noqa: E402


def plot(cases, out, source, quick):
    return slip_curves(cases, "M_z_SAE_Nm", "M_z_stderr_Nm", 1.0, "k_m_Nm_per_rad", lambda k, a: k * a,
                       _style.LABELS["aligning_moment_Nm"], "Figure 6-9: aligning moment vs slip angle (E10, 120 psi)",
                       "k_m_range_deg", lambda k: f"k_m = {k:.0f} N m/rad (dashed: its fit range)", out, source, quick)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig6_9_aligning_moment_slip.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "aligning moment curve per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
