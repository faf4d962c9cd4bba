"""MF-Tyre 6.1 property file (.tir, TeimOrbit layout) from a characterization, and a reader.

Section and key names, order and units follow the public MF 6.1 sample shipped with MFeval
(MagicFormula61_Parameters.tir; [UNITS] meter, newton, radians, kg, second) so the file loads in
standard MF 6.1/6.2 evaluators (6.2 readers take a 6.1 file; FITTYP says which equations apply).
Every derived key carries a `$` comment naming its source; keys the characterization does not
identify keep neutral defaults (a term switched off: camber, combined slip, overturning) or the
usual MF-Swift values (format settings, enveloping, turn slip), each commented "default". Mapping:
docs/rigid-ring.md §7 and §9.

Load/pressure laws fitted here (MF 6.1/6.2 forms, TyreDyn stiffness_mf6x / contact_patch_mf6x):
  C_z = VERTICAL_STIFFNESS (1 + PFZ1 dpi);  C_y = LATERAL_STIFFNESS (1 + PCFY1 dfz + PCFY2 dfz^2)
  (1 + PCFY3 dpi), C_x likewise with PCFX*;  a/R0 = Q_RA2 rho/R0 + Q_RA1 sqrt(rho/R0);
  b/W = Q_RB1 (rho/R0)^(1/3) (Q_RB2 = 0), rho = F_z / k_sv, a and b the half length and width;
  pure longitudinal slip (PCX1 ... PPX4): the MF fit to E06's force-slip curves
  (`mf_longitudinal`); without curves only K_xk = F_z (PKX1 + PKX2 dfz)(1 + PPX1 dpi) from k_k;
  rolling resistance QSY1, QSY7, QSY8 from E12's drag (`mf_rolling`).
"""

import math
import re

import numpy as np

from ..errors import ConfigError
from ..io import atomic_write_text
from . import magic_formula as mf
from . import mf_longitudinal as mfx
from . import mf_rolling as mfr
from .params import derive

