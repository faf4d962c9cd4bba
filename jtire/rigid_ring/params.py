"""Rigid-ring parameters of one condition: the measured row, the derived quantities of
docs/rigid-ring.md §3, §5 and §7, and the equinox Module the model integrates.

`derive(row, tire)` gives a `Derived` record (Python floats, None where an input is missing; used by
the tables and the .tir export). `RigidRingParams.from_derived(d)` gives the model's parameters (jax
float64 leaves; `Derived.missing(group)` names what a scenario lacks; a missing input is a placeholder).

Vertical split (§3, revised; `identify`): the dynamic springs use E02's tangent k_vt at the load (the
  secant k_sv without one, named in stiffness_source), 1/k_vt = 1/k_bz + 1/k_vr; variant A (k_dv = k_bz
  + k_vr, larger root to the sidewall; needs k_dv >= 4 k_vt), else variant B (k_bz = k_dv). The
  residual spring F = k_vr1 rho + k_vr2 rho^2 has the tangent k_vr and the secant (1/k_sv - 1/k_bz)^-1
  at the load: the ring rests at F_z/k_sv and rings at the tangent. C_bz + C_vr from E03's belt-mode
  zeta, their split from E04's in-contact bounce zeta; tau = C_tot / k_sv for both is the named fallback.
Longitudinal sidewall spring: k_bx, C_bx measured by E13 (rigid belt pushed fore-aft, jtire's addition);
  without E13 the first spec's isotropy assumption k_bx = k_bz, C_bx = C_bz, named in k_bx_source.
Lateral tread spring (§5): 1/k_cy = 1/k_l - 1/k_by - r_b^2/k_bgamma (rim held in camber; r_b the
  belt centre's height, R0 - rho_r), sigma_c = k_f / k_cy; when 1/k_cy <= 0 or sigma_c falls outside
  [a/4, min(4 a, sigma)], the SWIFT choice sigma_c = a, k_cy = k_f / a (the ring's k_l error reported).
Lateral tread damper: C_cy such that the ring's linear lateral release, with E07's C_by and E08's
  C_bgamma, has E09's fitted zeta (`identify.tread_damper`); k_cy C_l / k_l is the named fallback.
Lateral springs: E07-E09 push statically (the rubber's long-term moduli); the lateral mode rings where
  the storage modulus is higher. The row's k_l_storage (E09's push on the storage moduli at E09's
  release frequency) gives r = k_l_storage / k_l. lateral_springs="maxwell" (the default) keeps the
  static pushes and puts a Maxwell branch beside k_by and k_bgamma (`identify.maxwell_branch`, tau the
  rubber's longest relaxation time) so that the ring's k_l is r k_l at that frequency: static at rest,
  stiffer at the mode. "storage" takes k_by, k_bgamma, k_l x r; "static" neither. k_l_static: E09's k_l.
"""

import dataclasses
import math

import equinox as eqx
import jax.numpy as jnp

from ..errors import ConfigError
from .identify import branch_storage, damping_split, maxwell_branch, mz_curve, residual_spring, tread_damper
from .identify import residual_deflection, vertical_split
from .identify import finite as _ok
from .table import ConditionRow, TireInfo

SIGMA_C_RANGE = (0.25, 4.0)  # plausible sigma_c / a
LATERAL_SPRINGS = ("maxwell", "static", "storage")  # the ring's lateral springs (`derive`; the first: default)


