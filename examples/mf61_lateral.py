"""Read an MF 6.1 `.tir` file and plot the pure side-slip lateral force F_y0(alpha) at a few loads; with
--curves, overlay the cornering curves a characterization simulated and print how far the file is from them.

A stand-in for a vehicle engineer's own tool: it does not import jtire, only numpy and matplotlib.
Equations: Pacejka, Tire and Vehicle Dynamics, 3rd ed. (2012), section 4.3.2, F_y0 by (4.E19)-(4.E30)
and M_z0 by (4.E31)-(4.E49), at zero camber (every camber term drops out, zeta_i = 1), no turn slip,
V_cx > 0. The inflation-pressure terms (dp_i = (p - NOMPRES)/NOMPRES: PPY1-PPY4 in K_y and mu_y, PPZ1
in the trail) are read when present, 0 when absent; they act only at another pressure than NOMPRES
(--all-pressures). Scaling factors LFZO, LCY, LMUY, LEY, LKY, LHY, LVY, LTR, LRES are read from
[SCALING_COEFFICIENTS], 1 when absent.

Signs: the file's own axes, ISO-W (TYDEX W: x forward, y left, z up), as MF 6.1 files and evaluators
use them: a positive slip angle gives a negative F_y when PKY1 < 0. Flipping both alpha and F_y (SAE,
y right) maps a symmetric tire's curve onto itself, so K_y keeps its sign. TYRESIDE is printed; the
file is evaluated as written (a tool that mounts it on the other side mirrors it).

--curves: a characterization.json; its rows at the file's NOMPRES that carry E10 curves are drawn as
points (F_y in wheel axes, turned from the file's SAE signs into ISO-W: alpha and F_y, M_z change sign),
and one line per row gives the largest |F_y0 - F_y| (and |M_z0 - M_z|) over |alpha| <= 8 deg in % of
the curve's peak |F_y| (|M_z|). --all-pressures: every row with E10 curves, each evaluated at its own
pressure through the file's pressure terms.

Usage: python examples/mf61_lateral.py TIR_FILE --out PNG [--loads-kN 20,45.4,68] [--curves JSON [--all-pressures]]
Exits 2 with one line on stderr naming the file (and key) when a file is missing or unreadable, the .tir
lacks a key the F_y0 equations need, holds text where they need a number, or is not SI / not FITTYP 61, 62.
"""

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

FY_KEYS = ("FNOMIN", "PCY1", "PDY1", "PDY2", "PEY1", "PEY2", "PEY3", "PKY1", "PKY2", "PKY4",
           "PHY1", "PHY2", "PVY1", "PVY2")
MZ_KEYS = ("UNLOADED_RADIUS", "QBZ1", "QBZ2", "QBZ3", "QBZ9", "QBZ10", "QCZ1", "QDZ1", "QDZ2", "QDZ6", "QDZ7",
           "QEZ1", "QEZ2", "QEZ3", "QEZ4", "QHZ1", "QHZ2")
SCALING = ("LFZO", "LCY", "LMUY", "LEY", "LKY", "LHY", "LVY", "LTR", "LRES")
PRESSURE = ("PPY1", "PPY2", "PPY3", "PPY4", "PPZ1")  # 0 when absent: no pressure dependence
SI_UNITS = {"LENGTH": ("meter",), "FORCE": ("newton",), "ANGLE": ("radian", "radians")}


class TirError(Exception):  # a problem with the .tir: the message names the file and the key
    pass


class NoCurves(TirError):  # a readable characterization.json without the curves asked for
    pass