SECTIONS = (
    ("MDI_HEADER", "FILE_TYPE FILE_VERSION FILE_FORMAT"),
    ("UNITS", "LENGTH FORCE ANGLE MASS TIME"),
    ("MODEL", "FITTYP TYRESIDE LONGVL VXLOW ROAD_INCREMENT ROAD_DIRECTION PROPERTY_FILE_FORMAT USER_SUB_ID "
              "N_TIRE_STATES USE_MODE HMAX_LOCAL TIME_SWITCH_INTEG"),
    ("DIMENSION", "UNLOADED_RADIUS WIDTH ASPECT_RATIO RIM_RADIUS RIM_WIDTH"),
    ("OPERATING_CONDITIONS", "INFLPRES NOMPRES"),
    ("INERTIA", "MASS IXX IYY BELT_MASS BELT_IXX BELT_IYY GRAVITY"),
    ("VERTICAL", "FNOMIN VERTICAL_STIFFNESS VERTICAL_DAMPING MC_CONTOUR_A MC_CONTOUR_B BREFF DREFF FREFF Q_RE0 "
                 "Q_V1 Q_V2 Q_FZ2 Q_FCX Q_FCY Q_CAM PFZ1 BOTTOM_OFFST BOTTOM_STIFF"),
    ("STRUCTURAL", "LONGITUDINAL_STIFFNESS LATERAL_STIFFNESS YAW_STIFFNESS FREQ_LONG FREQ_LAT FREQ_YAW FREQ_WINDUP "
                   "DAMP_LONG DAMP_LAT DAMP_YAW DAMP_WINDUP DAMP_RESIDUAL DAMP_VLOW Q_BVX Q_BVT PCFX1 PCFX2 PCFX3 "
                   "PCFY1 PCFY2 PCFY3 PCMZ1"),
    ("CONTACT_PATCH", "Q_RA1 Q_RA2 Q_RB1 Q_RB2 ELLIPS_SHIFT ELLIPS_LENGTH ELLIPS_HEIGHT ELLIPS_ORDER ELLIPS_MAX_STEP "
                      "ELLIPS_NWIDTH ELLIPS_NLENGTH"),
    ("INFLATION_PRESSURE_RANGE", "PRESMIN PRESMAX"),
    ("VERTICAL_FORCE_RANGE", "FZMIN FZMAX"),
    ("LONG_SLIP_RANGE", "KPUMIN KPUMAX"),
    ("SLIP_ANGLE_RANGE", "ALPMIN ALPMAX"),
    ("INCLINATION_ANGLE_RANGE", "CAMMIN CAMMAX"),
    ("SCALING_COEFFICIENTS", "LFZO LCX LMUX LEX LKX LHX LVX LCY LMUY LEY LKY LHY LVY LTR LRES LXAL LYKA LVYKA LS "
                             "LKYC LKZC LVMX LMX LMY LMP"),
    ("LONGITUDINAL_COEFFICIENTS", "PCX1 PDX1 PDX2 PDX3 PEX1 PEX2 PEX3 PEX4 PKX1 PKX2 PKX3 PHX1 PHX2 PVX1 PVX2 PPX1 "
                                  "PPX2 PPX3 PPX4 RBX1 RBX2 RBX3 RCX1 REX1 REX2 RHX1"),
    ("OVERTURNING_COEFFICIENTS", "QSX1 QSX2 QSX3 QSX4 QSX5 QSX6 QSX7 QSX8 QSX9 QSX10 QSX11 QSX12 QSX13 QSX14 PPMX1"),
    ("LATERAL_COEFFICIENTS", "PCY1 PDY1 PDY2 PDY3 PEY1 PEY2 PEY3 PEY4 PEY5 PKY1 PKY2 PKY3 PKY4 PKY5 PKY6 PKY7 PHY1 "
                             "PHY2 PVY1 PVY2 PVY3 PVY4 PPY1 PPY2 PPY3 PPY4 PPY5 RBY1 RBY2 RBY3 RBY4 RCY1 REY1 REY2 "
                             "RHY1 RHY2 RVY1 RVY2 RVY3 RVY4 RVY5 RVY6"),
    ("ROLLING_COEFFICIENTS", "QSY1 QSY2 QSY3 QSY4 QSY5 QSY6 QSY7 QSY8"),
    ("ALIGNING_COEFFICIENTS", "QBZ1 QBZ2 QBZ3 QBZ4 QBZ5 QBZ9 QBZ10 QCZ1 QDZ1 QDZ2 QDZ3 QDZ4 QDZ6 QDZ7 QDZ8 QDZ9 QDZ10 "
                              "QDZ11 QEZ1 QEZ2 QEZ3 QEZ4 QEZ5 QHZ1 QHZ2 QHZ3 QHZ4 PPZ1 PPZ2 SSZ1 SSZ2 SSZ3 SSZ4"),
    ("TURNSLIP_COEFFICIENTS", "PDXP1 PDXP2 PDXP3 PKYP1 PDYP1 PDYP2 PDYP3 PDYP4 PHYP1 PHYP2 PHYP3 PHYP4 PECP1 PECP2 "
                              "QDTP1 QCRP1 QCRP2 QBRP1 QDRP1"),
)
LAYOUT = {s: tuple(k.split()) for s, k in SECTIONS}