@dataclasses.dataclass(frozen=True)
class Derived:
    """Measured and derived rigid-ring quantities of one condition (SI; None: not available)."""

    load_N: float
    pressure_Pa: float
    tire: TireInfo
    # measured (from the row)
    a: float | None  # contact half length (m)
    w: float | None
    k_sv: float | None
    k_dv: float | None
    f_dv: float | None
    C_tot: float | None
    k_btheta: float | None
    C_btheta: float | None
    k_k: float | None
    k_cx: float | None
    k_by: float | None
    C_by: float | None
    k_bgamma: float | None
    C_bgamma: float | None
    k_l: float | None
    C_l: float | None
    k_f: float | None
    k_m: float | None
    sigma_measured: float | None  # E11 value
    # derived
    rho: float | None  # static deflection F_z / k_sv
    r_l: float | None  # loaded radius R0 - rho (rim centre height)
    r_b: float | None  # belt-centre height R0 - rho_r: the ring's lever arm to the road
    r_e: float | None  # effective rolling radius R0 - rho / 3
    variant_A_valid: bool
    variant_used: str | None  # "A" or "B" or None
    k_bz_A: float | None
    k_vr_A: float | None
    k_bz_B: float | None
    k_vr_B: float | None
    k_bz: float | None
    k_vr: float | None  # residual spring's tangent at the load (with k_bz: k_dv, and the dynamics)
    tau: float | None  # C_tot / k_sv (s)
    C_bz: float | None
    C_vr: float | None
    C_bz_B: float | None
    C_vr_B: float | None
    k_bx: float | None
    C_bx: float | None
    sigma: float | None  # k_f / k_l (the model's)
    k_cy: float | None
    sigma_c: float | None
    C_cy: float | None
    k_cy_source: str | None  # "series compliance" or "fallback sigma_c = a (...)"
    k_l_ring: float | None  # lateral stiffness of the ring with this k_cy (rim camber held)
    k_l_ring_rel_error: float | None
    C_x: float | None  # the ring's standstill fore-aft stiffness: 1/C_x = 1/k_cx + 1/k_bx + r_b^2/k_btheta
    trail: float | None  # k_m / k_f
    k_bx_source: str | None = None  # "E13" (measured) or the isotropy assumption's name
    C_x_shell: float | None = None  # E14's measured standstill C_x: the .tir's LONGITUDINAL_STIFFNESS when there
    k_vt: float | None = None  # E02's tangent vertical stiffness at the load (None: not measured)
    k_vr_secant: float | None = None  # residual spring's secant at the load: 1/k_sv - 1/k_bz
    k_vr1: float | None = None  # contact law F = k_vr1 rho + k_vr2 rho^2 (N/m, N/m^2): its secant at the
    k_vr2: float | None = None  # load is k_vr_secant (static rest at F_z/k_sv), its tangent k_vr
    rho_r: float | None = None  # residual spring's deflection at the load (m)
    rho_max: float | None = None  # above the load + k_vr3 (rho - rho_r)^3 up to rho_max (E02's largest load),
    k_vr3: float | None = None  # then its end slope (`identify.residual_spring`); None: the quadratic throughout
    stiffness_source: str | None = None  # which stiffness the dynamic springs use, and why
    damping_source: str | None = None  # how C_bz, C_vr were identified (or the fallback, and why)
    mz_curve: tuple | None = None  # (alpha SAE rad (n,), M_z SAE N m (n,)): E10's steady curve, odd, ascending
    ellips: tuple | None = None  # E03's tandem cam (l_s, a_e, b_e, c_e) (m, m, m, -); None: point contact
    k_l_static: float | None = None  # E09's static k_l (k_l above is the ring's: x lateral_storage_ratio)
    lateral_storage_ratio: float | None = None  # k_l on the storage moduli / static k_l (None: not measured)
    lateral_spring_source: str | None = None  # which moduli the lateral springs rest on, and why
    C_cy_source: str | None = None  # how the lateral tread damper was identified (`identify.tread_damper`)
    lateral_branch: tuple | None = None  # (beta, tau s): the sidewall's lateral Maxwell branches (`maxwell_branch`)

    @property
    def branch_beta(self) -> float | None:  # the lateral Maxwell branches' stiffness ratio (None: none)
        return None if self.lateral_branch is None else self.lateral_branch[0]

    @property
    def tread_damper_identified(self) -> bool:
        """C_cy from E09's release zeta (`identify.tread_damper`), not the k_cy C_l / k_l fallback."""
        return (self.C_cy_source or "").startswith("E09")

    def k_l_at(self, f_hz: float) -> float | None:
        """The ring's lateral stiffness (rim camber held) on the springs' storage at f_hz: the Maxwell
        branches (when it has them) stiffen the sidewall springs by `identify.branch_storage`."""
        if not _ok(self.k_cy, self.k_by, self.k_bgamma, self.r_b):
            return None
        s = branch_storage(*(self.lateral_branch or (0.0, 1.0)), f_hz)
        return 1.0 / (1.0 / self.k_cy + (1.0 / self.k_by + self.r_b**2 / self.k_bgamma) / s)

    def residual_deflection(self, force: float) -> float:
        """The residual spring's deflection (m) under a contact force (N) (`identify.residual_deflection`)."""
        top = () if self.k_vr3 is None else (self.rho_r, self.rho_max, self.k_vr3)
        return residual_deflection(force, self.k_vr1, self.k_vr2 or 0.0, *top)

    @property
    def uses_tangent(self) -> bool:
        """The dynamic springs are E02's tangent (not the secant fallback)."""
        return (self.stiffness_source or "").startswith("tangent")

    @property
    def dampers_identified(self) -> bool:
        """C_bz, C_vr from E03's belt mode and E04's bounce (not the one-time-constant fallback)."""
        return (self.damping_source or "").startswith("belt mode")

    @property
    def k_bx_measured(self) -> bool:
        """k_bx (and C_bx, or tau k_bx) from E13 rather than the isotropy assumption."""
        return (self.k_bx_source or "").startswith("E13")

    @property
    def uses_storage(self) -> bool:
        """The lateral springs are E07-E09's x lateral_storage_ratio (derive's lateral_springs="storage")."""
        return (self.lateral_spring_source or "").startswith("storage")

    def structural(self) -> dict:
        """FREQ_* (Hz) and DAMP_* (-) of §7, None where an input is missing."""
        t = self.tire

        def freq(k, m):
            return math.sqrt(k / m) / (2 * math.pi) if _ok(k) and k > 0 else None

        def damp(c, k, m):
            return c / (2 * math.sqrt(k * m)) if _ok(c, k) and k > 0 else None

        return {"FREQ_LONG": freq(self.k_bz, t.m_b_kg), "FREQ_LAT": freq(self.k_by, t.m_b_kg),
                "FREQ_YAW": freq(self.k_bgamma, t.I_bx_kgm2), "FREQ_WINDUP": freq(self.k_btheta, t.I_by_kgm2),
                "DAMP_LONG": damp(self.C_bz, self.k_bz, t.m_b_kg), "DAMP_LAT": damp(self.C_by, self.k_by, t.m_b_kg),
                "DAMP_YAW": damp(self.C_bgamma, self.k_bgamma, t.I_bx_kgm2),
                "DAMP_WINDUP": damp(self.C_btheta, self.k_btheta, t.I_by_kgm2),
                "DAMP_RESIDUAL": self.C_vr / self.k_vr if _ok(self.C_vr, self.k_vr) and self.k_vr > 0 else None}

    def missing(self, group: str) -> list:
        """Inputs a model part lacks: group "vertical", "inplane", "lateral_ring", "lateral_reduced"."""
        need = {"vertical": ("k_sv", "k_dv", "C_tot"),
                "inplane": ("k_sv", "k_dv", "C_tot", "k_btheta", "C_btheta", "k_k", "a"),
                "lateral_ring": ("k_sv", "k_by", "C_by", "k_bgamma", "C_bgamma", "k_l", "C_l", "k_f", "k_m", "a"),
                "lateral_reduced": ("k_sv", "k_l", "C_l", "k_f", "k_m")}[group]
        out = [n for n in need if getattr(self, n) is None]
        if group != "lateral_reduced" and self.k_bz is None and "k_dv" not in out and "k_sv" not in out:
            out.append("k_bz (k_dv <= k_sv: neither vertical split is valid)")
        return out

    def require(self, group: str, what: str) -> None:
        m = self.missing(group)
        if m:
            raise ConfigError(f"{what} at {self.load_N:.0f} N / {self.pressure_Pa:.0f} Pa: missing {m}")


