"""Magic Formula 6.1/6.2 pure longitudinal slip: F_x0 at zero camber, and its least-squares fit to the
E06 force-slip curves.

Equations (Pacejka, Tire and Vehicle Dynamics 3rd ed. §4.3.2, as coded by the public readers MFeval
and TyreDyn), ISO-W axes, camber 0, all scaling factors lambda = 1, zeta_1 = 1:
  dfz = (F_z - FNOMIN)/FNOMIN, dpi = (p - NOMPRES)/NOMPRES
  S_Hx = PHX1 + PHX2 dfz,  S_Vx = F_z (PVX1 + PVX2 dfz),  kappa_x = kappa + S_Hx
  C_x = PCX1,  mu_x = (PDX1 + PDX2 dfz)(1 + PPX3 dpi + PPX4 dpi^2),  D_x = mu_x F_z
  E_x = (PEX1 + PEX2 dfz + PEX3 dfz^2)(1 - PEX4 sgn(kappa_x)) <= 1
  K_xk = F_z (PKX1 + PKX2 dfz) exp(PKX3 dfz)(1 + PPX1 dpi + PPX2 dpi^2),  B_x = K_xk / (C_x D_x)
  F_x0 = D_x sin(C_x atan(B_x kappa_x - E_x (B_x kappa_x - atan(B_x kappa_x)))) + S_Vx
E06's slip kappa = Omega / Omega_free - 1 and its F_x (> 0 driving) are already ISO.
"""

import dataclasses
import math

import numpy as np

from ..errors import ConfigError
from .magic_formula import Nominal, bounded_lsq, on_bound

FX_KEYS = ("PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PEX3", "PEX4", "PKX1", "PKX2", "PKX3", "PHX1", "PHX2", "PVX1",
           "PVX2", "PPX1", "PPX2", "PPX3", "PPX4")
NEUTRAL = {k: 0.0 for k in FX_KEYS} | {"PCX1": 1.65, "PDX1": 1.0, "PKX1": 20.0}
BOUNDS = {"PCX1": (1.0, 2.5), "PDX1": (0.05, 3.0), "PDX2": (-1.0, 1.0), "PEX1": (-10.0, 1.0), "PEX2": (-10.0, 10.0),
          "PEX3": (-10.0, 10.0), "PEX4": (-1.0, 1.0), "PKX1": (0.01, 500.0), "PKX2": (-50.0, 50.0),
          "PKX3": (-5.0, 5.0), "PHX1": (-0.1, 0.1), "PHX2": (-0.1, 0.1), "PVX1": (-0.5, 0.5), "PVX2": (-0.5, 0.5),
          "PPX1": (-5.0, 5.0), "PPX2": (-5.0, 5.0), "PPX3": (-5.0, 5.0), "PPX4": (-5.0, 5.0)}


def _get(c, k):
    return c.get(k, NEUTRAL[k])


def fx0(c: dict, nom: Nominal, fz, kappa, p=None):
    """Pure longitudinal force F_x0 (N, ISO) at load fz (N), slip kappa, pressure p (Pa; None:
    NOMPRES). Broadcasts."""
    fz, kappa = np.asarray(fz, float), np.asarray(kappa, float)
    p = nom.nompres if p is None else p
    dfz = (fz - nom.fnomin) / nom.fnomin
    dpi = (np.asarray(p, float) - nom.nompres) / nom.nompres
    kx = kappa + _get(c, "PHX1") + _get(c, "PHX2") * dfz
    cx = _get(c, "PCX1")
    dx = (_get(c, "PDX1") + _get(c, "PDX2") * dfz) * (1 + _get(c, "PPX3") * dpi + _get(c, "PPX4") * dpi**2) * fz
    ex = np.minimum((_get(c, "PEX1") + _get(c, "PEX2") * dfz + _get(c, "PEX3") * dfz**2)
                    * (1 - _get(c, "PEX4") * np.sign(kx)), 1.0)
    kxk = slip_stiffness(c, nom, fz, p)
    bx = kxk / (cx * dx + np.where(cx * dx >= 0, 1e-12, -1e-12))
    svx = fz * (_get(c, "PVX1") + _get(c, "PVX2") * dfz)
    return dx * np.sin(cx * np.arctan(bx * kx - ex * (bx * kx - np.arctan(bx * kx)))) + svx


def slip_stiffness(c: dict, nom: Nominal, fz, p=None):
    """K_xk = dF_x0/dkappa at kappa = 0 with no shifts (N per unit slip)."""
    fz = np.asarray(fz, float)
    p = nom.nompres if p is None else p
    dfz = (fz - nom.fnomin) / nom.fnomin
    dpi = (np.asarray(p, float) - nom.nompres) / nom.nompres
    return (fz * (_get(c, "PKX1") + _get(c, "PKX2") * dfz) * np.exp(_get(c, "PKX3") * dfz)
            * (1 + _get(c, "PPX1") * dpi + _get(c, "PPX2") * dpi**2))


@dataclasses.dataclass(frozen=True)
class SlipCurve:
    """One condition's force-slip curve: kappa (n,), F_x (n,) N (ISO), at load fz (N), pressure p (Pa).
    f0: the curve's F_x at kappa = 0 (free rolling: minus the rolling resistance on its surface),
    removed before the fit."""

    fz: float
    p: float
    kappa: np.ndarray
    fx: np.ndarray
    f0: float = 0.0
    surface: str | None = None


