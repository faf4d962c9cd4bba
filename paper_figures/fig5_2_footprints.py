"""Study Figure 5-2 counterpart: contact pressure over the footprint at the nine conditions (E01).

One panel per condition (rows: pressure, columns: load): every contact point in contact drawn as
its share of the tread (circumferential x lateral extent on the reference shape), coloured by the
contact pressure the model transmits there (the penalty normal force over the point's area,
`jtire.contact_pressure`), on one colour scale; the simulated 2a x w and the integrated pressure
over the load in each title. The study's measured 2a x w at rated load and pressure (the tire
file's [reference]) is drawn as a dashed box in that panel.

Reads each case's contact-pressure table: the columns point_x_m, point_y_m, contact_pressure_Pa,
point_dx_m, point_dy_m, point_area_m2 in signals.csv or in contact_pressure.csv beside result.json
(what `_data.run_cases` writes for E01).

    python paper_figures/fig5_2_footprints.py --out runs/figures/fig5_2.png
    python paper_figures/fig5_2_footprints.py --from runs/char --out fig5_2.png
    python paper_figures/fig5_2_footprints.py --quick --out /tmp/fig5_2.png
"""

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

from jtire.config import load_tire  # noqa: E402
from jtire.errors import ConfigError  # noqa: E402
from jtire.resources import config_path  # noqa: E402

EXPERIMENT, KIND = "footprint", "grid"
COLUMNS = ("point_x_m", "point_y_m", "contact_pressure_Pa", "point_dx_m", "point_dy_m", "point_area_m2")


def pressure_table(case) -> dict:
    for table in (case.signals, case.tables.get("contact_pressure", {})):
        if all(k in table for k in COLUMNS):
            return table
    raise ConfigError(f"{case.name}: no contact-pressure table (columns {', '.join(COLUMNS)} in signals.csv or "
                      "contact_pressure.csv)")


def plot(cases, out, source, quick):
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Rectangle

    pressures = sorted({round(c.pressure_psi, 6) for c in cases})
    loads = sorted({round(c.load_kg, 6) for c in cases})
    nr, nc = len(pressures), len(loads)
    fig, axes = _style.figure((3.3 * nc + 1.2, 2.9 * nr + 0.4), ncols=nc, nrows=nr, squeeze=False,
                              sharex=True, sharey=True)
    tables = [pressure_table(c) for c in cases]
    vmax = max(float(np.max(t["contact_pressure_Pa"])) for t in tables) * 1e-3
    ref = load_tire(config_path("tires", "xone_xda.toml")).reference
    ext_x = max(max(float(np.max(np.abs(t["point_x_m"]) + t["point_dx_m"] / 2)) for t in tables),
                ref["footprint_length_mm"] / 2) * 1e3 + 15  # mm (the reference is SI: m)
    ext_y = max(max(float(np.max(np.abs(t["point_y_m"]) + t["point_dy_m"] / 2)) for t in tables),
                ref["footprint_width_mm"] / 2) * 1e3 + 15
    coll = None
    for c, t in zip(cases, tables):
        ax = axes[pressures.index(round(c.pressure_psi, 6))][loads.index(round(c.load_kg, 6))]
        x, y = t["point_x_m"] * 1e3, t["point_y_m"] * 1e3
        dx, dy = t["point_dx_m"] * 1e3, t["point_dy_m"] * 1e3
        rects = [Rectangle((xi - a / 2, yi - b / 2), a, b) for xi, yi, a, b in zip(x, y, dx, dy)]
        coll = PatchCollection(rects, cmap="viridis", edgecolor="w", linewidth=0.2)
        coll.set_array(t["contact_pressure_Pa"] * 1e-3)
        coll.set_clim(0.0, vmax)
        ax.add_collection(coll)
        total = float(np.sum(t["contact_pressure_Pa"] * t["point_area_m2"]))
        q = c.quantities
        ax.set_title(f"{c.pressure_psi:.0f} psi, {c.load_kg:g} kg\n2a = {q['contact_length_m'] * 1e3:.0f} mm, "
                     f"w = {q['contact_width_m'] * 1e3:.0f} mm, sum p A / F_z = {total / c.condition['load_N']:.3f}",
                     fontsize=7)
        if abs(c.pressure_psi - _data.RATED_PSI) < 1e-6 and abs(c.load_kg - _data.RATED_KG) < 1e-6 \
                and ref["footprint_length_mm"] > 0:
            L, W = ref["footprint_length_mm"] * 1e3, ref["footprint_width_mm"] * 1e3
            ax.add_patch(Rectangle((-L / 2, -W / 2), L, W, fill=False, ls="--", ec="r", lw=1,
                                   label="measured 2a x w"))
            ax.legend(loc="lower right", fontsize=6)
        ax.set_aspect("equal")
    for ax in axes.flat:
        ax.set_xlim(-ext_x, ext_x)
        ax.set_ylim(-ext_y, ext_y)
    for ax in axes[-1]:
        ax.set_xlabel(_style.LABELS["x_mm"])
    for ax in axes[:, 0]:
        ax.set_ylabel(_style.LABELS["y_left_mm"])
    fig.colorbar(coll, ax=axes, label=_style.LABELS["pressure_kPa"], shrink=0.8)
    fig.suptitle("Figure 5-2 counterpart: contact pressure over the footprint (E01)")
    _style.footnote(fig, source, quick)
    from jtire.io import atomic_savefig

    atomic_savefig(fig, out, dpi=80 if quick else 200)
    return len(cases)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_2_footprints.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "footprint panels")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
