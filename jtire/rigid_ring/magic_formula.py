"""Magic Formula 6.1/6.2 pure side slip: F_y0 and M_z0 at zero camber, and their least-squares fit to
the E10 curves.

Equations (MF 6.1 as published in Pacejka, Tire and Vehicle Dynamics 3rd ed. §4.3.2, and as coded by
the public readers MFeval and TyreDyn), ISO-W axes, camber 0, no turn slip, all scaling factors
lambda = 1, V_cx > 0, so zeta_i = 1 and the camber terms vanish:
  F'z0 = FNOMIN, dfz = (F_z - F'z0)/F'z0, dpi = (p - NOMPRES)/NOMPRES, alpha* = tan(alpha)
  S_Hy = PHY1 + PHY2 dfz,  S_Vy = F_z (PVY1 + PVY2 dfz),  alpha_y = alpha* + S_Hy
  mu_y = (PDY1 + PDY2 dfz)(1 + PPY3 dpi + PPY4 dpi^2),  D_y = mu_y F_z,  C_y = PCY1
  K_ya = PKY1 F'z0 (1 + PPY1 dpi) sin(PKY4 atan(F_z / (PKY2 (1 + PPY2 dpi) F'z0)))
  E_y = (PEY1 + PEY2 dfz)(1 - PEY3 sgn(alpha_y)) <= 1,  B_y = K_ya / (C_y D_y)
  F_y0 = D_y sin(C_y atan(B_y alpha_y - E_y (B_y alpha_y - atan(B_y alpha_y)))) + S_Vy
  S_Ht = QHZ1 + QHZ2 dfz,  alpha_t = alpha* + S_Ht,  alpha_r = alpha* + S_Hy + S_Vy / K_ya
  B_t = QBZ1 + QBZ2 dfz + QBZ3 dfz^2,  C_t = QCZ1
  D_t = F_z (R0 / F'z0)(QDZ1 + QDZ2 dfz)(1 - PPZ1 dpi)
  E_t = (QEZ1 + QEZ2 dfz + QEZ3 dfz^2)(1 + QEZ4 (2/pi) atan(B_t C_t alpha_t)) <= 1
  t_0 = D_t cos(C_t atan(B_t alpha_t - E_t (B_t alpha_t - atan(B_t alpha_t)))) cos(alpha)
  B_r = QBZ9 + QBZ10 B_y C_y,  D_r = F_z R0 (QDZ6 + QDZ7 dfz) cos(alpha),  C_r = 1
  M_zr0 = D_r cos(C_r atan(B_r alpha_r)) cos(alpha),  M_z0 = -t_0 F_y0 + M_zr0
ISO vs the E10 curves (SAE): alpha_ISO = -alpha_SAE, F_y,ISO = -F_y,SAE, M_z,ISO = -M_z,SAE: for a
symmetric tire the curve is the same function; PKY1 < 0 (F_y < 0 for alpha > 0).
"""

import dataclasses
import math

import numpy as np
import scipy.optimize

from ..errors import ConfigError

# Pure-side-slip keys (the .tir's [LATERAL_COEFFICIENTS] / [ALIGNING_COEFFICIENTS]) and the values
# that leave a term out; the evaluator reads only these.
FY_KEYS = ("PCY1", "PDY1", "PDY2", "PEY1", "PEY2", "PEY3", "PKY1", "PKY2", "PKY4", "PHY1", "PHY2", "PVY1", "PVY2",
           "PPY1", "PPY2", "PPY3", "PPY4")
MZ_KEYS = ("QBZ1", "QBZ2", "QBZ3", "QBZ9", "QBZ10", "QCZ1", "QDZ1", "QDZ2", "QDZ6", "QDZ7", "QEZ1", "QEZ2", "QEZ3",
           "QEZ4", "QHZ1", "QHZ2", "PPZ1")
NEUTRAL = {k: 0.0 for k in FY_KEYS + MZ_KEYS} | {"PCY1": 1.3, "PDY1": 1.0, "PKY1": -10.0, "PKY2": 2.0, "PKY4": 2.0,
                                                "QBZ1": 10.0, "QCZ1": 1.2, "QDZ1": 0.08}