@dataclasses.dataclass(frozen=True)
class LongitudinalFit:
    coefficients: dict  # every FX_KEYS value (fitted or fixed)
    fitted: tuple
    nominal: Nominal
    # per condition: (fz, p, max |F_x,MF - (F_x - f0)| over 0..err_range / peak |F_x - f0| over the curve)
    errors: tuple
    err_range: float
    max_error: float
    success: bool
    message: str
    at_bound: tuple = ()  # fitted coefficients that ended on a bound: not identified by the curves
    peak_reached: tuple = ()  # per condition: the curve falls > 2 % of its peak after its maximum

    def bound_note(self, key):
        """Why a coefficient sits on its bound, or None."""
        if key not in self.at_bound:
            return None
        return on_bound(self.coefficients[key], BOUNDS[key],
                        "no curve reaches its peak: the friction level is not identified"
                        if key in ("PDX1", "PDX2", "PCX1") and not any(self.peak_reached) else "the curves do not pin it")


def curves_from_characterization(char, pressures=None) -> list:
    """SlipCurve of every row with E06 curves (optionally only at the given pressures, Pa); points
    with non-finite values dropped, F(0) interpolated at kappa = 0."""
    out = []
    for r in char.rows:
        sc = r.slip_curves
        if sc is None:
            continue
        if pressures is not None and not any(math.isclose(r.pressure_Pa, p, rel_tol=1e-6) for p in pressures):
            continue
        k, f = np.asarray(sc.slip, float), np.asarray(sc.force_x_N, float)
        ok = np.isfinite(k) & np.isfinite(f)
        order = np.argsort(k[ok])
        k, f = k[ok][order], f[ok][order]
        if k.size < 4 or k[0] > 1e-9 or k[-1] <= 0:
            continue  # a curve that does not start at free rolling has no reference point
        out.append(SlipCurve(r.load_N, r.pressure_Pa, k, f, float(np.interp(0.0, k, f)), sc.surface))
    return out


def fit_pure_longitudinal(data, nominal: Nominal, fit_pressure=None, err_range=0.10, start=None) -> LongitudinalFit:
    """Least-squares fit of MF 6.1 F_x0 (camber 0, no shifts) to steady E06 force-slip curves.

    data: SlipCurve per condition (>= 1). Each curve's free-rolling F_x (f0, minus the rolling
    resistance: MF carries that in M_y) is removed first; the shifts PHX*, PVX* stay 0 and PEX4 0
    (only the driving side is measured). Residuals are scaled by each curve's peak |F_x - f0|, so
    every condition weighs the same. The load terms PDX2, PEX2, PKX2 need >= 2 loads, PKX3 and PEX3
    >= 3; the pressure terms PPX1, PPX3 need >= 2 pressures, PPX2, PPX4 >= 3 (fit_pressure=False
    keeps them 0). Errors: max |MF - data| over 0 <= kappa <= err_range relative to the curve's peak.
    """
    data = list(data)
    if not data:
        raise ConfigError("fit_pure_longitudinal: no E06 force-slip curves")
    loads = sorted({d.fz for d in data})
    pressures = sorted({d.p for d in data})
    fit_pressure = len(pressures) > 1 if fit_pressure is None else fit_pressure
    ys = [np.asarray(d.fx, float) - d.f0 for d in data]
    peak = [max(float(np.max(np.abs(y))), 1e-9) for y in ys]

    c0 = dict(NEUTRAL) | (start or {})
    if start is None:
        j = min(range(len(data)), key=lambda i: abs(data[i].fz - nominal.fnomin) + abs(data[i].p - nominal.nompres))
        k, y = np.asarray(data[j].kappa), ys[j]
        small = k <= min(0.02, k.max())
        k0 = np.polyfit(k[small], y[small], 1)[0] if small.sum() >= 2 else y[-1] / k[-1]
        c0["PKX1"] = float(np.clip(k0 / data[j].fz, 0.02, 499.0))
        c0["PDX1"] = float(np.clip(peak[j] / data[j].fz * 1.1, 0.06, 2.9))
        c0["PEX1"] = -0.5
    names = ["PCX1", "PDX1", "PEX1", "PKX1"]
    if len(loads) > 1:
        names += ["PDX2", "PEX2", "PKX2"]
    if len(loads) > 2:
        names += ["PKX3", "PEX3"]
    if fit_pressure and len(pressures) > 1:
        names += ["PPX1", "PPX3"] + (["PPX2", "PPX4"] if len(pressures) > 2 else [])

    def resid(c):
        return np.concatenate([(fx0(c, nominal, d.fz, d.kappa, d.p) - y) / pk for d, y, pk in zip(data, ys, peak)])

    sol = bounded_lsq(names, c0, resid, BOUNDS)
    coef = c0 | dict(zip(names, map(float, sol.x)))
    errors, reached = [], []
    for d, y, pk in zip(data, ys, peak):
        w = np.asarray(d.kappa) <= err_range + 1e-12
        e = float(np.max(np.abs(fx0(coef, nominal, d.fz, d.kappa[w], d.p) - y[w])) / pk)
        errors.append((d.fz, d.p, e))
        reached.append(bool(np.max(y) > y[-1] + 0.02 * pk))  # past its peak by more than a ripple
    at_bound = tuple(n for n in names
                     if min(abs(coef[n] - BOUNDS[n][0]), abs(coef[n] - BOUNDS[n][1])) <= 1e-6 * (BOUNDS[n][1] - BOUNDS[n][0]))
    return LongitudinalFit(coefficients=coef, fitted=tuple(names), nominal=nominal, errors=tuple(errors),
                           err_range=err_range, max_error=max(e[2] for e in errors), success=bool(sol.success),
                           message=f"F_x: {sol.message}", at_bound=at_bound, peak_reached=tuple(reached))