def parse_tir(path):
    """{SECTION: {KEY: value}} of a .tir: `[SECTION]` headers, `KEY = value` lines, `$` (and `!`)
    start a comment, quoted values are strings, the rest floats (kept as text when not a number).
    Lines without `=` (the rows of a [SHAPE] table) are skipped."""
    try:
        text = Path(path).read_text(errors="replace")
    except OSError as e:
        raise TirError(f"{path}: cannot read the file ({e.strerror or e})") from None
    out, sec = {}, None
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "$!{":
            continue
        if line.startswith("["):
            sec = line[1:].split("]")[0].strip().upper()
            out.setdefault(sec, {})
            continue
        if "=" not in line or sec is None:
            continue
        key, value = (s.strip() for s in line.split("=", 1))
        if value[:1] in "'\"":  # a quoted string: up to its closing quote
            out[sec][key.upper()] = ("str", value[1:].split(value[0])[0])
            continue
        value = value.split("$")[0].split("!")[0].strip()
        try:
            out[sec][key.upper()] = ("num", float(value))
        except ValueError:
            out[sec][key.upper()] = ("bad", value)
    if not out:
        raise TirError(f"{path}: no [SECTION] found: not a .tir file")
    return out


def numbers(path, tir, keys, scaling, what, optional=()):
    """{KEY: float} of `keys` (each required), `scaling` (1 when absent) and `optional` (0 when
    absent), after checking [UNITS] is SI and FITTYP is 61 or 62; what: the equations, for the messages."""
    flat = {k: v for s, kv in tir.items() if s != "UNITS" for k, v in kv.items()}
    for key, ok in SI_UNITS.items():  # the equations take SI units
        v = tir.get("UNITS", {}).get(key, ("str", ok[0]))[1]
        if str(v).lower() not in ok:
            raise TirError(f"{path}: [UNITS] {key} = {v!r}: only {ok[0]} is read")

    def number(key):
        if key not in flat:
            raise TirError(f"{path}: missing key {key} (the {what} equations need it)")
        kind, v = flat[key]
        if kind != "num":
            raise TirError(f"{path}: {key} = {v!r} is not a number")
        return v

    if number("FITTYP") not in (61.0, 62.0):  # 6 / 21 (MF 5.2) files follow other equations
        raise TirError(f"{path}: FITTYP = {flat['FITTYP'][1]:g}: these are the MF 6.1/6.2 equations (61 or 62)")
    c = {key: number(key) for key in ("FITTYP",) + tuple(keys)}
    c |= {key: number(key) if key in flat else 1.0 for key in scaling}
    c |= {key: number(key) if key in flat else 0.0 for key in optional}
    if c.get("FNOMIN", 1.0) <= 0:
        raise TirError(f"{path}: FNOMIN = {c['FNOMIN']!r}: must be > 0")
    return c


def coefficients(path, tir):
    """The numbers the equations need, checked: {KEY: float}, and the M_z0 keys the file lacks."""
    c = numbers(path, tir, FY_KEYS, SCALING, "F_y0", PRESSURE)
    flat = {k for s, kv in tir.items() if s != "UNITS" for k in kv}
    lacking_mz = [k for k in MZ_KEYS if k not in flat]
    if not lacking_mz:
        c |= numbers(path, tir, MZ_KEYS, (), "M_z0")
    return c, lacking_mz


def lateral(c, fz, alpha, dpi=0.0):
    """Pure side slip at gamma = 0: F_y0 (N), K_y (N/rad), D_y (N) and the parts M_z0 uses.
    fz in N, alpha in rad (ISO-W), dpi = (p - NOMPRES)/NOMPRES; broadcasts."""
    fz, alpha = np.asarray(fz, float), np.asarray(alpha, float)
    fz0 = c["FNOMIN"] * c["LFZO"]                                               # (4.E1)  F'_z0
    dfz = (fz - fz0) / fz0                                                       # (4.E2a) df_z
    lmuy_prime = 10 * c["LMUY"] / (1 + 9 * c["LMUY"])                            # (4.E8)  A_mu = 10
    a_star = np.tan(alpha)                                                       # (4.E3)  alpha*, V_cx > 0
    shy = (c["PHY1"] + c["PHY2"] * dfz) * c["LHY"]                               # (4.E27)
    svy = fz * (c["PVY1"] + c["PVY2"] * dfz) * c["LVY"] * lmuy_prime             # (4.E29)
    ay = a_star + shy                                                            # (4.E20)
    cy = c["PCY1"] * c["LCY"]                                                    # (4.E21)
    mu_p = 1 + c["PPY3"] * dpi + c["PPY4"] * dpi**2
    dy = (c["PDY1"] + c["PDY2"] * dfz) * mu_p * c["LMUY"] * fz                   # (4.E22), (4.E23)
    ey = np.minimum((c["PEY1"] + c["PEY2"] * dfz) * (1 - c["PEY3"] * np.sign(ay)) * c["LEY"], 1.0)  # (4.E24)
    ky = (c["PKY1"] * fz0 * (1 + c["PPY1"] * dpi)
          * np.sin(c["PKY4"] * np.arctan(fz / (c["PKY2"] * (1 + c["PPY2"] * dpi) * fz0))) * c["LKY"])  # (4.E25)
    by = ky / (cy * dy + np.where(cy * dy >= 0, 1e-12, -1e-12))                  # (4.E26)
    fy = dy * np.sin(cy * np.arctan(by * ay - ey * (by * ay - np.arctan(by * ay)))) + svy          # (4.E19)
    return {"fy": fy, "ky": ky, "dy": dy, "by": by, "cy": cy, "shy": shy, "svy": svy, "dfz": dfz,
            "a_star": a_star, "fz0": fz0}


