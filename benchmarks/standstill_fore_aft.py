"""The shell's standstill fore-aft stiffness and the contact spring it implies: for each validation condition
of a characterization, the shell tire inflated, loaded on the road by E01's static path and then pushed
fore-aft at the rim (rim x and z free, its spin held, the patch held by friction) in two static levels,
on the long-term moduli and on the storage moduli (`validate.storage_tire`) at the shell's drum-cleat
fore-aft frequency. C_x = F / x is the rigid ring's LONGITUDINAL_STIFFNESS, 1/C_x = 1/k_cx + 1/k_bx +
r_b^2/k_btheta (docs/rigid-ring.md, "The .tir file"); with E13's k_bx and E05's k_btheta from the table it
gives the contact spring k_cx the shell's patch has, beside the ring's k_cx = k_k / a. Then the ring's
ringing fore-aft modes and its drum-cleat run (what the validation reads) with that contact spring (its
relaxation length k_k / k_cx in place of a, the same slip stiffness k_k).

    python benchmarks/standstill_fore_aft.py runs/characterize            # its validation conditions
    python benchmarks/standstill_fore_aft.py runs/characterize --condition 4625 120 --force-kN 2

Prints one markdown table, every ringing fore-aft mode and the drum-cleat readings, and writes
OUT/standstill_fore_aft.json. Default mesh: about 25 s per condition on 2 cores (two static paths, two ring runs).
"""

import dataclasses
import inspect
import sys
import time

import numpy as np
from inplane_storage import fore_aft
from lateral_storage import parse, save, setup


def push(model, params, pressure, load, forces, where):
    """E14's static path (`experiments.standstill`) to `load`, then the rim forces `forces` (N, +x):
    [(F, x from the loaded state, the patch's F_x)] per level (long-term moduli of `params`)."""
    import jax.numpy as jnp

    from jtire import equilibrium as EQ
    from jtire.experiments.standstill import _fore_aft_path_jit
    from jtire.experiments.static_path import STATIC_LOADS

    loads = load * jnp.arange(1, STATIC_LOADS + 1) / STATIC_LOADS
    st = _fore_aft_path_jit(model, params, pressure, loads, jnp.asarray(forces, jnp.float64))
    EQ.check_static(st["infos"], lambda k: f"{where}: static level {k}")
    EQ.check_static(st["fore_aft_infos"], lambda k: f"{where}: fore-aft level {k}")
    q, contact = np.asarray(st["fore_aft_q"]), np.asarray(st["fore_aft_contact"])
    x0 = float(np.asarray(st["q"])[-1, 0])
    return [(float(fx), float(q[i, 0] - x0), float(contact[i, 0])) for i, fx in enumerate(forces)]


