"""Study Figure 5-4: vertical load against deflection at three inflation pressures (E02).

The quasi-static ramp of E02 (rim load 0 -> 60 kN on a rigid flat road) at 70, 120 and 150 psi and
4625 kg: the load on the rim against the rim's travel from first contact, with the secant k_sv at
the stated load in the legend, and the study's calibration point (50 kN, 39.06 mm at 120 psi,
configs/reference_xone_xda.toml) as a star.

    python paper_figures/fig5_4_vertical_load_deflection.py --out runs/figures/fig5_4.png
    python paper_figures/fig5_4_vertical_load_deflection.py --from runs/char --out fig5_4.png
    python paper_figures/fig5_4_vertical_load_deflection.py --quick --out /tmp/fig5_4.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

from jtire.config import read_toml  # noqa: E402
from jtire.resources import config_path  # noqa: E402

EXPERIMENT, KIND = "vertical_stiffness", "pressures"


def plot(cases, out, source, quick):
    fig, ax = _style.figure()
    for c in cases:
        st = _style.case_style(c, "pressure")
        k = c.quantities.get("k_sv_N_per_m")
        ax.plot(c.signals["deflection_m"] * 1e3, c.signals["load_N"] * 1e-3, color=st["color"],
                label=st["label"] + (f": k_sv = {k / 1e3:.0f} kN/m" if k else ""))
    ref = read_toml(config_path("reference_xone_xda.toml"))["calibration"]["targets"]["vertical_deflection"]
    ax.plot(ref["deflection_mm"], ref["applied_force_kN"], **_style.MEASURED,
            label=f"study calibration target, 120 psi ({ref['stiffness_kN_per_m']:g} kN/m)")
    ax.set_xlabel(_style.LABELS["deflection_mm"])
    ax.set_ylabel(_style.LABELS["load_kN"])
    ax.set_title("Figure 5-4: static vertical load-deflection (E02)")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.legend(loc="upper left")
    _style.footnote(fig, source, quick)
    _style.save(fig, out, quick)
    return len(cases)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_4_vertical_load_deflection.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "load-deflection per pressure")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
