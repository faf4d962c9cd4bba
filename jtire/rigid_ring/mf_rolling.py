"""MF 6.1/6.2 rolling resistance (QSY1, QSY7, QSY8) from E12's free-rolling drag.

The .tir's rolling-resistance moment (MF 6.1.2; Pacejka 2012, 4.E70 in the form the TNO solver and
MFeval use): M_y = -R0 FNOMIN (QSY1 + QSY2 F_x/FNOMIN + QSY3 |V_x/LONGVL| + QSY4 (V_x/LONGVL)^4 + ...)
(F_z/FNOMIN)^QSY7 (p/NOMPRES)^QSY8. A free-rolling wheel in a vehicle model balances M_y with the road's
F_x about the axle, F_x R_l = M_y, so E12's hub drag D means |M_y| = D R_l, with R_l = R0 - rho and rho
the .tir's own static deflection at F_z (`loaded_radius`: the file's F_z(rho) law). E12 runs at one
speed, so the moment is taken as speed-independent (QSY3 = QSY4 = 0) and QSY2 (the F_x term) is 0.
Fits: ln|M_y| = ln(R0 FNOMIN QSY1) + QSY7 ln(F_z/FNOMIN) over the loads at NOMPRES (least squares;
one load: QSY1 alone, QSY7 = 1), then QSY8 over the pressures at FNOMIN (through the fitted nominal).
"""

import dataclasses
import math

import numpy as np


def loaded_radius(fz, dpi, R0, fnomin, c_z, q_fz2, pfz1=0.0):
    """R0 - rho, rho the root of F_z = FNOMIN (1 + PFZ1 dpi)(Q_FZ1 x + Q_FZ2 x^2), x = rho/R0, with
    Q_FZ1 = sqrt((C_z R0/FNOMIN)^2 - 4 Q_FZ2) (MF 6.1's vertical force at zero speed, no camber or
    shear terms)."""
    q1 = math.sqrt((c_z * R0 / fnomin) ** 2 - 4.0 * q_fz2)
    f = fz / (fnomin * (1.0 + pfz1 * dpi))
    x = f / q1 if q_fz2 == 0 else 2.0 * f / (q1 + math.sqrt(q1 * q1 + 4.0 * q_fz2 * f))  # the stable root
    return R0 * (1.0 - x)


@dataclasses.dataclass(frozen=True)
class RollingFit:
    """QSY1, QSY7, QSY8 and how well the law gives back E12's drag at each condition used."""

    qsy1: float
    qsy7: float | None  # None: one load (the default 1 stands)
    qsy8: float | None  # None: one pressure (the default 0 stands)
    n_loads: int
    n_pressures: int
    errors: tuple  # ((F_z, p, E12's drag, the law's drag, relative error), ...) at every condition given

    @property
    def max_error(self) -> float:
        return max(abs(e[-1]) for e in self.errors)

    def drag(self, fz, p, r_l, R0, fnomin, nompres) -> float:
        """The hub drag (N) the fitted M_y gives at F_z, p on a loaded radius r_l."""
        m = R0 * fnomin * self.qsy1 * (fz / fnomin) ** (self.qsy7 or 1.0) * (p / nompres) ** (self.qsy8 or 0.0)
        return m / r_l


