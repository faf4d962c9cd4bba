"""The rigid-ring tables: in-plane and out-of-plane parameters per condition, as CSV, JSON and the
study's markdown layout (one block per quantity: rows load, columns pressure).

Damping quantities carry both reductions (two-peak `_2p`, damped-sine fit `_fit`) and their relative
disagreement (2p - fit) / fit. Derived in-plane columns: k_bz, k_vr, C_bz, C_vr of the variant used
(A when k_dv >= 4 k_sv, else B; the column `vertical_split` says which and `variant_A_valid` flags
it) with variant B beside. Missing values are None in JSON, empty in CSV and "—" in markdown.
"""

import math
from pathlib import Path

from .. import units as U
from ..io import atomic_write_csv, atomic_write_json, atomic_write_text
from .params import derive
from .table import QUANTITIES, Characterization, variant_keys

DASH = "—"
# derived columns: (name, symbol, unit, display unit, factor, plane, Derived attribute)
DERIVED = (
    ("k_bz_N_per_m", "k_bz", "N/m", "kN/m", 1e-3, "in", "k_bz"),
    ("k_vr_N_per_m", "k_vr", "N/m", "kN/m", 1e-3, "in", "k_vr"),
    ("k_vr2_N_per_m2", "k_vr2", "N/m^2", "MN/m^2", 1e-6, "in", "k_vr2"),
    ("k_vr3_N_per_m3", "k_vr3", "N/m^3", "GN/m^3", 1e-9, "in", "k_vr3"),
    ("rho_max_m", "rho_max", "m", "mm", 1e3, "in", "rho_max"),
    ("C_bz_Ns_per_m", "C_bz", "N s/m", "N s/m", 1.0, "in", "C_bz"),
    ("C_vr_Ns_per_m", "C_vr", "N s/m", "N s/m", 1.0, "in", "C_vr"),
    ("k_bz_B_N_per_m", "k_bz (B)", "N/m", "kN/m", 1e-3, "in", "k_bz_B"),
    ("k_vr_B_N_per_m", "k_vr (B)", "N/m", "kN/m", 1e-3, "in", "k_vr_B"),
    ("C_bz_B_Ns_per_m", "C_bz (B)", "N s/m", "N s/m", 1.0, "in", "C_bz_B"),
    ("C_vr_B_Ns_per_m", "C_vr (B)", "N s/m", "N s/m", 1.0, "in", "C_vr_B"),
    ("tau_s", "tau = C_tot/k_sv", "s", "ms", 1e3, "in", "tau"),
    ("C_x_ring_N_per_m", "C_x (ring: 1/k_cx + 1/k_bx + r_b^2/k_btheta)", "N/m", "kN/m", 1e-3, "in", "C_x"),
    ("k_cy_N_per_m", "k_cy", "N/m", "kN/m", 1e-3, "out", "k_cy"),
    ("sigma_c_m", "sigma_c", "m", "mm", 1e3, "out", "sigma_c"),
    ("sigma_kf_over_kl_m", "k_f/k_l", "m", "mm", 1e3, "out", "sigma"),
    ("C_cy_Ns_per_m", "C_cy", "N s/m", "N s/m", 1.0, "out", "C_cy"),
    ("branch_beta", "Maxwell beta", "-", "-", 1.0, "out", "branch_beta"),
)


def _rel(a, b):
    return None if a is None or b is None or b == 0 else (a - b) / b