BOUNDS = {"PCY1": (1.0, 2.5), "PDY1": (0.05, 3.0), "PDY2": (-1.0, 1.0), "PEY1": (-10.0, 1.0), "PEY2": (-10.0, 10.0),
          "PKY1": (-500.0, -0.01), "PKY2": (0.05, 50.0), "PKY4": (1.0, 4.0), "PHY1": (-0.1, 0.1), "PHY2": (-0.1, 0.1),
          "PVY1": (-0.5, 0.5), "PVY2": (-0.5, 0.5), "PPY1": (-5.0, 5.0), "PPY2": (-5.0, 5.0), "PPY3": (-5.0, 5.0),
          "PPY4": (-5.0, 5.0), "QBZ1": (0.1, 100.0), "QBZ2": (-50.0, 50.0), "QBZ3": (-50.0, 50.0), "QCZ1": (0.5, 3.0),
          "QDZ1": (1e-4, 1.0), "QDZ2": (-1.0, 1.0), "QEZ1": (-50.0, 1.0), "QEZ2": (-50.0, 50.0), "QEZ3": (-50.0, 50.0),
          "QHZ1": (-0.1, 0.1), "QHZ2": (-0.1, 0.1), "PPZ1": (-5.0, 5.0)}


@dataclasses.dataclass(frozen=True)
class Nominal:
    """The MF's reference values: FNOMIN (N), NOMPRES (Pa), UNLOADED_RADIUS (m)."""

    fnomin: float
    nompres: float
    r0: float


def _get(c, k):
    return c.get(k, NEUTRAL[k])


def _lateral_parts(c: dict, nom: Nominal, fz, alpha, p):
    fz, alpha = np.asarray(fz, float), np.asarray(alpha, float)
    p = nom.nompres if p is None else p
    dfz = (fz - nom.fnomin) / nom.fnomin
    dpi = (np.asarray(p, float) - nom.nompres) / nom.nompres
    a_star = np.tan(alpha)
    shy = _get(c, "PHY1") + _get(c, "PHY2") * dfz
    svy = fz * (_get(c, "PVY1") + _get(c, "PVY2") * dfz)
    ay = a_star + shy
    mu = (_get(c, "PDY1") + _get(c, "PDY2") * dfz) * (1 + _get(c, "PPY3") * dpi + _get(c, "PPY4") * dpi**2)
    dy = mu * fz
    cy = _get(c, "PCY1")
    kya = (_get(c, "PKY1") * nom.fnomin * (1 + _get(c, "PPY1") * dpi)
           * np.sin(_get(c, "PKY4") * np.arctan(fz / (_get(c, "PKY2") * (1 + _get(c, "PPY2") * dpi) * nom.fnomin))))
    ey = np.minimum((_get(c, "PEY1") + _get(c, "PEY2") * dfz) * (1 - _get(c, "PEY3") * np.sign(ay)), 1.0)
    by = kya / (cy * dy + np.where(cy * dy >= 0, 1e-12, -1e-12))
    fy = dy * np.sin(cy * np.arctan(by * ay - ey * (by * ay - np.arctan(by * ay)))) + svy
    return dict(fy=fy, kya=kya, by=by, cy=cy, dy=dy, shy=shy, svy=svy, dfz=dfz, dpi=dpi, a_star=a_star)


def fy0(c: dict, nom: Nominal, fz, alpha, p=None):
    """Pure lateral force F_y0 (N, ISO) at load fz (N), slip angle alpha (rad, ISO), pressure p (Pa;
    None: NOMPRES). Broadcasts."""
    return _lateral_parts(c, nom, fz, alpha, p)["fy"]


def cornering_stiffness(c: dict, nom: Nominal, fz, p=None):
    """K_ya = dF_y0/dalpha at alpha = 0 with no shifts (N/rad, ISO sign: < 0)."""
    return _lateral_parts(c, nom, fz, 0.0, p)["kya"]


