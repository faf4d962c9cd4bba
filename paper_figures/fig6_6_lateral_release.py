"""Study Figure 6-6: lateral release of the loaded tire, the rim's lateral motion (E09).

The tire, loaded on the road, is pushed sideways by 5 kN at the rim centre (friction holds the
patch); the force is ramped off and the rim's lateral free decay is recorded (E09 with
decay_s > 0; the script sets lateral_stiffness.decay_s when it simulates). One curve per load at
120 psi, displacement from the loaded pose before the lateral force, k_l and C_l in the legend.

    python paper_figures/fig6_6_lateral_release.py --out runs/figures/fig6_6.png
    python paper_figures/fig6_6_lateral_release.py --from runs/char --out fig6_6.png
    python paper_figures/fig6_6_lateral_release.py --quick --out /tmp/fig6_6.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

EXPERIMENT, KIND = "lateral_stiffness", "loads"


def plot(cases, out, source, quick):
    def legend(c):
        k, C = c.quantities.get("k_l_N_per_m"), c.quantities.get("C_l_Ns_per_m")
        return f"k_l = {k / 1e3:.0f} kN/m, C_l = {C:.0f} N s/m" if k and C else ""

    if any("rim_y_m" not in c.signals for c in cases):
        from jtire.errors import ConfigError

        raise ConfigError("lateral_stiffness results without the release decay (run E09 with decay_s > 0)")
    return _style.time_curves(cases, "rim_y_m", 1e3, _style.LABELS["rim_y_mm"] + ", from the loaded pose",
                              "Figure 6-6: lateral release of the loaded tire (E09, 120 psi)", "load", out, source,
                              quick, legend)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig6_6_lateral_release.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "rim lateral decay per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