def table_rows(char: Characterization, plane: str) -> list:
    """One dict per condition (sorted by load, then pressure): load/pressure, each measured
    quantity of the plane (damping: value, _2p, _fit, _rel_diff), the derived columns."""
    out = []
    for r in sorted(char.rows, key=lambda r: (r.load_N, r.pressure_Pa)):
        d = derive(r, char.tire)
        row = {"load_N": r.load_N, "pressure_Pa": r.pressure_Pa, "load_kg": r.load_N / U.G0,
               "pressure_psi": r.pressure_Pa / U.PSI}
        for q in QUANTITIES:
            if q.plane != plane:
                continue
            row[q.key] = r.get(q.key)
            if q.damping:
                k2, kf = variant_keys(q)
                row[k2], row[kf] = r.get(k2), r.get(kf)
                row[_rel_key(q)] = _rel(r.get(k2), r.get(kf))
        for name, _, _, _, _, pl, attr in DERIVED:
            if pl == plane:
                row[name] = getattr(d, attr)
        if plane == "in":
            row["vertical_split"] = d.variant_used
            row["k_bx_source"] = d.k_bx_source
            row["stiffness_source"] = d.stiffness_source
            row["damping_source"] = d.damping_source
            row["variant_A_valid"] = d.variant_A_valid
            if d.k_dv is not None and d.k_sv is not None:
                row["k_dv_over_k_sv"] = d.k_dv / d.k_sv
        else:
            row["k_cy_source"] = d.k_cy_source
            row["C_cy_source"] = d.C_cy_source
            row["lateral_spring_source"] = d.lateral_spring_source
            row["k_l_ring_rel_error"] = d.k_l_ring_rel_error
        out.append(row)
    return out


def _rel_key(q):
    return variant_keys(q)[0].split("_2p_")[0] + "_rel_diff_2p_vs_fit"


def _columns(rows):
    cols = []
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    return cols


def units_of(plane: str) -> dict:
    u = {"load_N": "N", "pressure_Pa": "Pa", "load_kg": "kg", "pressure_psi": "psi"}
    for q in QUANTITIES:
        if q.plane == plane:
            u[q.key] = {"symbol": q.symbol, "unit": q.unit, "experiment": q.experiment}
            if q.damping:
                k2, kf = variant_keys(q)
                u[k2] = {"symbol": q.symbol + " (two peaks)", "unit": q.unit, "experiment": q.experiment}
                u[kf] = {"symbol": q.symbol + " (fit)", "unit": q.unit, "experiment": q.experiment}
                u[_rel_key(q)] = {"symbol": "(2p - fit)/fit", "unit": "-"}
    for name, sym, unit, _, _, pl, _ in DERIVED:
        if pl == plane:
            u[name] = {"symbol": sym, "unit": unit, "experiment": "derived (docs/rigid-ring.md §3, §5)"}
    return u


def _fmt(v, factor=1.0):
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return DASH
    x = v * factor
    return f"{x:.4g}" if abs(x) < 1e5 else f"{x:.4e}"