D = "default"
DEFAULTS = {
    "FILE_TYPE": ("tir", D), "FILE_VERSION": (3, D), "FILE_FORMAT": ("ASCII", D),
    "LENGTH": ("meter", D), "FORCE": ("newton", D), "ANGLE": ("radians", D), "MASS": ("kg", D), "TIME": ("second", D),
    "FITTYP": (61, "Magic Formula version number"), "TYRESIDE": ("LEFT", D), "VXLOW": (1.0, "default: lower boundary of slip calculation"),
    "ROAD_INCREMENT": (0.01, D), "ROAD_DIRECTION": (1, D), "PROPERTY_FILE_FORMAT": ("USER", D), "USER_SUB_ID": (815, D),
    "N_TIRE_STATES": (4, D), "USE_MODE": (124, "default (ADAMS only)"), "HMAX_LOCAL": (0.00025, "default (ADAMS only)"),
    "TIME_SWITCH_INTEG": (0.1, "default (ADAMS only)"), "GRAVITY": (-9.81, "gravity acting on belt in Z direction"),
    "MC_CONTOUR_A": (0.0, D), "MC_CONTOUR_B": (0.0, D), "BREFF": (8.4, "default: effective rolling radius not identified"),
    "DREFF": (0.27, "default: effective rolling radius not identified"),
    "FREFF": (0.07, "default: effective rolling radius not identified"), "Q_RE0": (1.0, D), "Q_V1": (0.0, D),
    "Q_V2": (0.0, D), "Q_FZ2": (0.0, "default: linear load-deflection (k_sv)"), "Q_FCX": (0.0, D), "Q_FCY": (0.0, D),
    "Q_CAM": (0.0, D), "BOTTOM_OFFST": (0.01, D), "DAMP_VLOW": (0.001, "default (not from the study)"),
    "Q_BVX": (0.0, "default: no load/speed stiffening"), "Q_BVT": (0.0, "default: no load/speed stiffening"),
    "PCMZ1": (0.0, D), "Q_RB2": (0.0, "linear width term not fitted"), "ELLIPS_SHIFT": (0.8, "default: no enveloping identified"),
    "ELLIPS_LENGTH": (1.0, D), "ELLIPS_HEIGHT": (1.0, D), "ELLIPS_ORDER": (1.8, D), "ELLIPS_MAX_STEP": (0.025, D),
    "ELLIPS_NWIDTH": (10, D), "ELLIPS_NLENGTH": (10, D), "FZMIN": (0.0, D), "KPUMIN": (-1.0, D), "KPUMAX": (1.0, D),
    "CAMMIN": (-0.0873, "camber effects not identified (their coefficients are 0)"), "CAMMAX": (0.0873, "camber effects not identified"),
    "PCX1": (1.65, "default (longitudinal force curve not measured)"),
    "PDX1": (1.0, "default (longitudinal friction not measured)"), "QSY1": (0.01, "default (no E12 drag: rolling resistance not exported)"),
    "QSY7": (1.0, "default: moment proportional to load"), "PDXP1": (0.4, "default (turn slip not identified)"),
    "PKYP1": (1.0, D), "PDYP1": (0.4, D), "PHYP1": (1.0, D), "PHYP2": (0.15, D), "PHYP4": (-4.0, D), "PECP1": (0.5, D),
    "QDTP1": (10.0, D), "QCRP1": (0.2, D), "QCRP2": (0.1, D), "QBRP1": (0.1, D), "QDRP1": (1.0, D),
}
SCALING = set(LAYOUT["SCALING_COEFFICIENTS"])


def _lstsq(cols, y):
    a = np.column_stack(cols)
    return np.linalg.lstsq(a, np.asarray(y, float), rcond=None)[0]


def _near(x, ref):
    return math.isclose(x, ref, rel_tol=1e-6)


