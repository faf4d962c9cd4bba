"""Study Figure 3-5: rolling-resistance coefficient against vertical load on the rigid test track.

Every run as a point (120 psi filled, 80 psi hollow), configuration means with their standard
errors, the linear and power-law trends of the 120 psi runs with their confidence bands, and the
study's two calibration targets (configs/reference_xone_xda.toml) as stars.

    python paper_figures/fig3_5_track_rrc.py --out runs/figures/fig3_5_track_rrc.png [--quick]
"""

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from jtire.data import PSI_PA, analyze  # noqa: E402
from jtire.io import atomic_savefig  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs/figures/fig3_5_track_rrc.png")
    ap.add_argument("--quick", action="store_true", help="coarse curves, low resolution")
    ap.add_argument("--data-dir", default=None)
    ap.add_argument("--rrc", choices=("table", "ratio"), default="table")
    args = ap.parse_args(argv)

    s = analyze(args.data_dir, rrc_source=args.rrc)
    track, fits = s.track, s.fits["track_120psi"]
    rrc = track.rrc(args.rrc)
    kn = 1e-3  # N -> kN for the axis only

    fig, ax = plt.subplots(figsize=(7.0, 4.8))
    at120 = track.mask(pressure_psi=120.0)
    ax.scatter(track.fz_n[at120] * kn, rrc[at120], s=14, color="0.45", label="runs, 120 psi")
    ax.scatter(track.fz_n[~at120] * kn, rrc[~at120], s=14, facecolors="none", edgecolors="0.45",
               label="runs, 80 psi")
    for a in s.track_averages:
        mean = a.rrc_study if args.rrc == "table" else a.rrc_mean_of_ratios
        filled = np.isclose(a.pressure_pa, 120.0 * PSI_PA)
        ax.errorbar(a.fz_n * kn, mean, yerr=a.rrc_sem, fmt="s" if filled else "D", ms=6,
                    color="k", mfc="k" if filled else "w", capsize=3, zorder=3)
        ax.annotate(a.label, (a.fz_n * kn, mean), textcoords="offset points", xytext=(6, -12),
                    fontsize=7)
    ax.plot([], [], "ks", label="configuration mean +- s.e.")

    targets = s.targets
    hi = max(max(track.fz_n), max(t.load_n for t in targets))
    grid = np.linspace(0.8 * min(track.fz_n), 1.05 * hi, 40 if args.quick else 300)
    for fit, color, name in ((fits.linear, "C0", "linear"), (fits.power, "C3", "power law")):
        p = fit.predict(grid)
        ax.plot(grid * kn, p.mean, color=color, label=f"{name} fit (120 psi runs)")
        ax.fill_between(grid * kn, p.lower, p.upper, color=color, alpha=0.2, lw=0,
                        label=f"{name}: 95 % CI of the trend")
    ax.plot([t.load_n * kn for t in targets], [t.rrc for t in targets], "*", ms=14, color="C2",
            mec="k", zorder=4, label="study calibration targets (RRC "
            + ", ".join(f"{t.rrc:.4f}" for t in targets) + ")")

    ax.set_xlabel("vertical load F_z (kN)")
    ax.set_ylabel("RRC1 = F_x / F_z")
    ax.set_title("Test track, wide-base pusher tire, 15 mph")
    ax.set_ylim(0.0, 1.12 * max(max(rrc), max(t.rrc for t in targets)))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    atomic_savefig(fig, args.out, dpi=80 if args.quick else 200)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