def aligning(c, fz, alpha, dpi=0.0):
    """Pure side-slip aligning moment M_z0 = -t_0 F_y0 + M_zr0 (N m, ISO-W) at gamma = 0."""
    p = lateral(c, fz, alpha, dpi)
    fz, alpha, dfz = np.asarray(fz, float), np.asarray(alpha, float), p["dfz"]
    at = p["a_star"] + c["QHZ1"] + c["QHZ2"] * dfz                               # (4.E34), (4.E35)
    ky = np.where(np.abs(p["ky"]) > 1e-9, p["ky"], 1e-9)                         # K'_y = K_y + eps_K
    ar = p["a_star"] + p["shy"] + p["svy"] / ky                                  # (4.E37), (4.E38)
    bt = (c["QBZ1"] + c["QBZ2"] * dfz + c["QBZ3"] * dfz**2) * c["LKY"] / c["LMUY"]  # (4.E40)
    ct = c["QCZ1"]                                                               # (4.E41)
    dt = (fz * (c["UNLOADED_RADIUS"] / p["fz0"]) * (c["QDZ1"] + c["QDZ2"] * dfz) * (1 - c["PPZ1"] * dpi)
          * c["LTR"])                                                            # (4.E42), (4.E43)
    et = np.minimum((c["QEZ1"] + c["QEZ2"] * dfz + c["QEZ3"] * dfz**2)
                    * (1 + c["QEZ4"] * (2 / np.pi) * np.arctan(bt * ct * at)), 1.0)   # (4.E44)
    t0 = dt * np.cos(ct * np.arctan(bt * at - et * (bt * at - np.arctan(bt * at)))) * np.cos(alpha)  # (4.E33)
    br = c["QBZ9"] * c["LKY"] / c["LMUY"] + c["QBZ10"] * p["by"] * p["cy"]       # (4.E45)
    dr = fz * c["UNLOADED_RADIUS"] * (c["QDZ6"] + c["QDZ7"] * dfz) * c["LRES"] * c["LMUY"] * np.cos(alpha)  # (4.E47)
    mzr0 = dr * np.cos(np.arctan(br * ar)) * np.cos(alpha)                       # (4.E36), C_r = 1
    return -t0 * p["fy"] + mzr0                                                  # (4.E31), (4.E32)


def numerical_slope(c, fz, h=1e-6):
    """dF_y0/dalpha at alpha = 0 by a central difference (N/rad); equals K_y when S_Hy = S_Vy = 0."""
    return float((lateral(c, fz, h)["fy"] - lateral(c, fz, -h)["fy"]) / (2 * h))