def build(char, fit=None, longvl=6.7056, fittyp=61, rated=None, fit_x=None):
    """Values of every key: {section: [(key, value, comment)]} and a list of notes (magnitudes that
    depart from public .tir files, fallbacks used). char: Characterization; fit: a
    magic_formula.FitResult (None: fitted here to the E10 curves at the nominal pressure, or the
    lateral/aligning coefficients stay default when there are none); fit_x: a
    mf_longitudinal.LongitudinalFit (None: fitted here to the E06 curves at the nominal pressure, or
    only the slip stiffness PKX1, PKX2, PPX1 from k_k when there are none); longvl: speed of the E10 runs (m/s;
    default 15 mph); rated: the ConditionRow taken as nominal (default char.rated_row())."""
    if fittyp not in (61, 62):
        raise ConfigError(f"fittyp = {fittyp}: must be 61 or 62")
    t = char.tire
    r0 = rated or char.rated_row()
    d0 = derive(r0, t)
    fz0, p0, R0 = r0.load_N, r0.pressure_Pa, t.unloaded_radius_m
    vals, notes = {}, []

    def put(key, value, comment):
        if value is not None and math.isfinite(float(value)):
            vals[key] = (float(value), comment)

    at = f"{fz0:.0f} N / {p0 / 1e3:.0f} kPa"
    vals["FITTYP"] = (fittyp, "Magic Formula version number")
    put("LONGVL", longvl, "speed of the E10 cornering runs (m/s)")
    put("UNLOADED_RADIUS", R0, "tire config (free radius)")
    put("WIDTH", t.width_m, "tire config (section width)")
    put("ASPECT_RATIO", t.aspect_ratio, "tire config (section height / width)")
    put("RIM_RADIUS", t.rim_radius_m, "tire config")
    put("RIM_WIDTH", t.rim_width_m, "tire config")
    put("INFLPRES", p0, "nominal condition pressure")
    put("NOMPRES", p0, "nominal condition pressure")
    put("MASS", t.tire_mass_kg, "tire mass (no rim), tire config")
    if t.tire_Iy_kgm2 is not None and t.tire_Ix_kgm2 is not None:
        put("IXX", t.tire_Ix_kgm2, "whole tire (no rim) about a diameter: I_bx + sidewalls and beads (mesh)")
        put("IYY", t.tire_Iy_kgm2, "whole tire (no rim) about the axle: I_by + sidewalls and beads (mesh)")
    else:
        put("IXX", t.I_bx_kgm2, "[A] belt value I_bx: whole-tire inertia not recorded")
        put("IYY", t.I_by_kgm2, "[A] belt value I_by: whole-tire inertia not recorded")
    put("BELT_MASS", t.m_b_kg, "m_b, tire config")
    put("BELT_IXX", t.I_bx_kgm2, "I_bx, tire config")
    put("BELT_IYY", t.I_by_kgm2, "I_by, tire config")
    put("FNOMIN", fz0, "nominal (rated) load")
    if d0.uses_tangent:
        # MF 6.1's F_z = FNOMIN (Q_FZ1 rho/R0 + Q_FZ2 (rho/R0)^2), Q_FZ1 = sqrt((C_z R0/FNOMIN)^2 - 4 Q_FZ2):
        # C_z is then the tangent at FNOMIN, and this Q_FZ2 puts the rest at FNOMIN/k_sv (E02's secant)
        put("VERTICAL_STIFFNESS", d0.k_vt, f"tangent of the load-deflection curve (E02) at {at}")
        put("Q_FZ2", (d0.k_vt - d0.k_sv) * d0.k_sv * R0**2 / fz0**2,
            f"(k_vt - k_sv) k_sv R0^2/FNOMIN^2: rest at FNOMIN/k_sv (E02) at {at}")
    else:
        put("VERTICAL_STIFFNESS", d0.k_sv, f"k_sv (E02) at {at}")
    put("VERTICAL_DAMPING", d0.C_tot, f"C_tot (E04) at {at}")
    put("BOTTOM_STIFF", None if d0.k_sv is None else 10 * d0.k_sv, "[A] 10 k_sv")
    cx = "C_x_shell" if d0.C_x_shell is not None else "C_x"  # E14's push when measured, else the ring's springs
    if d0.C_x_shell is not None:
        put("LONGITUDINAL_STIFFNESS", d0.C_x_shell, f"C_x, E14's standstill push at the rim, at {at}")
        if d0.C_x is not None:
            rel = 100 * (d0.C_x / d0.C_x_shell - 1)
            notes.append(f"LONGITUDINAL_STIFFNESS {d0.C_x_shell:.4g} N/m is E14's; the ring's springs in series "
                         f"(1/k_cx + 1/k_bx + r_b^2/k_btheta) give {d0.C_x:.4g} ({rel:+.1f} %)")
    else:
        put("LONGITUDINAL_STIFFNESS", d0.C_x, f"1/C_x = 1/k_cx + 1/k_bx + r_b^2/k_btheta at {at} (no E14)")
    put("LATERAL_STIFFNESS", d0.k_l_static, f"k_l (E09's static push) at {at}")
    if d0.k_l_static is not None and d0.a is not None:
        put("YAW_STIFFNESS", d0.k_l_static * d0.a**2 / 3, "[A] brush estimate k_l a^2/3 (not measured)")
    for k, v in d0.structural().items():
        src = {"FREQ_LONG": "sqrt(k_bz/m_b)/2pi", "FREQ_LAT": "sqrt(k_by/m_b)/2pi", "FREQ_YAW": "sqrt(k_bgamma/I_bx)/2pi",
               "FREQ_WINDUP": "sqrt(k_btheta/I_by)/2pi", "DAMP_LONG": "C_bz/(2 sqrt(k_bz m_b))",
               "DAMP_LAT": "C_by/(2 sqrt(k_by m_b))", "DAMP_YAW": "C_bgamma/(2 sqrt(k_bgamma I_bx))",
               "DAMP_WINDUP": "C_btheta/(2 sqrt(k_btheta I_by))", "DAMP_RESIDUAL": "C_vr/k_vr"}[k]
        extra = f", vertical split {d0.variant_used}" if k in ("FREQ_LONG", "DAMP_LONG") else ""
        if k in ("FREQ_LAT", "FREQ_YAW", "DAMP_LAT", "DAMP_YAW") and d0.uses_storage:
            extra += f", springs: {d0.lateral_spring_source}"
        if k in ("DAMP_LONG", "DAMP_RESIDUAL") and d0.damping_source:
            extra += f", dampers: {d0.damping_source}"
        put(k, v, f"{src} at {at}{extra}")
        if k.startswith("DAMP_") and k != "DAMP_RESIDUAL" and v is not None and not 0.01 <= v <= 0.1:
            notes.append(f"{k} = {v:.3g}: public .tir files carry ~0.04")

    same_p = sorted((r for r in char.rows if _near(r.pressure_Pa, p0)), key=lambda r: r.load_N)
    same_l = sorted((r for r in char.rows if _near(r.load_N, fz0)), key=lambda r: r.pressure_Pa)
    ds_p = [derive(r, t) for r in same_p]
    ds_l = [derive(r, t) for r in same_l]

    def load_law(attr, k1, k2, what):
        pts = [((d.load_N - fz0) / fz0, getattr(d, attr)) for d in ds_p if getattr(d, attr) is not None]
        ref = getattr(d0, attr)
        if ref and len(pts) >= 3:
            c = _lstsq([[x for x, _ in pts], [x * x for x, _ in pts]], [v / ref - 1 for _, v in pts])
            put(k1, c[0], f"{what} vs load at {p0 / 1e3:.0f} kPa ({len(pts)} loads)")
            put(k2, c[1], f"{what} vs load, quadratic term")

    def pressure_law(attr, key, what):
        pts = [((d.pressure_Pa - p0) / p0, getattr(d, attr)) for d in ds_l if getattr(d, attr) is not None]
        ref = getattr(d0, attr)
        if ref and sum(abs(x) > 0 for x, _ in pts) >= 1:
            put(key, _lstsq([[x for x, _ in pts]], [v / ref - 1 for _, v in pts])[0],
                f"{what} vs pressure at {fz0:.0f} N ({len(pts)} pressures)")

    pressure_law("k_sv", "PFZ1", "k_sv")
    mfr.put_keys(char, vals, put, notes, r0)
    load_law("k_l_static", "PCFY1", "PCFY2", "k_l")
    pressure_law("k_l_static", "PCFY3", "k_l")
    load_law(cx, "PCFX1", "PCFX2", "C_x")
    pressure_law(cx, "PCFX3", "C_x")
    # contact patch: half length and half width against the static deflection rho = F_z / k_sv
    pa = [(d.rho / R0, d.a / R0) for d in ds_p if d.rho is not None and d.a is not None]
    if len(pa) >= 2:
        c = _lstsq([[math.sqrt(x) for x, _ in pa], [x for x, _ in pa]], [y for _, y in pa])
        put("Q_RA1", c[0], f"a/R0 = Q_RA2 rho/R0 + Q_RA1 sqrt(rho/R0), E01 + E02 at {len(pa)} loads")
        put("Q_RA2", c[1], "see Q_RA1")
    if d0.w is not None and d0.rho is not None:
        put("Q_RB1", (d0.w / 2 / t.width_m) / (d0.rho / R0) ** (1 / 3), f"b/W = Q_RB1 (rho/R0)^(1/3), E01 at {at}")
    # enveloping: E03's tandem cam at the nominal condition, in jtire's scaling (jtire.enveloping)
    if d0.ellips is not None:
        l_s, a_e, b_e, c_e = d0.ellips
        src = (f"E03's quasi-static crossing of its {r0.get('enveloping_max_height_m') or 0:.3g} m-high effective bump "
               f"at {at} (fit rms {1e3 * (r0.get('enveloping_fit_rms_height_m') or math.nan):.2g} mm)")
        if d0.a is not None:
            put("ELLIPS_SHIFT", l_s / (2 * d0.a), f"l_s / 2a: the cams' distance over the contact length (E01's a); {src}")
        put("ELLIPS_LENGTH", a_e / R0, "a_e / R0: the cam's half length; jtire's scaling (MF-Swift's own may differ)")
        put("ELLIPS_HEIGHT", b_e / R0, "b_e / R0: the cam's half height; jtire's scaling")
        put("ELLIPS_ORDER", c_e, "c_e: the cam's super-ellipse exponent")
    # ranges
    put("PRESMIN", min(r.pressure_Pa for r in char.rows), "lowest characterized pressure")
    put("PRESMAX", max(r.pressure_Pa for r in char.rows), "highest characterized pressure")
    put("FZMAX", max(r.load_N for r in char.rows), "highest characterized load")
    # pure longitudinal slip: the MF fit to E06's force-slip curves, else the slip stiffness alone,
    # K_xk = F_z (PKX1 + PKX2 dfz)(1 + PPX1 dpi)
    if fit_x is None:
        slip_curves = mfx.curves_from_characterization(char, pressures=[p0])
        if slip_curves:
            fit_x = mfx.fit_pure_longitudinal(slip_curves, mf.Nominal(fz0, p0, R0))
    kk = [((d.load_N - fz0) / fz0, d.k_k / d.load_N) for d in ds_p if d.k_k is not None]
    if fit_x is not None:
        surfaces = sorted({s for s in (r.slip_curves.surface for r in char.rows if r.slip_curves is not None) if s})
        where = f"E06's force-slip curves ({len(fit_x.errors)} conditions, {'/'.join(surfaces) or 'surface not recorded'})"
        err = f"max F_x error {100 * fit_x.max_error:.2g} % of peak over 0-{100 * fit_x.err_range:g} %"
        for k in mfx.FX_KEYS:
            bound = fit_x.bound_note(k)
            if bound:
                notes.append(f"{k} {bound}")
            if k in fit_x.fitted:
                put(k, fit_x.coefficients[k], f"fitted to {where}; {err}" + (f"; {bound}" if bound else ""))
            elif k in ("PHX1", "PHX2", "PVX1", "PVX2"):
                put(k, fit_x.coefficients[k], "0: E06's free-rolling F_x (the rolling resistance on its surface) is "
                    "removed before the fit; MF carries it in M_y")
            elif k == "PEX4":
                put(k, fit_x.coefficients[k], "0: only the driving side (kappa > 0) is simulated; braking taken as symmetric")
            else:
                put(k, fit_x.coefficients[k], "fixed in the E06 fit (the data do not identify it)")
        kmax = max(float(np.max(r.slip_curves.slip)) for r in char.rows if r.slip_curves is not None)
        put("KPUMIN", -kmax, "widest E06 slip (driving side, mirrored)")
        put("KPUMAX", kmax, "widest E06 slip")
        if not any(fit_x.peak_reached):
            notes.append(f"no E06 curve reaches its peak within {100 * kmax:.3g} % slip: PDX1/PCX1 extrapolate the friction level")
    elif len(kk) >= 2:
        c = _lstsq([[1.0] * len(kk), [x for x, _ in kk]], [y for _, y in kk])
        put("PKX1", c[0], f"k_k/F_z (E06) vs load at {p0 / 1e3:.0f} kPa")
        put("PKX2", c[1], "see PKX1")
    elif d0.k_k is not None:
        put("PKX1", d0.k_k / fz0, f"k_k/F_z (E06) at {at}")
    kp = [((d.pressure_Pa - p0) / p0, d.k_k) for d in ds_l if d.k_k is not None]
    if fit_x is None and d0.k_k and any(abs(x) > 0 for x, _ in kp):
        put("PPX1", _lstsq([[x for x, _ in kp]], [v / d0.k_k - 1 for _, v in kp])[0], "k_k vs pressure (E06)")
    # lateral and aligning: the MF fit
    if fit is None:
        curves = mf.curves_from_characterization(char, pressures=[p0])
        if curves:
            fit = mf.fit_pure_lateral(curves, mf.Nominal(fz0, p0, R0))
    if fit is not None:
        rng = f"0-{fit.err_range_deg:g} deg"
        if fit.range_text() != rng:  # a curve ends before err_range_deg (a steady sweep that stopped)
            notes.append(f"MF fit errors over {fit.range_text()}")
            rng += " or where the curve ends (notes)"
        for k in mf.FY_KEYS + mf.MZ_KEYS:
            how = "fitted to the E10 curves" if k in fit.fitted_fy + fit.fitted_mz else "fixed in the E10 fit"
            bound = fit.bound_note(k)
            if bound:
                notes.append(f"{k} {bound}")
            put(k, fit.coefficients[k], f"{how} (max F_y error {100 * fit.max_fy_error:.2g} % of peak over {rng})"
                + (f"; {bound}" if bound else ""))
        angles = [abs(a) for r in char.rows if r.curves is not None for a in r.curves.slip_angle_deg]
        put("ALPMIN", -math.radians(max(angles)), "widest E10 slip angle")
        put("ALPMAX", math.radians(max(angles)), "widest E10 slip angle")
    else:
        notes.append("no E10 curves: lateral and aligning coefficients are defaults")
    if d0.k_k is not None and d0.k_f is not None and d0.k_k < d0.k_f:
        notes.append(f"k_k = {d0.k_k:.4g} N < k_f = {d0.k_f:.4g} N/rad: usual tyres have K_xk > K_ya")
    if d0.trail is not None and d0.a is not None and not 0.5 <= d0.trail / (d0.a / 3) <= 2:
        notes.append(f"pneumatic trail k_m/k_f = {d0.trail:.4g} m vs brush theory a/3 = {d0.a / 3:.4g} m")
    if not d0.variant_A_valid:
        notes.append("k_dv < 4 k_sv: vertical split variant A invalid, FREQ_LONG/DAMP_LONG use variant B")

    out = {}
    for sec, keys in LAYOUT.items():
        rows = []
        for k in keys:
            if k in vals and sec not in ("MDI_HEADER", "UNITS"):  # [UNITS] MASS is the unit name
                v, c = vals[k]
            elif k in SCALING:
                v, c = 1.0, "scale factor (1: none)"
            elif k in DEFAULTS:
                v, c = DEFAULTS[k]
            else:
                v, c = 0.0, "default: term not identified (0 switches it off)"
            rows.append((k, v, c))
        out[sec] = rows
    return out, notes


