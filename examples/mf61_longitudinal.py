"""Read an MF 6.1 `.tir` file and plot the pure longitudinal force F_x0(kappa) at a few loads; with
--curves, overlay the force-slip curves a characterization simulated and print how far the file is
from them.

A stand-in for a vehicle engineer's own tool, like mf61_lateral.py beside it (whose .tir reader it
shares): it does not import jtire, only numpy and matplotlib. Equations: Pacejka, Tire and Vehicle
Dynamics, 3rd ed. (2012), section 4.3.2, F_x0 by (4.E9)-(4.E18), at zero camber (PDX3 drops out,
zeta_1 = 1). The inflation-pressure terms PPX1-PPX4 (K_xk and mu_x against dp_i = (p - NOMPRES)/NOMPRES)
are read when present, 0 when absent; they act only at another pressure than NOMPRES (--all-pressures).
Scaling factors LFZO, LCX, LMUX, LEX, LKX, LHX, LVX are read from [SCALING_COEFFICIENTS], 1 when
absent. Signs ISO-W: kappa > 0 drives, F_x > 0.

--curves: a characterization.json; its rows at the file's NOMPRES that carry E06 curves are drawn as
points, each less its free-rolling F_x (the rolling resistance, which MF carries in M_y, not F_x0),
and one line per row gives the largest |F_x0 - F_x| over 0-10 % slip in % of the curve's peak.
--all-pressures: every row with E06 curves, each evaluated at its own pressure.
With --curves, the rows' E12 rolling resistance (when recorded) is compared with the file's rolling-resistance
moment (4.E70, at V_x = LONGVL, F_x = 0, camber 0) as the hub drag of a free-rolling wheel, |M_y| / R_l,
R_l = R0 - rho with rho the file's own static deflection at F_z (MF 6.1's F_z(rho) with Q_FZ2 and PFZ1).

Usage: python examples/mf61_longitudinal.py TIR_FILE --out PNG [--loads-kN 20,45.4,68] [--curves JSON [--all-pressures]]
Exits 2 with one line on stderr naming the file (and key) when a file is missing or unreadable, or the
.tir lacks a key the equations need, holds text where they need a number, or is not SI / FITTYP 61, 62.
"""

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from mf61_lateral import NoCurves, TirError, curve_rows, loads_asked, numbers, parse_tir  # noqa: E402  (the sibling script's reader)

FX_KEYS = ("FNOMIN", "NOMPRES", "PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PEX3", "PEX4", "PKX1", "PKX2", "PKX3",
           "PHX1", "PHX2", "PVX1", "PVX2")
SCALING = ("LFZO", "LCX", "LMUX", "LEX", "LKX", "LHX", "LVX")
PRESSURE = ("PPX1", "PPX2", "PPX3", "PPX4")  # 0 when absent: no pressure dependence
MY_KEYS = ("UNLOADED_RADIUS", "VERTICAL_STIFFNESS", "QSY1", "QSY7")
MY_OPTIONAL = ("QSY3", "QSY4", "QSY8", "Q_FZ2", "PFZ1")  # 0 when absent


def coefficients(path, tir):
    """The numbers the F_x0 equations need, checked: {KEY: float}."""
    return numbers(path, tir, FX_KEYS, SCALING, "F_x0", PRESSURE)