def derive(row: ConditionRow, tire: TireInfo, lateral_springs: str = "maxwell") -> Derived:
    """The derived quantities of one row. lateral_springs: "maxwell" (the default), "static" or "storage"
    (the module docstring)."""
    if lateral_springs not in LATERAL_SPRINGS:
        raise ConfigError(f"lateral_springs = {lateral_springs!r}: must be one of {', '.join(LATERAL_SPRINGS)}")
    g = row.get
    fz = row.load_N
    r0 = tire.unloaded_radius_m
    length = g("contact_length_m")
    a = None if length is None else length / 2
    k_sv, f_dv, c_tot = g("k_sv_N_per_m"), g("first_mode_Hz"), g("C_tot_Ns_per_m")
    k_dv = g("k_dv_N_per_m")
    if k_dv is None and f_dv is not None:
        k_dv = (2 * math.pi * f_dv) ** 2 * tire.m_b_kg
    k_k, k_cx = g("k_k_N_per_slip"), g("k_cx_N_per_m")
    if k_cx is None and _ok(k_k, a):
        k_cx = k_k / a
    k_by, k_bgamma, k_l = g("k_by_N_per_m"), g("k_bgamma_Nm_per_rad"), g("k_l_N_per_m")
    k_f, k_m, c_l = g("k_f_N_per_rad"), g("k_m_Nm_per_rad"), g("C_l_Ns_per_m")
    # E09's push on the storage moduli at its release frequency over its static push (measured, reported);
    # "storage" applies it to all three pushes: the springs the lateral mode sees, not the slow build-up
    k_l_static, k_ls = k_l, g("k_l_storage_N_per_m")
    storage = k_ls / k_l if _ok(k_ls, k_l) and k_ls > 0 and k_l > 0 else None
    if storage is not None and lateral_springs == "storage":
        k_by, k_bgamma, k_l = (None if v is None else v * storage for v in (k_by, k_bgamma, k_l))
        f_s = g("f_l_storage_Hz")
        lat_src = (f"storage moduli at {f_s:.4g} Hz (E09's release): E07-E09's springs x {storage:.4g}" if _ok(f_s)
                   else f"storage moduli: E07-E09's springs x {storage:.4g}")
    else:
        lat_src = None if k_l is None else "static pushes (the rubber's long-term moduli)"
    k_btheta = g("k_btheta_Nm_per_rad")

    rho = fz / k_sv if _ok(k_sv) else None
    r_l = None if rho is None else r0 - rho
    r_e = None if rho is None else r0 - rho / 3

    # the springs small motions see: E02's tangent at the load (the load-deflection curve stiffens, and
    # the secant makes the ring's bounce and impact soft), with a quadratic residual spring that keeps
    # the static rest at F_z/k_sv; the secant and a linear spring when that is not possible (named)
    k_t = g("k_sv_tangent_N_per_m")
    vert = res = None
    if not (_ok(k_t, fz, k_sv) and k_t > 0):
        why = "no tangent in the row"
    else:
        vert = vertical_split(k_t, k_dv)
        why = "neither vertical split is valid with the tangent"
        if vert[6] is not None:
            res, why = residual_spring(fz, k_sv, vert[6], vert[7], (g("max_load_N"), g("settled_deflection_at_max_load_m")))
    if res is not None:
        res["stiffness_source"] = "tangent at the load (E02), static rest at the secant k_sv" + (
            "" if res["k_vr3"] is None else ", above the load through E02's largest load")
    else:
        vert = vertical_split(k_sv, k_dv)
        k_lin = vert[7]
        res = {"k_vr_secant": k_lin, "k_vr1": k_lin, "k_vr2": 0.0 if _ok(k_lin) else None,
               "rho_r": fz / k_lin if _ok(k_lin, fz) else None, "stiffness_source": f"secant k_sv ({why})"}
    valid_a, k_bz_a, k_vr_a, k_bz_b, k_vr_b, used, k_bz, k_vr = vert
    tau = c_tot / k_sv if _ok(c_tot, k_sv) else None
    split = damping_split(tire, k_bz, k_vr, g("first_mode_xi"), g("xi_in_contact_fit"), tau)

    def times(t, k):
        return t * k if _ok(t, k) else None

    sigma = k_f / k_l if _ok(k_f, k_l) else None
    k_cy = sigma_c = c_cy = c_cy_src = src = k_l_ring = k_l_err = branch = None
    r_b = r_l if res["rho_r"] is None else r0 - res["rho_r"]
    if _ok(k_l, k_by, k_bgamma, r_b, k_f, a):
        comp = 1.0 / k_l - 1.0 / k_by - r_b**2 / k_bgamma
        sc = k_f * comp if comp > 0 else None
        lo, hi = SIGMA_C_RANGE[0] * a, min(SIGMA_C_RANGE[1] * a, sigma)
        if sc is not None and lo <= sc <= hi:
            k_cy, sigma_c, src = 1.0 / comp, sc, "series compliance 1/k_l - 1/k_by - r_b^2/k_bgamma"
        else:
            why = "1/k_cy <= 0" if sc is None else f"sigma_c = {sc:.4g} m outside [{lo:.4g}, {hi:.4g}]"
            k_cy, sigma_c, src = k_f / a, a, f"fallback sigma_c = a ({why})"
        k_l_ring = 1.0 / (1.0 / k_cy + 1.0 / k_by + r_b**2 / k_bgamma)
        k_l_err = k_l_ring / k_l - 1.0
        if lateral_springs == "maxwell":
            branch, why = maxwell_branch(k_l, k_by, k_bgamma, k_cy, r_b, storage, g("f_l_storage_Hz"),
                                         tire.relaxation_time_s)
            lat_src = why if branch is not None else f"{lat_src} (no Maxwell branch: {why})"
        c_cy, c_cy_src = tread_damper(tire, r_b, k_by, k_cy, k_bgamma, g("C_by_Ns_per_m"), g("C_bgamma_Nms_per_rad"),
                                      g("xi_l_fit"), k_cy * c_l / k_l if _ok(c_l) else None, branch)
    c_x = None
    k_bx, c_bx = g("k_bx_N_per_m"), g("C_bx_Ns_per_m")
    if _ok(k_bx) and k_bx > 0:
        bx_src = "E13"
        if not _ok(c_bx):
            c_bx, bx_src = times(tau, k_bx), "E13 (C_bx = tau k_bx: no decay)"
    else:
        # isotropy: the fore-aft sidewall is the radial one, damper included (C_bz as identified above)
        k_bx, c_bx = k_bz, split[0]
        bx_src = None if k_bz is None else "isotropy assumption k_bx = k_bz, C_bx = C_bz (no E13)"
    if _ok(k_cx, k_bx, r_b, k_btheta):
        c_x = 1.0 / (1.0 / k_cx + 1.0 / k_bx + r_b**2 / k_btheta)
    return Derived(
        load_N=fz, pressure_Pa=row.pressure_Pa, tire=tire, a=a, w=g("contact_width_m"), k_sv=k_sv, k_dv=k_dv,
        f_dv=f_dv, C_tot=c_tot, k_btheta=k_btheta, C_btheta=g("C_btheta_Nms_per_rad"), k_k=k_k, k_cx=k_cx,
        k_by=k_by, C_by=g("C_by_Ns_per_m"), k_bgamma=k_bgamma, C_bgamma=g("C_bgamma_Nms_per_rad"), k_l=k_l,
        C_l=c_l, k_f=k_f, k_m=k_m, sigma_measured=g("sigma_m"), rho=rho, r_l=r_l, r_b=r_b, r_e=r_e,
        variant_A_valid=bool(valid_a), variant_used=used, k_bz_A=k_bz_a, k_vr_A=k_vr_a, k_bz_B=k_bz_b,
        k_vr_B=k_vr_b, k_bz=k_bz, k_vr=k_vr, tau=tau, C_bz=split[0], C_vr=split[1],
        C_bz_B=times(tau, k_bz_b), C_vr_B=times(tau, k_vr_b), k_bx=k_bx, C_bx=c_bx, sigma=sigma,
        k_cy=k_cy, sigma_c=sigma_c, C_cy=c_cy, k_cy_source=src, k_l_ring=k_l_ring, k_l_ring_rel_error=k_l_err,
        C_x=c_x, trail=k_m / k_f if _ok(k_m, k_f) and k_f != 0 else None, k_bx_source=bx_src, C_x_shell=g("C_x_N_per_m"),
        k_vt=k_t, **res, damping_source=split[2], mz_curve=mz_curve(row.curves), ellips=_ellips(row),
        k_l_static=k_l_static, lateral_storage_ratio=storage, lateral_spring_source=lat_src, C_cy_source=c_cy_src,
        lateral_branch=branch)


