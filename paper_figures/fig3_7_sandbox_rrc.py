"""Study Figure 3-7: rolling-resistance coefficient against vertical load in the sandbox.

Both left-side axles through a loose dry-sand ditch at 5 mph: the pusher (LM, wide-base) and the
steer (LF) tire. Every run as a point (120 psi filled, 80 psi hollow), configuration means with
their standard errors, and each axle's linear and power-law trends of its 120 psi runs (the
linear one with its 95 % confidence band).

    python paper_figures/fig3_7_sandbox_rrc.py --out runs/figures/fig3_7_sandbox_rrc.png [--quick]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from jtire.data import PSI_PA, analyze  # noqa: E402
from jtire.io import atomic_savefig  # noqa: E402

AXLES = (("LM", "sandbox_LM_120psi", "C0", "pusher LM (445/50R22.5)"),
         ("LF", "sandbox_LF_120psi", "C1", "steer LF (275/80R22.5)"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs/figures/fig3_7_sandbox_rrc.png")
    ap.add_argument("--quick", action="store_true", help="coarse curves, low resolution")
    ap.add_argument("--data-dir", default=None)
    args = ap.parse_args(argv)

    s = analyze(args.data_dir)
    sand = s.sandbox
    kn = 1e-3  # N -> kN for the axis only

    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    for axle, fit_name, color, name in AXLES:
        on = sand.mask(axle=axle)
        at120 = on & sand.mask(pressure_psi=120.0)
        low = on & ~at120
        ax.scatter(sand.fz_n[at120] * kn, sand.rrc_table[at120], s=14, color=color, alpha=0.6)
        ax.scatter(sand.fz_n[low] * kn, sand.rrc_table[low], s=14, facecolors="none",
                   edgecolors=color)
        for a in (a for a in s.sandbox_averages if a.axle == axle):
            filled = np.isclose(a.pressure_pa, 120.0 * PSI_PA)
            ax.errorbar(a.fz_n * kn, a.rrc_study, yerr=a.rrc_sem, fmt="s", ms=6, color=color,
                        mec="k", mfc=color if filled else "w", capsize=3, zorder=3)
        fits = s.fits[fit_name]
        grid = np.linspace(0.9 * fits.fz_n.min(), 1.1 * fits.fz_n.max(), 30 if args.quick else 200)
        lin, pw = fits.linear.predict(grid), fits.power.predict(grid)
        ax.plot(grid * kn, lin.mean, color=color, label=f"{name}: linear fit, 95 % CI")
        ax.fill_between(grid * kn, lin.lower, lin.upper, color=color, alpha=0.15, lw=0)
        ax.plot(grid * kn, pw.mean, "--", color=color, label=f"{name}: power law")
    ax.scatter([], [], s=14, facecolors="none", edgecolors="0.3", label="80 psi runs (not fitted)")
    ax.plot([], [], "s", color="0.6", mec="k", label="configuration mean +- s.e.")

    ax.set_xlabel("vertical load F_z (kN)")
    ax.set_ylabel("RRC1 = F_x / F_z")
    ax.set_title("Sandbox (loose dry sand), 5 mph, left side of the truck")
    ax.set_ylim(0.0, None)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    atomic_savefig(fig, args.out, dpi=80 if args.quick else 200)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
