"""Rigid-ring identification of the vertical path and the aligning moment from a measured row
(docs/rigid-ring.md §3, revised; `params.derive` uses them): the split of the dynamic stiffness
with the drum's k_dv, the residual spring's quadratic law, the two-test damper split, and E10's
M_z curve as a table."""

import math

import numpy as np

from .linear import modes as linear_modes


def finite(*xs):
    return all(x is not None and math.isfinite(x) for x in xs)


def vertical_split(k_dyn, k_dv):
    """§3's split of the dynamic stiffness k_dyn (tangent or secant) with the drum's k_dv:
    (valid_a, k_bz_A, k_vr_A, k_bz_B, k_vr_B, variant used, k_bz, k_vr)."""
    valid_a = finite(k_dyn, k_dv) and k_dv >= 4 * k_dyn
    k_bz_a = k_vr_a = k_bz_b = k_vr_b = None
    if valid_a:
        disc = math.sqrt(k_dv * k_dv - 4 * k_dv * k_dyn)
        k_bz_a, k_vr_a = 0.5 * (k_dv + disc), 0.5 * (k_dv - disc)
    if finite(k_dyn, k_dv) and k_dv > k_dyn:
        k_bz_b, k_vr_b = k_dv, 1.0 / (1.0 / k_dyn - 1.0 / k_dv)
    if valid_a:
        return valid_a, k_bz_a, k_vr_a, k_bz_b, k_vr_b, "A", k_bz_a, k_vr_a
    if k_bz_b is not None:
        return valid_a, k_bz_a, k_vr_a, k_bz_b, k_vr_b, "B", k_bz_b, k_vr_b
    return valid_a, k_bz_a, k_vr_a, k_bz_b, k_vr_b, None, None, None


def residual_spring(fz, k_sv, k_bz, k_vr):
    """The residual (belt-road) spring's law F = k_vr1 rho + k_vr2 rho^2 such that, with the sidewall's
    k_bz in series, its secant at the load gives the static rest F_z/k_sv and its tangent is k_vr.
    Returns (fields, None) or (None, why) when no such law stiffens monotonically from rho = 0
    (k_vr2 >= 0, k_vr1 > 0)."""
    if not k_bz > k_sv:
        return None, f"k_bz = {k_bz:.4g} N/m <= k_sv: no residual secant"
    ks = 1.0 / (1.0 / k_sv - 1.0 / k_bz)
    rho = fz / ks
    k1, k2 = 2.0 * ks - k_vr, (k_vr - ks) / rho
    if k2 < 0 or k1 <= 0:
        return None, "its residual spring softens" if k2 < 0 else "its residual spring stiffens past a quadratic"
    return {"k_vr_secant": ks, "k_vr1": k1, "k_vr2": k2, "rho_r": rho}, None


def damping_split(tire, k_bz, k_vr, zeta_v, zeta_bounce, tau, n_grid=201):
    """(C_bz, C_vr, source) from two tests (rigid-ring.md §3, revised): the rim-locked belt mode on the
    drum (E03's modal zeta_v) fixes C_bz + C_vr = 2 zeta_v sqrt((k_bz + k_vr) m_b); the drop's bounce
    in contact (E04's zeta after the last lift-off: rim mass on the sidewall, belt on the road) fixes
    how it divides. The share is found where the linear 2-DOF bounce mode's zeta meets the measured
    one (a root bracketed on a grid, then bisected; the root nearest the equal-tau share when there are
    two). No root, or a missing input: the one time constant tau = C_tot/k_sv for both (named)."""
    def fallback(why):
        c = (None, None) if not finite(tau, k_bz, k_vr) else (tau * k_bz, tau * k_vr)
        return (*c, f"one time constant tau = C_tot/k_sv for both (fallback: {why})")

    if not finite(k_bz, k_vr):
        return fallback("no vertical split")
    if not finite(zeta_v, zeta_bounce) or zeta_v <= 0 or zeta_bounce <= 0:
        miss = [n for n, v in (("E03 first_mode_xi", zeta_v), ("E04 xi_in_contact_fit", zeta_bounce))
                if not finite(v) or v <= 0]
        return fallback(f"no {' or '.join(miss)}")
    m_a, m_b = tire.m_tot_kg - tire.m_b_kg, tire.m_b_kg
    total = 2.0 * zeta_v * math.sqrt((k_bz + k_vr) * m_b)
    M = np.diag([m_a, m_b])
    K = np.array([[k_bz, -k_bz], [-k_bz, k_bz + k_vr]])

    def gap(x):  # bounce zeta with C_bz = x total, C_vr = (1 - x) total, minus the measured one
        cb, cr = x * total, (1.0 - x) * total
        _, z, _ = linear_modes(M, K, np.array([[cb, -cb], [-cb, cb + cr]]))
        return (z[0] if len(z) == 2 else np.nan) - zeta_bounce

    xs = np.linspace(0.0, 1.0, n_grid)
    gs = np.array([gap(x) for x in xs])
    brackets = [i for i in range(n_grid - 1) if np.isfinite(gs[i]) and np.isfinite(gs[i + 1]) and gs[i] * gs[i + 1] <= 0]
    if not brackets:
        ok = gs[np.isfinite(gs)]
        rng = "" if ok.size == 0 else f" (it spans {ok.min() + zeta_bounce:.3g}-{ok.max() + zeta_bounce:.3g})"
        return fallback(f"no C_bz, C_vr >= 0 with C_bz + C_vr from the belt mode's zeta {zeta_v:.3g} gives the "
                        f"bounce's zeta {zeta_bounce:.3g}{rng}")
    x_tau = k_bz / (k_bz + k_vr)
    i = min(brackets, key=lambda j: abs(xs[j] - x_tau))
    lo, hi, g_lo = xs[i], xs[i + 1], gs[i]
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        g_mid = gap(mid)
        if g_lo * g_mid <= 0:
            hi = mid
        else:
            lo, g_lo = mid, g_mid
    x = 0.5 * (lo + hi)
    return x * total, (1.0 - x) * total, (f"belt mode zeta {zeta_v:.3g} (E03) and in-contact bounce zeta "
                                          f"{zeta_bounce:.3g} (E04)")


def mz_curve(curves):
    """E10's steady M_z(alpha) of the condition as an odd, ascending table (SAE, rad and N m), or None
    without a curve. Where both signs of an angle were run, their odd part (M(a) - M(-a)) / 2."""
    if curves is None or curves.M_z_SAE_Nm is None:
        return None
    a = np.radians(np.asarray(curves.slip_angle_deg, float))
    m = np.asarray(curves.M_z_SAE_Nm, float)
    ok = np.isfinite(a) & np.isfinite(m)
    a, m = a[ok], m[ok]
    pos = sorted({round(float(x), 12) for x in np.abs(a) if x > 0})
    if not pos:
        return None
    vals = []
    for x in pos:
        plus, minus = m[np.isclose(a, x)], m[np.isclose(a, -x)]
        vals.append(float(plus.mean() - minus.mean()) / 2 if plus.size and minus.size else
                    float(plus.mean()) if plus.size else -float(minus.mean()))
    xs = np.concatenate([-np.asarray(pos)[::-1], [0.0], pos])
    ms = np.concatenate([-np.asarray(vals)[::-1], [0.0], vals])
    return tuple(xs.tolist()), tuple(ms.tolist())