def _ellips(row) -> tuple | None:
    """E03's tandem cam from the row, when all four parameters are there."""
    v = tuple(row.get(k) for k in ("ellips_shift_m", "ellips_length_m", "ellips_height_m", "ellips_order"))
    return v if all(_ok(x) and x > 0 for x in v) else None


def _mz_table(d: Derived) -> dict:
    if d.mz_curve is not None:
        a, m = d.mz_curve
    else:
        k_m = 1.0 if d.k_m is None else d.k_m
        a, m = (-1.0, 1.0), (-k_m, k_m)
    return {"mz_alpha": jnp.asarray(a, dtype=jnp.float64), "mz_value": jnp.asarray(m, dtype=jnp.float64)}


def _leaf(x):
    # a missing input becomes a finite placeholder (1.0): a part of the model a scenario does not
    # exercise must stay finite, or the adaptive step's error norm turns NaN; every scenario checks
    # its own inputs first (Derived.require)
    return jnp.asarray(1.0 if x is None else x, dtype=jnp.float64)


class RigidRingParams(eqx.Module):
    """Rigid-ring parameters (SI, float64 jax scalars; 1.0 placeholders where not available).

    Masses and inertias: m_b, m_a = m_tot - m_b (rim side, in-plane and ring lateral), m_tot (the
    reduced lateral model's wheel), I_by, I_bx (belt), I_ay, I_ax (rim). Geometry: R0, a (contact
    half length), r_l (loaded radius, R0 - F_z/k_sv), r_e (effective rolling radius). Springs and
    dampers as in docs/rigid-ring.md §2-§6; damp_vlow (s): low-speed tread damping C = damp_vlow k
    that keeps the standing contact from ringing undamped (MF-Swift DAMP_VLOW, 0.001 s).
    """

    m_b: jnp.ndarray
    m_a: jnp.ndarray
    m_tot: jnp.ndarray
    I_by: jnp.ndarray
    I_bx: jnp.ndarray
    I_ay: jnp.ndarray
    I_ax: jnp.ndarray
    R0: jnp.ndarray
    a: jnp.ndarray
    r_l: jnp.ndarray
    r_e: jnp.ndarray
    k_bz: jnp.ndarray
    C_bz: jnp.ndarray
    k_vr: jnp.ndarray  # the residual spring F = k_vr rho + k_vr2 rho^2 (Derived.k_vr1, k_vr2)
    C_vr: jnp.ndarray
    k_bx: jnp.ndarray
    C_bx: jnp.ndarray
    k_btheta: jnp.ndarray
    C_btheta: jnp.ndarray
    k_k: jnp.ndarray
    k_by: jnp.ndarray
    C_by: jnp.ndarray
    k_bgamma: jnp.ndarray
    C_bgamma: jnp.ndarray
    k_cy: jnp.ndarray
    C_cy: jnp.ndarray
    k_l: jnp.ndarray
    C_l: jnp.ndarray
    k_f: jnp.ndarray
    k_m: jnp.ndarray
    damp_vlow: jnp.ndarray
    k_vr2: jnp.ndarray
    rho_r: jnp.ndarray  # the law above the load (`identify.residual_force`; rho_r = rho_max = 1 km: none)
    rho_max: jnp.ndarray
    k_vr3: jnp.ndarray
    k_by_branch: jnp.ndarray  # the sidewall's lateral Maxwell branches: stiffness beta k_by, beta k_bgamma,
    k_bgamma_branch: jnp.ndarray  # relaxation time tau_branch (Derived.lateral_branch; 0 stiffness: none)
    tau_branch: jnp.ndarray
    mz_alpha: jnp.ndarray  # M_z(alpha') as a table (SAE, rad and N m; alpha' = -F_y_SAE / k_f): E10's curve,
    mz_value: jnp.ndarray  # or the line k_m alpha' through two points when the row has none

    @classmethod
    def from_derived(cls, d: Derived, damp_vlow: float = 0.001) -> "RigidRingParams":
        t = d.tire
        if not t.m_tot_kg > t.m_b_kg > 0:
            raise ConfigError(f"tire m_tot_kg = {t.m_tot_kg}, m_b_kg = {t.m_b_kg}: need m_tot > m_b > 0")
        beta, tau = d.lateral_branch or (0.0, 1.0)  # no branch: zero stiffness (its state then idles)
        up = {k: _leaf(v) for k, v in zip(("rho_r", "rho_max", "k_vr3"), (1e3, 1e3, 0.0) if d.k_vr3 is None else
                                          (d.rho_r, d.rho_max, d.k_vr3))}
        return cls(m_b=_leaf(t.m_b_kg), m_a=_leaf(t.m_tot_kg - t.m_b_kg), m_tot=_leaf(t.m_tot_kg),
                   I_by=_leaf(t.I_by_kgm2), I_bx=_leaf(t.I_bx_kgm2), I_ay=_leaf(t.I_ay_kgm2), I_ax=_leaf(t.I_ax_kgm2),
                   R0=_leaf(t.unloaded_radius_m), a=_leaf(d.a), r_l=_leaf(d.r_l), r_e=_leaf(d.r_e),
                   k_bz=_leaf(d.k_bz), C_bz=_leaf(d.C_bz), k_vr=_leaf(d.k_vr1), C_vr=_leaf(d.C_vr),
                   k_bx=_leaf(d.k_bx), C_bx=_leaf(d.C_bx), k_btheta=_leaf(d.k_btheta), C_btheta=_leaf(d.C_btheta),
                   k_k=_leaf(d.k_k), k_by=_leaf(d.k_by), C_by=_leaf(d.C_by), k_bgamma=_leaf(d.k_bgamma),
                   C_bgamma=_leaf(d.C_bgamma), k_cy=_leaf(d.k_cy), C_cy=_leaf(d.C_cy), k_l=_leaf(d.k_l),
                   C_l=_leaf(d.C_l), k_f=_leaf(d.k_f), k_m=_leaf(d.k_m), damp_vlow=_leaf(damp_vlow),
                   k_vr2=_leaf(d.k_vr2 or 0.0), **up, k_by_branch=_leaf(beta * (d.k_by or 0.0)),
                   k_bgamma_branch=_leaf(beta * (d.k_bgamma or 0.0)), tau_branch=_leaf(tau), **_mz_table(d))

    @classmethod
    def from_row(cls, row: ConditionRow, tire: TireInfo, damp_vlow: float = 0.001) -> "RigidRingParams":
        return cls.from_derived(derive(row, tire), damp_vlow)