def loads_asked(ap, text, fnomin):
    """The loads (N) of --loads-kN, or 0.5, 1 and 1.5 x FNOMIN; a bad list is an argparse error."""
    if text is None:
        return [f * fnomin for f in (0.5, 1.0, 1.5)]
    try:
        loads = [1e3 * float(s) for s in text.split(",")]
    except ValueError:
        ap.error(f"--loads-kN {text!r}: give numbers separated by commas, e.g. 20,45.4,68")
    if not all(math.isfinite(f) and f > 0 for f in loads):
        ap.error(f"--loads-kN {text!r}: loads must be > 0")
    return loads


def curve_rows(path, key, nompres, every_pressure=False):
    """[(F_z, dp_i, curves dict)] of a characterization.json's rows with `key` ("E10_curves",
    "E06_curves") at NOMPRES (every_pressure: at every pressure), by pressure then load."""
    try:
        rows = json.loads(Path(path).read_text())["rows"]
        out = [(float(r["load_N"]), (float(r["pressure_Pa"]) - nompres) / nompres, r[key]) for r in rows
               if r.get(key) and (every_pressure or math.isclose(float(r["pressure_Pa"]), nompres, rel_tol=1e-6))]
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
        raise TirError(f"{path}: not a readable characterization.json ({type(e).__name__}: {e})") from None
    if not out:
        raise NoCurves(f"{path}: no row {'' if every_pressure else f'at NOMPRES = {nompres:g} Pa '}carries {key}")
    return sorted(out, key=lambda x: (x[1], x[0]))


