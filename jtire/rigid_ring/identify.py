"""Rigid-ring identification of the vertical path and the aligning moment from a measured row
(docs/rigid-ring.md §3, revised; `params.derive` uses them): the split of the dynamic stiffness
with the drum's k_dv, the residual spring's quadratic law, the two-test damper split, the tread's
lateral damper from E09's release, the sidewall's lateral Maxwell branches, and E10's M_z curve as a
table."""

import math

import numpy as np

from .linear import lateral_ring_modes
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


def residual_spring(fz, k_sv, k_bz, k_vr, top=None):
    """The residual (belt-road) spring's law F = k_vr1 rho + k_vr2 rho^2 up to the load, such that, with
    the sidewall's k_bz in series, its secant at the load gives the static rest F_z/k_sv and its tangent
    is k_vr. top = (F_max, deflection at F_max): E02's largest load; above the load the law then goes on
    with a cubic term k_vr3 s^3 (s = rho - rho_r: value, tangent and curvature continuous at the rest)
    through E02's largest load, and past it along its end slope, instead of stiffening quadratically
    (`residual_force`). Returns (fields, None) or (None, why) when no law stiffens monotonically from
    rho = 0 (k_vr2 >= 0, k_vr1 > 0); an upper piece whose end slope is not positive is left out."""
    if not k_bz > k_sv:
        return None, f"k_bz = {k_bz:.4g} N/m <= k_sv: no residual secant"
    ks = 1.0 / (1.0 / k_sv - 1.0 / k_bz)
    rho = fz / ks
    k1, k2 = 2.0 * ks - k_vr, (k_vr - ks) / rho
    if k2 < 0 or k1 <= 0:
        return None, "its residual spring softens" if k2 < 0 else "its residual spring stiffens past a quadratic"
    out = {"k_vr_secant": ks, "k_vr1": k1, "k_vr2": k2, "rho_r": rho, "rho_max": None, "k_vr3": None}
    if top is not None and finite(*top) and top[0] > 1.05 * fz:
        span = top[1] - top[0] / k_bz - rho
        if span > 0:
            k3 = (top[0] - fz - k_vr * span - k2 * span**2) / span**3
            # F' = k_vr + 2 k2 s + 3 k3 s^2 is positive on [0, span] when it is at both ends (k2 >= 0)
            if k_vr + 2.0 * k2 * span + 3.0 * k3 * span**2 > 0:
                out |= {"rho_max": rho + span, "k_vr3": k3}
    return out, None


def residual_force(rho, k1, k2, rho_r, rho_max, k3, xp=np):
    """The residual spring's force (N) at deflection rho (m, >= 0) on the law of `residual_spring`:
    k1 rho + k2 rho^2 + k3 s^3 with s = clip(rho - rho_r, 0, rho_max - rho_r), and past rho_max the
    end slope's line (k3 = 0 and rho_max beyond any deflection: the quadratic throughout; xp: numpy or
    jax.numpy)."""
    top = xp.minimum(rho, rho_max)
    s = xp.clip(rho - rho_r, 0.0, rho_max - rho_r)
    span = rho_max - rho_r
    k_end = k1 + 2.0 * k2 * rho_max + 3.0 * k3 * span**2
    return k1 * top + k2 * top**2 + k3 * s**3 + k_end * xp.maximum(rho - rho_max, 0.0)


def residual_deflection(force, k1, k2, rho_r=math.inf, rho_max=math.inf, k3=0.0):
    """The inverse of `residual_force`: rho (m) under a contact force (N)."""
    def quad(f):  # rho >= 0 with k1 rho + k2 rho^2 = f, the stable root
        return f / k1 if k2 == 0.0 else 2.0 * f / (k1 + math.sqrt(k1 * k1 + 4.0 * k2 * f))

    if not math.isfinite(rho_r) or force <= k1 * rho_r + k2 * rho_r**2:
        return quad(force)
    f_max = float(residual_force(rho_max, k1, k2, rho_r, rho_max, k3))
    if force > f_max:
        span = rho_max - rho_r
        return rho_max + (force - f_max) / (k1 + 2.0 * k2 * rho_max + 3.0 * k3 * span**2)
    lo, hi = rho_r, rho_max  # monotone between: bisection to round-off
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if residual_force(mid, k1, k2, rho_r, rho_max, k3) < force else (lo, mid)
    return 0.5 * (lo + hi)


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