def fit(points, R0, fnomin, nompres):
    """points: [(F_z, p, drag D, loaded radius R_l)] with D > 0 (N) at every condition. None without a
    point at NOMPRES."""
    pts = [(fz, p, d, r) for fz, p, d, r in points if d is not None and d > 0 and r > 0]
    at_p = [q for q in pts if math.isclose(q[1], nompres, rel_tol=1e-6)]
    if not at_p:
        return None
    x = np.array([math.log(fz / fnomin) for fz, _, _, _ in at_p])
    y = np.array([math.log(d * r / (R0 * fnomin)) for _, _, d, r in at_p])
    if len({round(v, 9) for v in x}) >= 2:
        c = np.linalg.lstsq(np.column_stack([np.ones_like(x), x]), y, rcond=None)[0]
        qsy1, qsy7 = math.exp(c[0]), float(c[1])
    else:  # one load: QSY1 at it (the moment taken as proportional to the load, QSY7 = 1)
        qsy1, qsy7 = float(np.mean(np.exp(y - x))), None
    at_l = [q for q in pts if math.isclose(q[0], fnomin, rel_tol=1e-6) and not math.isclose(q[1], nompres, rel_tol=1e-6)]
    qsy8 = None
    if at_l:
        u = np.array([math.log(p / nompres) for _, p, _, _ in at_l])
        v = np.array([math.log(d * r / (R0 * fnomin * qsy1)) for _, _, d, r in at_l])
        qsy8 = float(u @ v / (u @ u))
    f = RollingFit(qsy1, qsy7, qsy8, len(at_p), len(at_l) + 1, ())
    errors = tuple((fz, p, d, f.drag(fz, p, r, R0, fnomin, nompres),
                    f.drag(fz, p, r, R0, fnomin, nompres) / d - 1.0) for fz, p, d, r in pts)
    return dataclasses.replace(f, errors=errors)


def rolling_fit(char, vals, rated=None):
    """`mf_rolling.fit` of E12's drag on the loaded radius of this file's own F_z(rho) (vals: {key: (value,
    comment)}, e.g. from `build`'s sections); None without a drag at the nominal pressure."""
    r0 = rated or char.rated_row()
    fz0, p0, R0 = r0.load_N, r0.pressure_Pa, char.tire.unloaded_radius_m
    c_z, q_fz2, pfz1 = (vals.get(k, (d, ""))[0] for k, d in (("VERTICAL_STIFFNESS", None), ("Q_FZ2", 0.0), ("PFZ1", 0.0)))
    if not c_z:
        return None
    pts = [(r.load_N, r.pressure_Pa, r.get("rolling_resistance_N"),
            loaded_radius(r.load_N, (r.pressure_Pa - p0) / p0, R0, fz0, c_z, q_fz2, pfz1))
           for r in char.rows if r.get("rolling_resistance_N")]
    return fit(pts, R0, fz0, p0)


def put_keys(char, vals, put, notes, rated):
    """The .tir's QSY1, QSY7, QSY8 from `rolling_fit` (put(key, value, comment), as in `tir.build`); QSY2-QSY4
    0, with why."""
    f = rolling_fit(char, vals, rated)
    if f is None:
        notes.append("no E12 drag at the nominal pressure: QSY1 and QSY7 are defaults (rolling resistance not exported)")
        return
    fz0, p0 = rated.load_N, rated.pressure_Pa
    fitted = [e for e in f.errors if math.isclose(e[1], p0, rel_tol=1e-6) or math.isclose(e[0], fz0, rel_tol=1e-6)]
    err = (f"E12's drag D, |M_y| = D R_l (R_l = R0 - rho, rho from this file's F_z law); max drag error "
           f"{100 * max(abs(e[-1]) for e in fitted):.2g} % at the {len(fitted)} conditions fitted, "
           f"{100 * f.max_error:.2g} % at all {len(f.errors)}")
    put("QSY1", f.qsy1, f"|M_y|/(R0 FNOMIN) at {fz0:.0f} N / {p0 / 1e3:.0f} kPa, fitted over {f.n_loads} loads: {err}")
    if f.qsy7 is not None:
        put("QSY7", f.qsy7, f"ln|M_y| vs ln(F_z/FNOMIN) over {f.n_loads} loads at {p0 / 1e3:.0f} kPa (E12)")
    if f.qsy8 is not None:
        put("QSY8", f.qsy8, f"ln|M_y| vs ln(p/NOMPRES) over {f.n_pressures} pressures at {fz0:.0f} N (E12)")
    for k, why in (("QSY2", "0: E12 rolls free (no F_x term identified)"),
                   ("QSY3", "0: E12 ran at one speed (the moment taken as speed-independent)"),
                   ("QSY4", "0: E12 ran at one speed")):
        put(k, 0.0, why)