def longitudinal(c, fz, kappa, dpi=0.0):
    """Pure longitudinal slip at gamma = 0: F_x0 (N), K_xk (N), D_x (N); dpi = (p - NOMPRES)/NOMPRES.
    Broadcasts."""
    fz, kappa = np.asarray(fz, float), np.asarray(kappa, float)
    fz0 = c["FNOMIN"] * c["LFZO"]                                                # (4.E1)
    dfz = (fz - fz0) / fz0                                                       # (4.E2a)
    lmux_prime = 10 * c["LMUX"] / (1 + 9 * c["LMUX"])                            # (4.E8), A_mu = 10
    shx = (c["PHX1"] + c["PHX2"] * dfz) * c["LHX"]                               # (4.E17)
    kx = kappa + shx                                                             # (4.E10)
    cx = c["PCX1"] * c["LCX"]                                                    # (4.E11)
    mu_p = 1 + c["PPX3"] * dpi + c["PPX4"] * dpi**2
    dx = (c["PDX1"] + c["PDX2"] * dfz) * mu_p * c["LMUX"] * fz                   # (4.E12), (4.E13)
    ex = np.minimum((c["PEX1"] + c["PEX2"] * dfz + c["PEX3"] * dfz**2) * (1 - c["PEX4"] * np.sign(kx)) * c["LEX"],
                    1.0)                                                         # (4.E14)
    kxk = (fz * (c["PKX1"] + c["PKX2"] * dfz) * np.exp(c["PKX3"] * dfz)
           * (1 + c["PPX1"] * dpi + c["PPX2"] * dpi**2) * c["LKX"])  # (4.E15)
    bx = kxk / (cx * dx + np.where(cx * dx >= 0, 1e-12, -1e-12))                 # (4.E16)
    svx = fz * (c["PVX1"] + c["PVX2"] * dfz) * c["LVX"] * lmux_prime             # (4.E18)
    fx = dx * np.sin(cx * np.arctan(bx * kx - ex * (bx * kx - np.arctan(bx * kx)))) + svx  # (4.E9)
    return {"fx": fx, "kxk": kxk, "dx": dx}


def rolling_drag(c, fz, dpi=0.0):
    """The free-rolling hub drag |M_y| / R_l (N) at F_z, dp_i: M_y by (4.E70) at V_x = LONGVL, F_x = 0,
    camber 0; R_l = R0 - rho, F_z = FNOMIN (1 + PFZ1 dp_i)(Q_FZ1 rho/R0 + Q_FZ2 (rho/R0)^2)."""
    r0, fz0 = c["UNLOADED_RADIUS"], c["FNOMIN"]
    q1 = np.sqrt((c["VERTICAL_STIFFNESS"] * r0 / fz0) ** 2 - 4 * c["Q_FZ2"])
    f = fz / (fz0 * (1 + c["PFZ1"] * dpi))
    x = f / q1 if c["Q_FZ2"] == 0 else (-q1 + np.sqrt(q1 * q1 + 4 * c["Q_FZ2"] * f)) / (2 * c["Q_FZ2"])
    p_ratio = 1 + dpi  # p / NOMPRES
    my = r0 * fz0 * (c["QSY1"] + c["QSY3"] + c["QSY4"]) * (fz / fz0) ** c["QSY7"] * p_ratio ** c["QSY8"]
    return my / (r0 * (1 - x))


def simulated_drag(path, nompres, every_pressure=False):
    """[(F_z, dp_i, E12's drag)] of the rows that record one, or [] (an older characterization)."""
    try:
        return [(fz, dpi, float(d)) for fz, dpi, d in curve_rows(path, "rolling_resistance_N", nompres, every_pressure)]
    except NoCurves:
        return []