def tread_damper(tire, r_b, k_by, k_cy, k_bgamma, C_by, C_bgamma, zeta_l, c_fallback, branch=None, c_max=1e6):
    """(C_cy, source) of the ring's lateral tread damper (rigid-ring.md §5, revised). E07 and E08 measure
    the sidewall's C_by and C_bgamma; the tread's damper has no test of its own, and E09's release is
    the test that excites it: C_cy is set so the ring's linear lateral release (`linear.lateral_ring_modes`,
    with the sidewall's Maxwell branches `branch` = (beta, tau) when it has them) has E09's fitted zeta_l
    (its damped-sine fit, the same reduction the validation applies to both records): the smallest such
    C_cy in [0, c_max], bracketed on a grid, then bisected. Fallback, named: c_fallback (k_cy C_l / k_l,
    the tread at E09's time constant) when zeta_l is missing or no C_cy >= 0 reaches it (the sidewall's
    dampers alone give more)."""
    if not finite(r_b, k_by, k_cy, k_bgamma, C_by, C_bgamma):
        return c_fallback, "k_cy C_l / k_l (fallback: the ring's lateral springs or sidewall dampers are missing)"
    if not finite(zeta_l) or zeta_l <= 0:
        return c_fallback, "k_cy C_l / k_l (fallback: no E09 xi_l_fit)"

    def zeta(c):
        _, z = lateral_ring_modes(tire, r_b, k_by, k_cy, k_bgamma, C_by, c, C_bgamma, branch)
        return z[0] if len(z) else np.nan

    cs = np.concatenate([[0.0], np.geomspace(1.0, c_max, 121)])
    gs = np.array([zeta(c) for c in cs]) - zeta_l
    up = [i for i in range(cs.size - 1) if np.isfinite(gs[i]) and np.isfinite(gs[i + 1]) and gs[i] <= 0 <= gs[i + 1]]
    if not up:  # (a stiff enough tread damper locks the tread: zeta is not monotone in C_cy, hence the grid)
        ok = gs[np.isfinite(gs)] + zeta_l
        rng = "" if ok.size == 0 else f" spans zeta {ok.min():.3g}-{ok.max():.3g}"
        return c_fallback, (f"k_cy C_l / k_l (fallback: the ring's release{rng} for C_cy in [0, {c_max:.3g}] N s/m, "
                            f"E09's is {zeta_l:.3g})")
    lo, hi = cs[up[0]], cs[up[0] + 1]  # the smallest C_cy that reaches it
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if zeta(mid) < zeta_l:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi), f"E09's release zeta {zeta_l:.3g} (damped-sine fit) with E07's C_by and E08's C_bgamma"


def branch_storage(beta, tau, f_hz):
    """A spring k with a Maxwell branch (beta k, relaxation time tau) beside it, on its storage at f_hz:
    k x (1 + beta x^2 / (1 + x^2)), x = 2 pi f tau. Returns that factor."""
    x2 = (2.0 * math.pi * f_hz * tau) ** 2
    return 1.0 + beta * x2 / (1.0 + x2)


def sidewall_stiffening(k_l, k_by, k_bgamma, k_cy, r_b, storage_ratio):
    """The factor s on both sidewall springs that makes the ring's series lateral stiffness (rim camber
    held, tread k_cy unchanged) storage_ratio x k_l: 1/(storage_ratio k_l) = 1/k_cy + (1/k_by +
    r_b^2/k_bgamma) / s. None when the tread alone is softer than that."""
    rest = 1.0 / (storage_ratio * k_l) - 1.0 / k_cy
    return (1.0 / k_by + r_b**2 / k_bgamma) / rest if rest > 0 else None


def maxwell_branch(k_l, k_by, k_bgamma, k_cy, r_b, storage_ratio, f_storage, tau):
    """((beta, tau), source) of the sidewall's lateral Maxwell branches (rigid-ring.md §5, revised), or
    (None, why). E07-E09 push statically (the rubber's long-term moduli); E09's push on the storage
    moduli at its release frequency f_storage gives k_l' = storage_ratio k_l. The ring keeps its static
    springs, so E09's static deflection and the slip step's slow build-up see them, and puts a Maxwell
    branch (stiffness beta k, relaxation time tau) beside k_by and k_bgamma, with beta such that at
    f_storage the sidewall's `branch_storage` is the `sidewall_stiffening` that gives k_l' (tread k_cy
    unchanged: the tread's own stiffening is carried by the sidewall's branches)."""
    if not finite(storage_ratio, f_storage) or storage_ratio <= 1.0 or f_storage <= 0:
        return None, "no push on the storage moduli in the row (k_l_storage, f_l_storage_Hz), or k_l' <= k_l"
    if not finite(tau) or tau <= 0:
        return None, "no relaxation time in the characterization's tire (an older folder)"
    if not finite(k_l, k_by, k_bgamma, k_cy, r_b):
        return None, "the lateral springs are missing"
    s = sidewall_stiffening(k_l, k_by, k_bgamma, k_cy, r_b, storage_ratio)
    if s is None:
        return None, f"the tread's k_cy alone is softer than k_l' = {storage_ratio * k_l:.4g} N/m"
    beta = (s - 1.0) / (branch_storage(1.0, tau, f_storage) - 1.0)  # branch_storage is linear in beta
    return (beta, tau), (f"static pushes with a Maxwell branch beside k_by and k_bgamma (beta {beta:.4g}, tau "
                         f"{tau * 1e3:.4g} ms): k_l x {storage_ratio:.4g} at {f_storage:.4g} Hz, E09's release on the "
                         f"storage moduli")


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