def markdown(char: Characterization, plane: str) -> str:
    """The study's layout: for each quantity a block of rows (one per load, kg) with one column per
    pressure (psi). Damping cells: "two-peak / fit (rel. diff)"."""
    loads, pressures = char.loads(), char.pressures()
    head = "| quantity | load (kg) | " + " | ".join(f"{p / U.PSI:.0f} psi" for p in pressures) + " |"
    lines = [head, "|" + "---|" * (2 + len(pressures))]
    derived = {(r.load_N, r.pressure_Pa): derive(r, char.tire) for r in char.rows}

    def cell(load, p, fn):
        r = char.row(load, p)
        return DASH if r is None else fn(r, derived[(r.load_N, r.pressure_Pa)])

    items = []
    for q in QUANTITIES:
        if q.plane != plane:
            continue
        unit, fac = q.display
        if q.damping:
            k2, kf = variant_keys(q)

            def fn(r, d, k2=k2, kf=kf, fac=fac):
                a, b = r.get(k2), r.get(kf)
                rel = _rel(a, b)
                return f"{_fmt(a, fac)} / {_fmt(b, fac)}" + ("" if rel is None else f" ({100 * rel:+.1f} %)")
            items.append((f"{q.symbol} 2p / fit ({unit}) [{q.experiment}]", fn))
        else:
            items.append((f"{q.symbol} ({unit}) [{q.experiment}]", lambda r, d, k=q.key, fac=fac: _fmt(r.get(k), fac)))
    for name, sym, _, dunit, fac, pl, attr in DERIVED:
        if pl == plane:
            items.append((f"{sym} ({dunit}) [derived]", lambda r, d, a=attr, fac=fac: _fmt(getattr(d, a), fac)))
    if plane == "in":
        items.append(("vertical split used", lambda r, d: DASH if d.variant_used is None else
                      d.variant_used + ("" if d.variant_A_valid else " (A invalid: k_dv < 4 k_sv)")))
        items.append(("k_bx, C_bx source", lambda r, d: DASH if d.k_bx_source is None else
                      ("E13" if d.k_bx_measured else "k_bz (isotropy: no E13)")))
        items.append(("dynamic springs", lambda r, d: DASH if d.stiffness_source is None else
                      ("tangent" if d.uses_tangent else "secant")))
        items.append(("C_bz, C_vr from", lambda r, d: DASH if d.damping_source is None else
                      ("E03 + E04" if d.dampers_identified else "tau (fallback)")))
    else:
        items.append(("k_cy source", lambda r, d: DASH if d.k_cy_source is None else
                      ("series" if d.k_cy_source.startswith("series") else "fallback sigma_c = a")))
        items.append(("k_l' / k_l", lambda r, d: _fmt(d.lateral_storage_ratio)))
        items.append(("C_cy from", lambda r, d: DASH if d.C_cy_source is None else
                      ("E09's zeta" if d.tread_damper_identified else "k_cy C_l / k_l (fallback)")))
    for label, fn in items:
        for i, load in enumerate(loads):
            lines.append(f"| {label if i == 0 else ''} | {load / U.G0:.1f} | "
                         + " | ".join(cell(load, p, fn) for p in pressures) + " |")
    title = "In-plane rigid-ring parameters" if plane == "in" else "Out-of-plane rigid-ring parameters"
    note = ("Vertical split of the tangent k_vt (the secant k_sv without one): variant A (k_dv = k_bz + k_vr, needs "
            "k_dv >= 4 k_vt) when valid, else B (k_bz = k_dv); the residual spring k_vr rho + k_vr2 rho^2 rests at "
            "F_z/k_sv; above the load it goes on with k_vr3 (rho - rho_r)^3 through E02's largest load (its "
            "residual deflection rho_max), past it on its end slope. C_bz + C_vr from E03's belt-mode zeta, divided "
            "so the linear bounce has E04's in-contact zeta; else (and in the B columns) tau = C_tot / k_sv for both."
            if plane == "in" else
            "k_cy from 1/k_l - 1/k_by - r_b^2/k_bgamma, or the fallback sigma_c = a when ill-conditioned. k_l' / k_l: "
            "E09's push on the rubber's storage moduli at its release frequency over its static push; the ring's "
            "springs are the static pushes, each sidewall spring k with a Maxwell branch (stiffness beta k, the "
            "rubber's longest relaxation time) that makes its k_l equal k_l' there. C_cy: the tread damper that "
            "gives the ring's linear release E09's fitted zeta (docs/rigid-ring.md).")
    return f"### {title}\n\n" + "\n".join(lines) + f"\n\n{note} Damping: two-peak / fit (relative difference).\n"


def write_tables(char: Characterization, out_dir) -> list:
    """in_plane.csv/.json/.md and out_of_plane.csv/.json/.md in out_dir. Returns the paths."""
    out = Path(out_dir)
    written = []
    for plane, stem in (("in", "in_plane"), ("out", "out_of_plane")):
        rows = table_rows(char, plane)
        cols = _columns(rows)
        written.append(atomic_write_csv(out / f"{stem}.csv", cols, [[r.get(c) for c in cols] for r in rows]))
        written.append(atomic_write_json(out / f"{stem}.json", {"plane": stem, "units": units_of(plane), "rows": rows}))
        written.append(atomic_write_text(out / f"{stem}.md", markdown(char, plane)))
    return written

