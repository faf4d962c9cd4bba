"""A synthetic characterization with the study's magnitudes, for tests and demonstrations.

NOT simulation output: every number is a smooth made-up law around the study's rated values
(k_sv = 1280 kN/m, k_l = 450 kN/m, 2a = 200 mm, w = 379 mm at 4625 kg / 120 psi) or a stated
assumption (damping ratios 0.03-0.05, sidewall stiffnesses giving FREQ_* of 20-45 Hz), and the E10
curves come from a known MF 6.1 coefficient set (`TRUE_MF`), so a fit must recover it. The
trends are the physical ones (stiffnesses rise with pressure, the footprint lengthens with load...).
The E06 force-slip curves come from `TRUE_MF_X` plus a free-rolling drag of 0.6 % of F_z (the fit
must remove it); their slope at zero slip is near, not equal to, the row's k_k law. E12's drag is 0.6 %
of F_z at the rated condition and a power law in load and pressure around it.
"""

import dataclasses

import numpy as np

from .. import units as U
from .magic_formula import Nominal, cornering_stiffness, fy0, mz0
from .mf_longitudinal import fx0
from .table import Characterization, ConditionRow, E06Curves, E10Curves, TireInfo

LOADS_KG = (2312.5, 4625.0, 6937.5)
PRESSURES_PSI = (70.0, 120.0, 150.0)
E10_ANGLES_DEG = (0, 1, 2, 3, 4, 6, 8, 10, 12, 20)
# a truck-tire-like MF 6.1 pure-side-slip set (ISO); pressure terms non-zero so a multi-pressure
# fit has something to find
TRUE_MF = {"PCY1": 1.35, "PDY1": 0.85, "PDY2": -0.12, "PEY1": -0.6, "PEY2": -0.25, "PKY1": -5.0, "PKY2": 1.8,
           "PKY4": 2.0, "PPY1": 0.3, "PPY2": 0.6, "PPY3": -0.1, "PPY4": 0.05,
           "QBZ1": 9.0, "QBZ2": -1.5, "QCZ1": 1.25, "QDZ1": 0.075, "QDZ2": -0.012, "QEZ1": -1.5, "QEZ2": -0.4,
           "PPZ1": 0.4}
# pure longitudinal slip (ISO, driving side), every load and pressure term non-zero
TRUE_MF_X = {"PCX1": 1.6, "PDX1": 0.9, "PDX2": -0.08, "PEX1": 0.3, "PEX2": 0.1, "PEX3": -0.05, "PKX1": 24.0,
             "PKX2": -3.0, "PKX3": 0.2, "PPX1": -0.3, "PPX2": 0.2, "PPX3": -0.1, "PPX4": 0.05}
E06_SLIPS = tuple(np.round(np.linspace(0.0, 0.2, 21), 12))
FREE_ROLLING_DRAG = 0.006  # of F_z: F_x at zero slip is -0.006 F_z (the rolling resistance)
# E12's drag: FREE_ROLLING_DRAG F_z at the rated condition, x (F_z/F_z,rated)^0.15 (p/p_rated)^-0.3 elsewhere
RR_LOAD_EXPONENT, RR_PRESSURE_EXPONENT = 0.15, -0.3


def _xi_c(xi, k, m):
    return 2 * xi * np.sqrt(k * m)