def simulated_curves(path, nompres, every_pressure=False):
    """[(F_z, dp_i, kappa, F_x - F_x(0))] of the characterization's rows at NOMPRES (every_pressure: at
    every pressure) with E06 curves."""
    out = []
    for fz, dpi, cv in curve_rows(path, "E06_curves", nompres, every_pressure):
        if not all(k in cv for k in ("slip", "force_x_N")):
            raise TirError(f"{path}: an E06_curves entry lacks slip or force_x_N")
        k, f = np.asarray(cv["slip"], float), np.asarray(cv["force_x_N"], float)
        ok = np.isfinite(k) & np.isfinite(f)
        k, f = k[ok], f[ok]
        out.append((fz, dpi, k, f - float(np.interp(0.0, k, f))))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description="F_x0(kappa) of an MF 6.1 .tir (pure longitudinal slip, camber 0)")
    ap.add_argument("tir", help="the .tir file")
    ap.add_argument("--out", required=True, help="PNG to write")
    ap.add_argument("--loads-kN", default=None, help="comma-separated loads in kN (default 0.5, 1, 1.5 x FNOMIN)")
    ap.add_argument("--curves", default=None, help="a characterization.json whose E06 curves to compare")
    ap.add_argument("--all-pressures", action="store_true",
                    help="with --curves: compare the rows at every pressure (default: NOMPRES only)")
    args = ap.parse_args(argv)
    if args.all_pressures and not args.curves:
        ap.error("--all-pressures compares curves: give --curves too")
    try:
        c = coefficients(args.tir, parse_tir(args.tir))
        drag = simulated_drag(args.curves, c["NOMPRES"], args.all_pressures) if args.curves else []
        try:  # a characterization with E12 but no E06 (e.g. experiments = ["rolling_resistance"]) compares the drag only
            sim = simulated_curves(args.curves, c["NOMPRES"], args.all_pressures) if args.curves else []
        except NoCurves:
            if not drag:
                raise
            sim = []
    except TirError as e:
        print(f"mf61_longitudinal: {e}", file=sys.stderr)
        return 2
    loads = sorted({fz for fz, _, _, _ in sim}) if sim else loads_asked(ap, args.loads_kN, c["FNOMIN"])
    kappa = np.linspace(0.0, 0.3, 3001)
    print(f"{args.tir}: FITTYP {c['FITTYP']:g}, FNOMIN {c['FNOMIN']:.2f} N\n"
          "ISO-W signs (kappa > 0 driving), camber 0, nominal pressure, pure longitudinal slip")
    print(f"{'F_z [N]':>12} {'K_xk [N]':>14} {'peak F_x [N]':>14} {'at kappa [%]':>13} {'D_x [N]':>13}")
    for fz in loads:
        part = longitudinal(c, fz, kappa)
        k = int(np.argmax(part["fx"]))
        print(f"{fz:12.2f} {float(part['kxk']):14.7g} {part['fx'][k]:14.7g} {100 * kappa[k]:13.2f} "
              f"{float(part['dx']):13.7g}")
    for fz, dpi, k, f in sim:  # the file against the simulated curves, over 0-10 % slip
        w = k <= 0.10 + 1e-12
        err = np.max(np.abs(longitudinal(c, fz, k[w], dpi)["fx"] - f[w])) / max(np.max(np.abs(f)), 1e-9)
        at = f" at {c['NOMPRES'] * (1 + dpi) / 1e3:.0f} kPa" if args.all_pressures else ""
        print(f"{fz:12.2f} N{at}: max |F_x0 - F_x| over 0-10 % slip = {100 * err:.2f} % of the curve's peak")
    if drag:
        try:
            cy = numbers(args.tir, parse_tir(args.tir), MY_KEYS + ("FNOMIN",), (), "M_y", MY_OPTIONAL)
        except TirError as e:
            print(f"mf61_longitudinal: {e}", file=sys.stderr)
            return 2
        for fz, dpi, d in drag:  # the rolling-resistance moment against E12's drag
            at = f" at {c['NOMPRES'] * (1 + dpi) / 1e3:.0f} kPa"
            mf_d = float(rolling_drag(cy, fz, dpi))
            print(f"{fz:12.2f} N{at}: rolling resistance |M_y|/R_l = {mf_d:.4g} N, E12's drag {d:.4g} N "
                  f"({100 * (mf_d / d - 1):+.2f} %)")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for i, fz in enumerate(loads):
        ax.plot(100 * kappa, longitudinal(c, fz, kappa)["fx"] / 1e3, color=f"C{i}", label=f"MF, F_z = {fz / 1e3:.1f} kN")
    for fz, dpi, k, f in sim:  # the points at NOMPRES (the MF lines are at NOMPRES)
        if abs(dpi) < 1e-9:
            ax.plot(100 * k, f / 1e3, "o", color=f"C{loads.index(fz)}", ms=4, label=f"simulated (E06), {fz / 1e3:.1f} kN")
    ax.set(xlabel="longitudinal slip kappa [%] (ISO-W)", ylabel="F_x0 [kN]", title=f"MF {Path(args.tir).name}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