def simulated_curves(path, nompres, every_pressure=False):
    """[(F_z, dp_i, alpha rad, F_y N, M_z N m or None)] in ISO-W of the characterization's rows with
    E10 curves (see curve_rows). F_y is the wheel-axis force: F_y_SAE_N when recorded, else the
    road-axis force turned by alpha with F_x, (lateral + F_x sin a) / cos a, else the road-axis force."""
    out = []
    for fz, dpi, cv in curve_rows(path, "E10_curves", nompres, every_pressure):
        if not all(k in cv for k in ("slip_angle_deg", "lateral_force_N")):
            raise TirError(f"{path}: an E10_curves entry lacks slip_angle_deg or lateral_force_N")
        a = np.radians(np.asarray(cv["slip_angle_deg"], float))
        if cv.get("F_y_SAE_N") is not None:
            fy = np.asarray(cv["F_y_SAE_N"], float)
        elif cv.get("F_x_N") is not None:
            fy = (np.asarray(cv["lateral_force_N"], float) + np.asarray(cv["F_x_N"], float) * np.sin(a)) / np.cos(a)
        else:
            fy = np.asarray(cv["lateral_force_N"], float)
        mz = None if cv.get("M_z_SAE_Nm") is None else -np.asarray(cv["M_z_SAE_Nm"], float)
        ok = np.isfinite(a) & np.isfinite(fy) & (np.isfinite(mz) if mz is not None else True)
        out.append((fz, dpi, -a[ok], -fy[ok], None if mz is None else mz[ok]))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description="F_y0(alpha) of an MF 6.1 .tir (pure side slip, camber 0)")
    ap.add_argument("tir", help="the .tir file")
    ap.add_argument("--out", required=True, help="PNG to write")
    ap.add_argument("--loads-kN", default=None, help="comma-separated loads in kN (default 0.5, 1, 1.5 x FNOMIN)")
    ap.add_argument("--curves", default=None, help="a characterization.json whose E10 curves to compare")
    ap.add_argument("--all-pressures", action="store_true",
                    help="with --curves: compare the rows at every pressure (default: NOMPRES only)")
    args = ap.parse_args(argv)
    if args.all_pressures and not args.curves:
        ap.error("--all-pressures compares curves: give --curves too")
    try:
        tir = parse_tir(args.tir)
        c, lacking_mz = coefficients(args.tir, tir)
        has_mz = not lacking_mz
        nompres = numbers(args.tir, tir, ("NOMPRES",), (), "the curves' pressure")["NOMPRES"] if args.curves else None
        sim = simulated_curves(args.curves, nompres, args.all_pressures) if args.curves else []
    except TirError as e:
        print(f"mf61_lateral: {e}", file=sys.stderr)
        return 2
    loads = sorted({fz for fz, _, _, _, _ in sim}) if sim else loads_asked(ap, args.loads_kN, c["FNOMIN"])
    # the curves: alpha from -15 to 15 deg (wider when a simulated curve is), one per load
    amax = max([15.0] + [float(np.degrees(np.max(np.abs(a)))) for _, _, a, _, _ in sim])
    alpha_deg = np.linspace(-amax, amax, 3001)
    alpha = np.radians(alpha_deg)
    side = tir.get("MODEL", {}).get("TYRESIDE", ("str", "not given"))[1]
    print(f"{args.tir}: FITTYP {c['FITTYP']:g}, TYRESIDE {side}, FNOMIN {c['FNOMIN']:.2f} N\n"
          "ISO-W signs (F_y < 0 for alpha > 0 when PKY1 < 0), camber 0, nominal pressure, pure side slip")
    print(f"{'F_z [N]':>12} {'K_y formula [N/rad]':>20} {'K_y numeric [N/rad]':>20} "
          f"{'peak |F_y| [N]':>15} {'at alpha [deg]':>15} {'D_y [N]':>13}")
    curves = []
    for fz in loads:
        part = lateral(c, fz, alpha)
        k = int(np.argmax(np.abs(part["fy"])))
        print(f"{fz:12.2f} {float(part['ky']):20.7g} {numerical_slope(c, fz):20.7g} "
              f"{abs(part['fy'][k]):15.7g} {alpha_deg[k]:15.2f} {float(part['dy']):13.7g}")
        curves.append((fz, part["fy"], aligning(c, fz, alpha) if has_mz else None))
    if not has_mz:
        print(f"M_z0 not plotted: the file lacks {' '.join(lacking_mz)}")
    for fz, dpi, a, fy, mz in sim:  # the file against the simulated curves, over |alpha| <= 8 deg
        w = np.abs(a) <= np.radians(8.0) + 1e-12
        err = np.max(np.abs(lateral(c, fz, a[w], dpi)["fy"] - fy[w])) / max(np.max(np.abs(fy)), 1e-9)
        at = f" at {nompres * (1 + dpi) / 1e3:.0f} kPa" if args.all_pressures else ""
        line = f"{fz:12.2f} N{at}: max |F_y0 - F_y| over 0-8 deg = {100 * err:.2f} % of the curve's peak"
        if has_mz and mz is not None:
            err_m = np.max(np.abs(aligning(c, fz, a[w], dpi) - mz[w])) / max(np.max(np.abs(mz)), 1e-9)
            line += f", |M_z0 - M_z| = {100 * err_m:.2f} %"
        print(line)
    # the figure: F_y0(alpha) (and M_z0(alpha)) per load
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2 if has_mz else 1, figsize=(11 if has_mz else 6, 4.2), squeeze=False)
    for i, (fz, fy, mz) in enumerate(curves):
        axes[0, 0].plot(alpha_deg, fy / 1e3, color=f"C{i}", label=f"F_z = {fz / 1e3:.1f} kN")
        if mz is not None:
            axes[0, 1].plot(alpha_deg, mz, color=f"C{i}", label=f"F_z = {fz / 1e3:.1f} kN")
    for fz, dpi, a, fy, mz in sim:  # the points at NOMPRES (the MF lines are at NOMPRES)
        if abs(dpi) < 1e-9:
            i = loads.index(fz)
            axes[0, 0].plot(np.degrees(a), fy / 1e3, "o", color=f"C{i}", ms=4, label=f"simulated (E10), {fz / 1e3:.1f} kN")
            if has_mz and mz is not None:
                axes[0, 1].plot(np.degrees(a), mz, "o", color=f"C{i}", ms=4)
    titles = [("F_y0 [kN]", f"MF {Path(args.tir).name}"), ("M_z0 [N m]", "aligning moment")]
    for ax, (ylabel, title) in zip(axes[0], titles):
        ax.set(xlabel="slip angle alpha [deg] (ISO-W)", ylabel=ylabel, title=title)
        ax.grid(alpha=0.3)
        ax.axhline(0, color="k", lw=0.5)
        ax.legend()
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