def mz0(c: dict, nom: Nominal, fz, alpha, p=None):
    """Pure aligning moment M_z0 (N m, ISO) = -t_0 F_y0 + M_zr0."""
    lp = _lateral_parts(c, nom, fz, alpha, p)
    fz, alpha = np.asarray(fz, float), np.asarray(alpha, float)
    dfz, dpi = lp["dfz"], lp["dpi"]
    at = lp["a_star"] + _get(c, "QHZ1") + _get(c, "QHZ2") * dfz
    kya = lp["kya"]
    ar = lp["a_star"] + lp["shy"] + lp["svy"] / np.where(np.abs(kya) > 1e-9, kya, 1e-9)
    bt = _get(c, "QBZ1") + _get(c, "QBZ2") * dfz + _get(c, "QBZ3") * dfz**2
    ct = _get(c, "QCZ1")
    dt = fz * (nom.r0 / nom.fnomin) * (_get(c, "QDZ1") + _get(c, "QDZ2") * dfz) * (1 - _get(c, "PPZ1") * dpi)
    et = np.minimum((_get(c, "QEZ1") + _get(c, "QEZ2") * dfz + _get(c, "QEZ3") * dfz**2)
                    * (1 + _get(c, "QEZ4") * (2 / np.pi) * np.arctan(bt * ct * at)), 1.0)
    t0 = dt * np.cos(ct * np.arctan(bt * at - et * (bt * at - np.arctan(bt * at)))) * np.cos(alpha)
    br = _get(c, "QBZ9") + _get(c, "QBZ10") * lp["by"] * lp["cy"]
    dr = fz * nom.r0 * (_get(c, "QDZ6") + _get(c, "QDZ7") * dfz) * np.cos(alpha)
    mzr = dr * np.cos(np.arctan(br * ar)) * np.cos(alpha)
    return -t0 * lp["fy"] + mzr


@dataclasses.dataclass(frozen=True)
class CurveData:
    """One condition's steady curve in SAE signs: alpha_deg (n,), F_y (n,) N (wheel axes),
    M_z (n,) N m or None, at load fz (N) and pressure p (Pa)."""

    fz: float
    p: float
    alpha_deg: np.ndarray
    fy: np.ndarray
    mz: np.ndarray | None = None


@dataclasses.dataclass(frozen=True)
class FitResult:
    coefficients: dict  # every FY_KEYS / MZ_KEYS value (fitted or fixed)
    fitted_fy: tuple
    fitted_mz: tuple
    nominal: Nominal
    # per condition: (fz, p, max |F_y,MF - F_y| over 0..err_range / max |F_y| over the curve, same for M_z)
    errors: tuple
    err_range_deg: float
    max_fy_error: float
    max_mz_error: float | None
    success: bool
    message: str
    at_bound: tuple = ()  # fitted coefficients that ended on a bound of BOUNDS: not identified by the curves
    reach_deg: tuple = ()  # per condition: the largest |alpha| (deg) of its curve within err_range_deg

    def range_text(self) -> str:
        """The slip-angle range the errors cover: "0-8 deg", or, where a curve ends sooner (a steady
        sweep that stopped), "0-8 deg (0-4 deg at 68.1 kN, 483 kPa: the curve ends there)"."""
        short = [(e[0], e[1], r) for e, r in zip(self.errors, self.reach_deg) if r < self.err_range_deg - 1e-9]
        text = f"0-{self.err_range_deg:g} deg"
        if short:
            text += " (" + "; ".join(f"0-{r:.3g} deg at {fz / 1e3:.4g} kN, {p / 1e3:.0f} kPa" for fz, p, r in short)
            text += ": the curve ends there)"
        return text

    def bound_note(self, key):
        """Why a coefficient sits on its bound, or None."""
        if key not in self.at_bound:
            return None
        return on_bound(self.coefficients[key], BOUNDS[key],
                        "K_y still proportional to F_z over the loads fitted: only PKY1 / PKY2 is identified"
                        if key == "PKY2" else "the curves do not pin it")


def on_bound(value, bounds, why) -> str:
    """'at the fit's upper (lower) bound B: why' for a coefficient that ended on a bound (lo, hi)."""
    lo, hi = bounds
    upper = abs(value - hi) <= abs(value - lo)
    return f"at the fit's {'upper' if upper else 'lower'} bound {hi if upper else lo:g}: {why}"


