"""Which peak of the shell's drum-cleat F_x is the ring's fore-aft mode: for each validation condition of a
characterization, the spindle F_x after the cleat of the shell (E04's record) and of the populated ring
(`rigid_ring.scenarios.drum_cleat`, what the validation runs), each read the way the validation reads it
(`spectra.first_mode` on the experiment's band, from the cleat's leaving) and also as every peak of its
padded spectrum above a tenth of the largest and every mode of a fixed four-mode fit, beside the ring's
linearized ringing fore-aft modes (`modes.fore_aft_modes` at the drum's speed).

    python benchmarks/drum_fore_aft_peaks.py runs/characterize            # its validation conditions
    python benchmarks/drum_fore_aft_peaks.py runs/characterize --condition 4625 120

Prints one block per condition and writes OUT/drum_fore_aft_peaks.json. A few seconds per condition after
compiling (one ring simulation, no shell run: the shell's records are read from the folder).
"""

import inspect
import sys
import time

import numpy as np
from inplane_storage import fore_aft
from lateral_storage import parse, save, setup

PEAK_FLOOR = 0.1  # spectral peaks listed down to this fraction of the band's largest
N_FIT = 4  # modes in the fixed fit: enough for two close modes beside the band's neighbours


def peaks(t, y, band, t_start):
    """The spectrum's local maxima in band above PEAK_FLOOR of the largest, by frequency: [(Hz, relative)],
    and the record's raw resolution (Hz)."""
    from jtire import spectra

    keep = t >= t_start
    raw = 1.0 / (np.count_nonzero(keep) * spectra.uniform_step(t[keep]))
    return sorted(spectra.spectrum_peaks(t, y, band, t_start=t_start, floor=PEAK_FLOOR)), raw


def read(t, y, band, t_start):
    """The validation's reading, the spectrum's peaks and the N_FIT-mode fit of one record."""
    from jtire import spectra

    first = spectra.first_mode(t, y, f_band=band, t_start=t_start)
    pk, raw = peaks(t, y, band, t_start)
    keep = t >= t_start
    mf = spectra._greedy_modal_fit(t[keep], y[keep], first.f_peak_Hz, N_FIT, "hann")
    order = np.argsort(mf.omega_n)
    modes = [(float(mf.omega_n[j] / (2 * np.pi)), float(mf.xi[j]), float(mf.amplitude[j])) for j in order]
    return {"metric_f_n_Hz": first.fn_fit_Hz, "metric_zeta": first.xi_fit, "metric_modes": first.n_modes_fit,
            "peaks_Hz_rel": pk, "raw_resolution_Hz": raw,
            "record_s": float(t[-1] - t_start), "fit_modes_Hz_zeta_amp_N": modes, "fit_rms_relative": mf.rms_relative}


def main(argv=None):
    a = parse(argv, __doc__.splitlines()[0], "runs/drum_fore_aft_peaks")
    from jtire import results
    from jtire.rigid_ring import scenarios
    from jtire.rigid_ring.params import derive
    from jtire.validate import _case_dir, _signals

    _, _, char, conds = setup(a)
    sig = inspect.signature(scenarios.drum_cleat).parameters
    speed, band = sig["speed"].default, sig["f_band"].default
    rows = []
    for kg, psi, c in conds:
        where, t0 = f"{kg:g} kg, {psi:g} psi", time.perf_counter()
        folder, row = _case_dir(a.char_dir, "drum_cleat", c["load_N"], c["pressure_Pa"]), char.row(c["load_N"],
                                                                                                    c["pressure_Pa"])
        if folder is None or row is None:
            print(f"{where}: no drum-cleat case or table row in {a.char_dir}", file=sys.stderr)
            continue
        info, s = results.read_result(folder)["info"], _signals(folder)
        if "axle_force_x_N" not in s:
            print(f"{where}: the shell's drum-cleat record has no spindle F_x", file=sys.stderr)
            continue
        shell_band = tuple(info["f_band_Hz"])
        shell = read(s["time_s"], s["axle_force_x_N"], shell_band,
                     float(info["t_cleat_leave_s"] - info["t_cleat_touch_s"]))
        d = derive(row, char.tire)
        r = scenarios.drum_cleat(d)
        ts = r.signals["time_s"]
        t_free = float(r.info["t_free_s"])  # the cleat has left the patch
        ring = read(ts, r.signals["spindle_F_x_N"], band, t_free)
        linear = fore_aft(d, speed, ring["metric_f_n_Hz"])[1]
        rows.append({"load_kg": kg, "pressure_psi": psi, "shell": shell, "ring": ring, "ring_linear_modes": linear,
                     "wall_s": time.perf_counter() - t0})
        print(f"{where}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

    def fmt(rd):
        pk = ", ".join(f"{f:.1f} ({m:.2f})" for f, m in rd["peaks_Hz_rel"])
        fm = ", ".join(f"{f:.1f} Hz / {z:.3f} / {abs(x):.0f} N" for f, z, x in rd["fit_modes_Hz_zeta_amp_N"])
        return (f"metric {rd['metric_f_n_Hz']:.2f} Hz, zeta {rd['metric_zeta']:.3f} ({rd['metric_modes']} modes); "
                f"record {rd['record_s']:.3f} s (bins {rd['raw_resolution_Hz']:.1f} Hz)\n"
                f"    spectrum peaks (relative): {pk}\n    {N_FIT}-mode fit (f_n / zeta / amplitude): {fm}")

    for r in rows:
        print(f"\n{r['load_kg']:g} kg, {r['pressure_psi']:g} psi")
        print(f"  shell: {fmt(r['shell'])}")
        print(f"  ring:  {fmt(r['ring'])}")
        print("  ring linear modes (f_n / zeta / x_b share): "
              + ", ".join(f"{f:.1f} / {z:.3f} / {x:.2f}" for f, z, x in r["ring_linear_modes"]))
    save(a, "drum_fore_aft_peaks", rows)


if __name__ == "__main__":
    main()