def row(tire: TireInfo, load_kg: float, pressure_psi: float, mf=None, angles_deg=E10_ANGLES_DEG,
        damping_spread: float = 0.04, slips=E06_SLIPS) -> ConditionRow:
    """One synthetic condition. damping_spread: relative gap put between the two-peak and the
    fitted damping values (two-peak = fit x (1 + spread)); slips: the E06 curve's slips (None: no
    E06 curve)."""
    mf = TRUE_MF if mf is None else mf
    fz, p = load_kg * U.G0, pressure_psi * U.PSI
    pr = p / tire.rated_pressure_Pa
    lr = fz / tire.rated_load_N
    nom = Nominal(tire.rated_load_N, tire.rated_pressure_Pa, tire.unloaded_radius_m)
    k_sv = 1.28e6 * pr**0.55 * (1 + 0.08 * (lr - 1))
    f1 = 72.0 * pr**0.12 * (1 + 0.03 * (lr - 1))
    k_dv = (2 * np.pi * f1) ** 2 * tire.m_b_kg
    length = 0.20012 * (lr**0.55) * pr**-0.3
    width = 0.37932 * lr**0.08 * pr**-0.04
    k_bth = 1.2e6 * pr**0.5
    k_k = 1.1e6 * lr**0.8 * pr**0.1
    k_by = 2.0e6 * pr**0.6
    k_bg = 2.0e5 * pr**0.6
    k_l = 450.4639e3 * pr**0.7 * (1 + 0.05 * (lr - 1))
    k_f = float(-cornering_stiffness(mf, nom, fz, p))
    alpha = np.radians(np.asarray(angles_deg, float))
    fy_sae = -fy0(mf, nom, fz, -alpha, p)
    mz_sae = -mz0(mf, nom, fz, -alpha, p)
    small = alpha <= np.radians(3.0)
    k_m = float(np.polyfit(alpha[small], mz_sae[small], 1)[0])
    q = {"contact_length_m": length, "contact_width_m": width, "k_sv_N_per_m": k_sv, "first_mode_Hz": f1,
         "k_dv_N_per_m": k_dv, "k_btheta_Nm_per_rad": k_bth, "k_k_N_per_slip": k_k, "k_cx_N_per_m": k_k / (length / 2),
         "k_by_N_per_m": k_by, "k_bgamma_Nm_per_rad": k_bg, "k_l_N_per_m": k_l, "k_f_N_per_rad": k_f,
         "k_m_Nm_per_rad": k_m, "sigma_m": k_f / k_l, "deflection_m": fz / k_sv,
         "rolling_resistance_N": FREE_ROLLING_DRAG * fz * lr**RR_LOAD_EXPONENT * pr**RR_PRESSURE_EXPONENT}
    for stem, unit, xi, k, m in (("C_tot", "Ns_per_m", 0.05, k_sv, tire.m_tot_kg),
                                 ("C_btheta", "Nms_per_rad", 0.04, k_bth, tire.I_by_kgm2),
                                 ("C_by", "Ns_per_m", 0.04, k_by, tire.m_b_kg),
                                 ("C_bgamma", "Nms_per_rad", 0.045, k_bg, tire.I_bx_kgm2),
                                 ("C_l", "Ns_per_m", 0.032, k_l, tire.m_tot_kg)):
        c_fit = _xi_c(xi, k, m)
        q[f"{stem}_fit_{unit}"] = c_fit
        q[f"{stem}_2p_{unit}"] = c_fit * (1 + damping_spread)
        q[f"{stem}_{unit}"] = c_fit * (1 + damping_spread)
    curves = E10Curves(slip_angle_deg=np.asarray(angles_deg, float), lateral_force_N=fy_sae, M_z_SAE_Nm=mz_sae,
                       F_z_N=np.full(alpha.shape, fz), F_y_SAE_N=fy_sae)
    slip = None
    if slips is not None:
        k = np.asarray(slips, float)
        slip = E06Curves(slip=k, force_x_N=fx0(TRUE_MF_X, nom, fz, k, p) - FREE_ROLLING_DRAG * fz,
                         force_z_N=np.full(k.shape, fz), surface="flat")
    return ConditionRow(fz, p, q, curves, slip)



def characterization(tire: TireInfo | None = None, loads_kg=LOADS_KG, pressures_psi=PRESSURES_PSI, mf=None,
                     angles_deg=E10_ANGLES_DEG, slips=E06_SLIPS) -> Characterization:
    """The full synthetic grid (default 3 loads x 3 pressures) for the study's tire."""
    tire = TireInfo.from_reference() if tire is None else tire
    rows = tuple(row(tire, lk, pp, mf, angles_deg, slips=slips) for lk in loads_kg for pp in pressures_psi)
    return Characterization(tire, rows)


def drop(char: Characterization, keys) -> Characterization:
    """The same characterization with the given quantity keys removed from every row."""
    rows = tuple(dataclasses.replace(r, q={k: v for k, v in r.q.items() if k not in keys}) for r in char.rows)
    return Characterization(char.tire, rows)