def _to_iso(d: CurveData):
    return np.radians(-np.asarray(d.alpha_deg, float)), -np.asarray(d.fy, float), (None if d.mz is None else -np.asarray(d.mz, float))


def bounded_lsq(names, fixed, resid_of, bounds=None):
    """Bounded least squares over the coefficients `names` (the rest as in `fixed`); bounds: {key: (lo,
    hi)} (default BOUNDS)."""
    bounds = BOUNDS if bounds is None else bounds
    lo = np.array([bounds[n][0] for n in names])
    hi = np.array([bounds[n][1] for n in names])
    x0 = np.clip(np.array([fixed[n] for n in names]), lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))

    def resid(x):
        return resid_of(fixed | dict(zip(names, x)))

    # x_scale="jac": the coefficients differ by orders of magnitude (PKY1 ~ -10, PHY1 ~ 1e-3)
    return scipy.optimize.least_squares(resid, x0, bounds=(lo, hi), method="trf", x_scale="jac",
                                        xtol=1e-14, ftol=1e-14, gtol=1e-14, max_nfev=4000)


def fit_pure_lateral(data, nominal: Nominal, fit_pkY4=False, fit_shifts=None, fit_pressure=None,
                     err_range_deg=8.0, start=None) -> FitResult:
    """Least-squares fit of MF 6.1 F_y0 then M_z0 (camber 0) to steady E10 curves.

    data: CurveData per condition (>= 1; the load terms need >= 2 loads, PPY* need >= 2 pressures).
    Residuals are scaled by each curve's peak |F_y| (|M_z|), so every condition weighs the same.
    fit_pkY4: free PKY4 (default fixed at 2, docs/rigid-ring.md §7). fit_shifts: PHY1, PHY2, PVY1,
    PVY2, QHZ1, QHZ2 (default: only when some curve has negative slip angles; from one side only
    the shifts are not identifiable apart from the curve's value at 0). fit_pressure: PPY1..4,
    PPZ1 (default: when the data span >= 2 pressures). The residual torque (QDZ6.., QBZ9/10) and the
    dfz^2 terms (QBZ3, QEZ3) stay 0. start: initial coefficients (default: from the data).
    Returns FitResult; errors are max |MF - data| over |alpha| <= err_range_deg relative to the
    curve's peak |F_y| (|M_z|).
    """
    data = list(data)
    if not data:
        raise ConfigError("fit_pure_lateral: no E10 curves")
    loads = sorted({d.fz for d in data})
    pressures = sorted({d.p for d in data})
    neg = any(np.any(np.asarray(d.alpha_deg) < -1e-9) for d in data)
    fit_shifts = neg if fit_shifts is None else fit_shifts
    fit_pressure = len(pressures) > 1 if fit_pressure is None else fit_pressure
    iso = [_to_iso(d) for d in data]
    peak_fy = [max(np.max(np.abs(f)), 1e-9) for _, f, _ in iso]

    c0 = dict(NEUTRAL) | (start or {})
    if start is None:
        # start from the data at the curve nearest the nominal load: slope at small angles, peak
        j = min(range(len(data)), key=lambda i: abs(data[i].fz - nominal.fnomin) + abs(data[i].p - nominal.nompres))
        a, f, _ = iso[j]
        small = np.abs(a) <= np.radians(2.5)
        k0 = np.polyfit(a[small], f[small], 1)[0] if small.sum() >= 2 else -10 * data[j].fz
        c0["PDY1"] = float(np.clip(peak_fy[j] / data[j].fz * 1.05, 0.06, 2.9))
        c0["PKY1"] = float(np.clip(k0 / (nominal.fnomin * math.sin(2 * math.atan(data[j].fz / (2 * nominal.fnomin)))),
                                   -499, -0.02))
        c0["PEY1"] = -0.5
    names = ["PCY1", "PDY1", "PEY1", "PKY1"]
    if len(loads) > 1:
        names += ["PDY2", "PEY2", "PKY2"]
    if fit_pkY4:
        names.append("PKY4")
    if fit_shifts:
        names += ["PHY1", "PVY1"] + (["PHY2", "PVY2"] if len(loads) > 1 else [])
    if fit_pressure:
        names += ["PPY1", "PPY2", "PPY3", "PPY4"]

    def resid_fy(c):
        return np.concatenate([(fy0(c, nominal, d.fz, a, d.p) - f) / pk for d, (a, f, _), pk in zip(data, iso, peak_fy)])

    sol = bounded_lsq(names, c0, resid_fy)
    coef = c0 | dict(zip(names, map(float, sol.x)))
    ok, msg = bool(sol.success), f"F_y: {sol.message}"

    mz_names = []
    have_mz = [i for i, (_, _, m) in enumerate(iso) if m is not None]
    if have_mz:
        mz_names = ["QBZ1", "QCZ1", "QDZ1", "QEZ1"]
        if len(loads) > 1:
            mz_names += ["QBZ2", "QDZ2", "QEZ2"]
        if fit_shifts:
            mz_names += ["QHZ1"] + (["QHZ2"] if len(loads) > 1 else [])
        if fit_pressure:
            mz_names.append("PPZ1")
        peak_mz = {i: max(np.max(np.abs(iso[i][2])), 1e-9) for i in have_mz}
        if start is None:
            i = min(have_mz, key=lambda i: abs(data[i].fz - nominal.fnomin))
            a, f, m = iso[i]
            small = (np.abs(a) <= np.radians(3.5)) & (np.abs(a) > 0)
            trail = float(np.median(-m[small] / f[small])) if small.any() else 0.05 * nominal.r0
            coef["QDZ1"] = float(np.clip(trail / nominal.r0, 2e-4, 0.9))
            coef["QEZ1"] = -1.0

        def resid_mz(c):
            return np.concatenate([(mz0(c, nominal, data[i].fz, iso[i][0], data[i].p) - iso[i][2]) / peak_mz[i]
                                   for i in have_mz])

        sol_m = bounded_lsq(mz_names, coef, resid_mz)
        coef |= dict(zip(mz_names, map(float, sol_m.x)))
        ok = ok and bool(sol_m.success)
        msg += f"; M_z: {sol_m.message}"

    errors, reach = [], []
    for i, (d, (a, f, m)) in enumerate(zip(data, iso)):
        w = np.abs(a) <= np.radians(err_range_deg) + 1e-12
        reach.append(float(np.degrees(np.abs(a[w]).max())) if w.any() else 0.0)
        e_fy = float(np.max(np.abs(fy0(coef, nominal, d.fz, a[w], d.p) - f[w])) / peak_fy[i]) if w.any() else None
        e_mz = None
        if m is not None and w.any():
            e_mz = float(np.max(np.abs(mz0(coef, nominal, d.fz, a[w], d.p) - m[w])) / max(np.max(np.abs(m)), 1e-9))
        errors.append((d.fz, d.p, e_fy, e_mz))
    at_bound = tuple(n for n in names + mz_names
                     if min(abs(coef[n] - BOUNDS[n][0]), abs(coef[n] - BOUNDS[n][1])) <= 1e-6 * (BOUNDS[n][1] - BOUNDS[n][0]))
    fy_errs = [e[2] for e in errors if e[2] is not None]
    mz_errs = [e[3] for e in errors if e[3] is not None]
    return FitResult(coefficients=coef, fitted_fy=tuple(names), fitted_mz=tuple(mz_names), nominal=nominal,
                     errors=tuple(errors), err_range_deg=err_range_deg, max_fy_error=max(fy_errs) if fy_errs else float("nan"),
                     max_mz_error=max(mz_errs) if mz_errs else None, success=ok, message=msg, at_bound=at_bound,
                     reach_deg=tuple(reach))


def curves_from_characterization(char, pressures=None) -> list:
    """CurveData of every row with E10 curves (optionally only at the given pressures, Pa)."""
    out = []
    for r in char.rows:
        if r.curves is None:
            continue
        if pressures is not None and not any(math.isclose(r.pressure_Pa, p, rel_tol=1e-6) for p in pressures):
            continue
        fy, _ = r.curves.wheel_lateral_force()
        out.append(CurveData(r.load_N, r.pressure_Pa, r.curves.slip_angle_deg, fy, r.curves.M_z_SAE_Nm))
    return out