def main(argv=None):
    a = parse(argv, __doc__.splitlines()[0], "runs/standstill_fore_aft",
              lambda ap: ap.add_argument("--force-kN", type=float, default=2.0,
                                         help="the rim's fore-aft force, pushed in two levels (F/2, F)"))
    from jtire.rigid_ring import scenarios
    from jtire.rigid_ring.params import derive
    from jtire.tire import make_tire
    from jtire.validate import shell_metrics, storage_tire

    plan, _, char, conds = setup(a)
    speed = inspect.signature(scenarios.drum_cleat).parameters["speed"].default
    forces = (0.5e3 * a.force_kN, 1e3 * a.force_kN)
    rows = []
    for kg, psi, c in conds:
        t0, where = time.perf_counter(), f"{kg:g} kg, {psi:g} psi"
        row, f_x = char.row(c["load_N"], c["pressure_Pa"]), shell_metrics(a.char_dir, c["load_N"],
                                                                          c["pressure_Pa"])[0].get("drum.fore_aft_mode_Hz")
        if row is None or f_x is None:
            print(f"{where}: no table row or drum fore-aft mode in {a.char_dir}", file=sys.stderr)
            continue
        d = derive(row, char.tire)
        out = {}
        for name, spec in (("static", plan.tire), ("storage", storage_tire(plan.tire, f_x))):
            tire = make_tire(spec)
            lv = push(tire.model, tire.params, c["pressure_Pa"], c["load_N"], forces, f"{where}, {name} moduli")
            for F, x, fc in lv:
                if not abs(abs(fc) - F) <= 0.01 * F:  # the patch carries the rim force (static equilibrium)
                    raise SystemExit(f"{where}, {name}: the patch carries {fc:.4g} N of the rim's {F:.4g} N")
            c_x = forces[1] / lv[1][1]
            series = 1.0 / c_x - 1.0 / d.k_bx - d.r_b**2 / d.k_btheta
            out[name] = {"levels_N_m_N": lv, "C_x_N_per_m": c_x, "secant_half_over_full": (forces[0] / lv[0][1]) / c_x,
                         "k_cx_implied_N_per_m": 1.0 / series if series > 0 else None}
        k_cx = out["static"]["k_cx_implied_N_per_m"]
        modes = drum = None
        if k_cx is not None:
            a_c = d.k_k / k_cx  # the contact's relaxation length with that spring
            dx = dataclasses.replace(d, a=a_c, k_cx=k_cx)
            modes = fore_aft(dx, speed, f_x)
            # what the validation reads off the ring's drum-cleat run with that contact spring
            q0, q1 = scenarios.drum_cleat(d).quantities, scenarios.drum_cleat(dx).quantities
            keys = ("F_x_f_n_fit_Hz", "F_x_zeta_fit", "F_z_peak_to_peak_N", "F_x_peak_to_peak_N")
            drum = {k: (q0[k], q1[k]) for k in keys}
        rows.append({"load_kg": kg, "pressure_psi": psi, "shell_fore_aft_Hz": f_x, "k_bx_N_per_m": d.k_bx,
                     "k_btheta_Nm_per_rad": d.k_btheta, "r_b_m": d.r_b, "k_k_N_per_slip": d.k_k, "a_m": d.a,
                     "ring_k_cx_N_per_m": d.k_k / d.a, "ring_C_x_N_per_m": d.C_x, "shell": out,
                     "ring_modes_with_implied_k_cx": modes,
                     "ring_drum_k_k_over_a_vs_implied": drum, "wall_s": time.perf_counter() - t0})
        print(f"{where}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

    print("| condition | shell C_x, long-term | on storage moduli | secant F/2 / F | ring C_x | k_cx implied | "
          "ring k_k / a | ring fore-aft mode on the implied k_cx (shell) |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        s, st = r["shell"]["static"], r["shell"]["storage"]
        kc = s["k_cx_implied_N_per_m"]
        m = r["ring_modes_with_implied_k_cx"]
        print(f"| {r['load_kg']:g} kg, {r['pressure_psi']:g} psi | {s['C_x_N_per_m'] / 1e3:.0f} kN/m | "
              f"{st['C_x_N_per_m'] / 1e3:.0f} kN/m | {s['secant_half_over_full']:.3f} | "
              f"{r['ring_C_x_N_per_m'] / 1e3:.0f} kN/m | "
              + (f"{kc / 1e3:.0f} kN/m" if kc else "none (series > C_x)") + f" | {r['ring_k_cx_N_per_m'] / 1e3:.0f} kN/m | "
              + (f"{m[0][0]:.2f} Hz ({r['shell_fore_aft_Hz']:.2f})" if m else "-") + " |")
    for r in rows:
        if r["ring_modes_with_implied_k_cx"]:
            print(f"{r['load_kg']:g} kg, {r['pressure_psi']:g} psi, ringing modes on the implied k_cx (f / zeta / x_b): "
                  + ", ".join(f"{f:.2f} / {z:.3f} / {x:.2f}" for f, z, x in r["ring_modes_with_implied_k_cx"][1]))
    for r in rows:
        if r["ring_drum_k_k_over_a_vs_implied"]:
            print(f"{r['load_kg']:g} kg, {r['pressure_psi']:g} psi, the ring's drum-cleat (k_k / a -> implied k_cx): "
                  + ", ".join(f"{k} {v0:.4g} -> {v1:.4g}" for k, (v0, v1) in r["ring_drum_k_k_over_a_vs_implied"].items()))
    save(a, "standstill_fore_aft", rows)


if __name__ == "__main__":
    main()
