"""Study Figure 5-6: vertical axle force after the cleat impact and its spectrum (E03 drum-cleat).

Left: the tire's vertical force on the locked rim against time from the cleat's first touch, one
curve per load at 120 psi. Right: the amplitude spectrum of the free response (from the time the
cleat leaves the patch; Hann window, zoomed to the experiment's band by `jtire.spectra`), with the
first in-plane mode E03 reports marked.

    python paper_figures/fig5_6_cleat_axle_force.py --out runs/figures/fig5_6.png
    python paper_figures/fig5_6_cleat_axle_force.py --from runs/char --out fig5_6.png
    python paper_figures/fig5_6_cleat_axle_force.py --quick --out /tmp/fig5_6.png
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _data  # noqa: E402
import _style  # noqa: E402

from jtire.spectra import amplitude_spectrum  # noqa: E402

EXPERIMENT, KIND = "drum_cleat", "loads"
RESOLUTION_HZ = 0.1  # spacing of the plotted spectrum (zoomed DFT on the band)


def plot(cases, out, source, quick):
    fig, (ax_t, ax_f) = _style.figure(_style.WIDE, ncols=2)
    for c in cases:
        st = _style.case_style(c, "load")
        t, f = c.signals["time_s"], c.signals["axle_force_N"]
        ax_t.plot(t * 1e3, f * 1e-3, color=st["color"], label=st["label"])
        t_free = c.info["t_cleat_leave_s"] - c.info["t_cleat_touch_s"]  # time_s is counted from the touch
        free = t >= t_free
        fr, mag, raw, _ = amplitude_spectrum(t[free], f[free], pad_to_resolution=RESOLUTION_HZ,
                                             f_band=c.info["f_band_Hz"])
        dt = t[1] - t[0]
        ax_f.plot(fr, mag * dt * 1e-3, color=st["color"],
                  label=f"{st['label']}: f1 = {c.quantities['first_mode_Hz']:.2f} Hz (raw bins {raw:.2g} Hz)")
        ax_f.axvline(c.quantities["first_mode_Hz"], color=st["color"], ls=":", lw=1)
    ax_t.axvline(0.0, color="0.5", lw=0.8)
    ax_t.set_xlabel("time from the cleat's first touch (ms)")
    ax_t.set_ylabel(_style.LABELS["axle_force_kN"])
    ax_t.set_title("axle force, 50 km/h over a 20 cm cleat")
    ax_t.legend(loc="best")
    ax_f.set_xlabel(_style.LABELS["frequency_Hz"])
    ax_f.set_ylabel(_style.LABELS["amplitude"])
    ax_f.set_title("spectrum of the free response (dotted: E03's first mode)")
    ax_f.legend(loc="upper right")
    fig.suptitle("Figure 5-6: drum-cleat axle force and its spectrum (E03, 120 psi)")
    _style.footnote(fig, source, quick)
    _style.save(fig, out, quick)
    return len(cases)


def main(argv=None) -> int:
    args = _style.parser(__doc__, "runs/figures/fig5_6_cleat_axle_force.png").parse_args(argv)
    cases, source = _data.obtain(EXPERIMENT, KIND, args)
    n = plot(cases, args.out, source, args.quick)
    _style.done(args.out, n, "axle force and spectrum per load")
    return 0


if __name__ == "__main__":
    raise SystemExit(_style.guard(main))
