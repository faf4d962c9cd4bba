"""The rigid ring's in-plane modes on the rubber's storage moduli: for each validation condition of a
characterization, the in-plane springs pushed statically on the long-term moduli and on the storage moduli
(`validate.storage_tire`) at the shell's own frequencies: E02's tangent at the drop bounce frequency, E13's
k_bx and E05's k_btheta at the drum-cleat fore-aft frequency; then the ring's linearized bounce
(`modes.vertical_modes`) and fore-aft / wind-up mode (`modes.fore_aft_modes`, the mode nearest the one the
ring's own drum-cleat spectrum reads, followed as the springs change) on the static and on the storage springs.

    python benchmarks/inplane_storage.py runs/characterize            # its validation conditions
    python benchmarks/inplane_storage.py runs/characterize --condition 4625 120

Prints one markdown table and every ringing fore-aft mode (also with the tread's k_k x 0.5 and x 2), and
writes OUT/inplane_storage.json. Default mesh: about 20 s per condition on 2 cores after compiling (six
static pushes).
"""

import dataclasses
import inspect
import sys
import time

from lateral_storage import parse, save, setup, storage_ratio

CONTACT_SCALES = (0.5, 2.0)  # the tread's longitudinal stiffness scaled: how the ring's modes follow the contact


def fore_aft(d, speed, target):
    """The ringing fore-aft mode of d nearest target (Hz): (f, zeta, x_b share)."""
    from jtire.rigid_ring.diagnosis_drum import RINGING_ZETA  # the diagnosis's: no peak in a spectrum above it
    from jtire.rigid_ring.modes import fore_aft_modes

    ms = [m for m in fore_aft_modes(d, speed) if m[1] < RINGING_ZETA]
    return min(ms, key=lambda m: abs(m[0] - target)), ms


def main(argv=None):
    a = parse(argv, __doc__.splitlines()[0], "runs/inplane_storage")
    from jtire.rigid_ring import scenarios
    from jtire.rigid_ring.modes import vertical_modes
    from jtire.rigid_ring.params import derive
    from jtire.validate import shell_metrics

    plan, proto, char, conds = setup(a)
    speed = inspect.signature(scenarios.drum_cleat).parameters["speed"].default  # the validation's drum
    rows = []
    for kg, psi, c in conds:
        shell = shell_metrics(a.char_dir, c["load_N"], c["pressure_Pa"])[0]
        f_b, f_x = shell.get("drop.bounce_f_Hz"), shell.get("drum.fore_aft_mode_Hz")
        row = char.row(c["load_N"], c["pressure_Pa"])
        if f_b is None or f_x is None or row is None:
            print(f"{kg:g} kg, {psi:g} psi: no drop, drum fore-aft or table row in {a.char_dir}", file=sys.stderr)
            continue
        t0, where, road_free = time.perf_counter(), f"{kg:g} kg, {psi:g} psi", {"pressure_Pa": c["pressure_Pa"]}
        ratio = {"k_sv_tangent_N_per_m": storage_ratio(plan, proto, "vertical_stiffness", "k_sv_tangent_N_per_m",
                                                       c, f_b, where),
                 "k_bx_N_per_m": storage_ratio(plan, proto, "sidewall_longitudinal", "k_bx_N_per_m", road_free,
                                               f_x, where),
                 "k_btheta_Nm_per_rad": storage_ratio(plan, proto, "inplane_rotation", "k_btheta_Nm_per_rad",
                                                      road_free, f_x, where)}
        d = derive(row, char.tire)  # the static pushes' springs
        dv = derive(dataclasses.replace(row, q=row.q | {"k_sv_tangent_N_per_m": row.q["k_sv_tangent_N_per_m"]
                                                        * ratio["k_sv_tangent_N_per_m"]}), char.tire)
        f_metric = scenarios.drum_cleat(d).quantities["F_x_f_n_fit_Hz"]  # what the validation compares
        m0, ringing = fore_aft(d, speed, f_metric)
        dx = dataclasses.replace(d, k_bx=d.k_bx * ratio["k_bx_N_per_m"],
                                 k_btheta=d.k_btheta * ratio["k_btheta_Nm_per_rad"])
        m1, _ = fore_aft(dx, speed, m0[0])
        # the contact's share: the ring's ringing modes with its tread's k_k (and k_cx = k_k / a) scaled
        contact = {m: fore_aft(dataclasses.replace(d, k_k=d.k_k * m, k_cx=d.k_cx * m), speed, m0[0])[1]
                   for m in CONTACT_SCALES}
        rows.append({"load_kg": kg, "pressure_psi": psi, "ratios": ratio,
                     "shell_bounce_Hz": f_b, "ring_bounce_Hz": vertical_modes(d)[0][0],
                     "ring_bounce_storage_Hz": vertical_modes(dv)[0][0],
                     "shell_fore_aft_Hz": f_x, "ring_fore_aft_metric_Hz": f_metric, "ring_fore_aft_Hz": m0[0],
                     "ring_fore_aft_storage_Hz": m1[0], "ring_fore_aft_ringing": ringing,
                     "ring_fore_aft_ringing_k_k_scaled": contact,
                     "wall_s": time.perf_counter() - t0})
        print(f"{where}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

    def fp(x, ref):
        return f"{x:.2f} ({100 * (x / ref - 1):+.1f} %)"

    print("| condition | E02, E13, E05 storage/static | shell bounce Hz | ring bounce | x E02's | "
          "shell fore-aft Hz | ring fore-aft | x E13's, E05's |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        ks = ", ".join(f"{v:.3f}" for v in r["ratios"].values())
        print(f"| {r['load_kg']:g} kg, {r['pressure_psi']:g} psi | {ks} | {r['shell_bounce_Hz']:.2f} | "
              f"{fp(r['ring_bounce_Hz'], r['shell_bounce_Hz'])} | {fp(r['ring_bounce_storage_Hz'], r['shell_bounce_Hz'])} | "
              f"{r['shell_fore_aft_Hz']:.2f} | {fp(r['ring_fore_aft_Hz'], r['shell_fore_aft_Hz'])} | "
              f"{fp(r['ring_fore_aft_storage_Hz'], r['shell_fore_aft_Hz'])} |")
    for r in rows:
        ms = ", ".join(f"{f:.2f} Hz (zeta {z:.2f}, x_b {s:.2f})" for f, z, s in r["ring_fore_aft_ringing"])
        print(f"{r['load_kg']:g} kg, {r['pressure_psi']:g} psi: ring's drum spectrum reads "
              f"{r['ring_fore_aft_metric_Hz']:.2f} Hz; its ringing fore-aft modes {ms}")
        for m, modes in r["ring_fore_aft_ringing_k_k_scaled"].items():
            print(f"  k_k x {m:g}: " + ", ".join(f"{f:.2f} Hz (x_b {s:.2f})" for f, _, s in modes))
    print("wrote", save(a, "inplane_storage.json", rows))


if __name__ == "__main__":
    main()