def _fmt(k, v):
    # by the value, not the key: [UNITS] MASS is the unit name 'kg', [INERTIA] MASS a number
    if isinstance(v, str):
        return f"'{v}'"
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    return repr(float(v))


def dumps(sections: dict, header_comments=()) -> str:
    lines = []
    for sec, rows in sections.items():
        if sec != "MDI_HEADER":
            lines.append("$" + "-" * (70 - len(sec)) + sec.lower())
        lines.append(f"[{sec}]")
        for k, v, c in rows:
            lines.append(f"{k:<25}= {_fmt(k, v):<24} ${c}")
        if sec == "MDI_HEADER":
            lines += [f"! : COMMENT : {c}" for c in header_comments]
    return "\n".join(lines) + "\n"


def write(path, sections: dict, header_comments=()):
    return atomic_write_text(path, dumps(sections, header_comments))


_LINE = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*=\s*('[^']*'|\"[^\"]*\"|[^\s$!]+)")


def loads(text: str) -> dict:
    """{SECTION: {KEY: value}}; quoted values are strings, the rest numbers (int when integral
    without a point). `$` and `!` start comments."""
    out, sec = {}, None
    for n, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line or line[0] in "$!":
            continue
        if line.startswith("["):
            sec = line[1:line.index("]")].strip().upper()
            out.setdefault(sec, {})
            continue
        m = _LINE.match(line)
        if m is None or sec is None:
            raise ConfigError(f".tir line {n}: cannot read {raw!r}")
        k, v = m.group(1).upper(), m.group(2)
        if v[0] in "'\"":
            out[sec][k] = v[1:-1]
        else:
            try:
                out[sec][k] = int(v) if re.fullmatch(r"[+-]?\d+", v) else float(v)
            except ValueError:
                raise ConfigError(f".tir line {n}: {k} = {v!r} is not a number") from None
    return out


def read(path) -> dict:
    """Read a `.tir` property file (as `write` makes it, or another MF 6.1/6.2 file in TeimOrbit layout).

    Returns:
        {SECTION: {KEY: value}}, section and key names upper-cased, values in the file's units (SI for
        the files jtire writes); quoted values are strings, the rest numbers (see `loads`). A line that
        cannot be read is a `ConfigError` naming it.
    """
    from pathlib import Path

    return loads(Path(path).read_text())
