"""The rigid ring's linear equations in numpy (the same equations as `model.RigidRing`, no
simulation): its vertical, belt, fore-aft and lateral modes (frequency and damping ratio) and the
stretched-string step response of the slip-step test. `diagnosis` puts the populated ring through
them to name the causes of its disagreements with the shell model.
"""

import inspect
import math

import numpy as np

from .linear import lateral_ring_modes
from .linear import modes as _modes
from .model import _D_TREAD, _W_TREAD, CONTACT, N_TREAD, VXLOW
from .params import RigidRingParams

__all__ = ["vertical_modes", "belt_vertical_mode", "fore_aft_modes", "lateral_modes", "string_step_s63"]


def vertical_modes(d):
    """Drop-test linearization (rim z free, belt on the residual spring): [(f, zeta) bounce,
    (f, zeta) belt] of rim mass m_a on k_bz || C_bz to the belt m_b on k_vr || C_vr."""
    t = d.tire
    M = np.diag([t.m_tot_kg - t.m_b_kg, t.m_b_kg])
    K = np.array([[d.k_bz, -d.k_bz], [-d.k_bz, d.k_bz + d.k_vr]])
    C = np.array([[d.C_bz, -d.C_bz], [-d.C_bz, d.C_bz + d.C_vr]])
    f, z, _ = _modes(M, K, C)
    return list(zip(f, z))


def belt_vertical_mode(d):
    """(f, zeta) of the belt's vertical mode with the rim locked (drum-cleat): k_bz + k_vr on m_b."""
    k, c, m = d.k_bz + d.k_vr, d.C_bz + d.C_vr, d.tire.m_b_kg
    return math.sqrt(k / m) / (2 * math.pi), c / (2 * math.sqrt(k * m))


def fore_aft_modes(d, speed, k_bx=None, C_bx=None, C_btheta=None, contact=CONTACT):
    """Drum-cleat linearization of the fore-aft / wind-up motion (rim x, z locked, rim spin free,
    rolling at `speed`): belt x_b, theta_b, rim theta_a and the tread's longitudinal slip states, as
    `model.RigidRing` with that contact: "string" (the brush's N_TREAD nodes through the patch) or
    "lag" (a du/dt + V u = -a (x_b' - r_e theta_b'), F_x = k_cx u), each with the low-speed damper
    below VXLOW. Returns [(f, zeta, x_b share of the mode's kinetic energy)]; k_bx, C_bx, C_btheta
    override."""
    t = d.tire
    kbx = d.k_bx if k_bx is None else k_bx
    cbx = d.C_bx if C_bx is None else C_bx
    cbt = d.C_btheta if C_btheta is None else C_btheta
    kbt, a, re, rb = d.k_btheta, d.a, d.r_e, d.r_b
    kcx = d.k_k / a
    damp_vlow = inspect.signature(RigidRingParams.from_derived).parameters["damp_vlow"].default
    cv = damp_vlow * kcx * max(0.0, 1.0 - abs(speed) / VXLOW)  # the low-speed tread damper, as the model
    m, Ib, Ia = t.m_b_kg, t.I_by_kgm2, t.I_ay_kgm2
    # state [x_b, th_b, th_a, x_b', th_b', th_a', slip states]; each slip state's rate carries
    # -(x_b' - r_e th_b') (the belt's slip velocity) plus its own transport or relaxation
    ns = N_TREAD if contact == "string" else 1
    n = 6 + ns
    A = np.zeros((n, n))
    A[0, 3] = A[1, 4] = A[2, 5] = 1.0
    drive = np.zeros(n)
    drive[3], drive[4] = -1.0, re
    if contact == "string":
        L = 2.0 * a
        rel = -abs(speed) * _D_TREAD[1:, 1:] / L  # the leading edge (node 0) stays undeflected
        A[6:] = drive
        A[6:, 6:] = rel
        w = _W_TREAD[1:]
        fx = np.zeros(n)
        fx[6:] = d.k_k / (2.0 * a * a) * L * w
        fx += cv * (w @ A[6:])
    else:
        A[6] = drive
        A[6, 6] = -abs(speed) / a
        fx = kcx * np.eye(n)[6] + cv * A[6]  # F_x as a row over the state
    A[3] = (-kbx * np.eye(n)[0] - cbx * np.eye(n)[3] + fx) / m
    msth = -kbt * (np.eye(n)[1] - np.eye(n)[2]) - cbt * (np.eye(n)[4] - np.eye(n)[5])
    A[4] = (msth - rb * fx) / Ib
    A[5] = -msth / Ia
    lam, vec = np.linalg.eig(A)
    out = []
    for i in np.flatnonzero(lam.imag > 1e-9):
        v = vec[:, i]
        ke = np.array([m * abs(v[3]) ** 2, Ib * abs(v[4]) ** 2, Ia * abs(v[5]) ** 2])
        out.append((abs(lam[i]) / (2 * math.pi), -lam[i].real / abs(lam[i]), float(ke[0] / ke.sum())))
    return sorted(out)


def lateral_modes(d, variant):
    """Lateral release linearization (standing, rim y free, camber held, patch stuck).
    "reduced": m_tot on k_l || C_l. "ring": rim m_a on the sidewall (k_by, C_by) to the belt m_b,
    I_bx (camber k_bgamma, C_bgamma) standing on the tread k_cy || C_cy at the lever arm r_b, with the
    sidewall's Maxwell branches where d has them (`Derived.lateral_branch`). Returns [(f, zeta)]."""
    t = d.tire
    if variant == "reduced":
        return [(math.sqrt(d.k_l / t.m_tot_kg) / (2 * math.pi), d.C_l / (2 * math.sqrt(d.k_l * t.m_tot_kg)))]
    f, z = lateral_ring_modes(t, d.r_b, d.k_by, d.k_cy, d.k_bgamma, d.C_by, d.C_cy, d.C_bgamma, d.lateral_branch)
    return list(zip(f, z))


def string_step_s63(sigma_total, a, n=2400):
    """Distance to 63 % of the steady side force after a slip-angle step for a stretched string
    with a contact patch of half length a (no sliding, no inertia; Pacejka's string model): the
    leading contact point obeys dv1/ds + v1 / sigma_s = alpha with sigma_s = sigma_total - a, the
    contact points keep their ground positions, the free string on either side adds sigma_s times
    its end deflection. Steady: F = 2 c (sigma_s + a)^2 alpha, standing stiffness 2 c (sigma_s + a):
    their ratio is sigma_total (= k_f / k_l). None when sigma_total <= a."""
    ss_ = sigma_total - a
    if not (ss_ > 0 and a > 0):
        return None
    s = np.linspace(0.0, 8.0 * sigma_total, n)[:, None]
    x = np.linspace(-a, a, 401)[None, :]
    laid = s - (a - x)  # where the contact point at x was laid down (the step at s = 0)
    v1 = np.where(laid > 0, ss_ * (1 - np.exp(-np.clip(laid, 0, None) / ss_)), 0.0)
    v = v1 + (s - np.maximum(laid, 0.0))
    lead = ss_ * (1 - np.exp(-s[:, 0] / ss_))
    F = np.trapezoid(v, x[0], axis=1) + ss_ * (lead + v[:, 0])
    frac = F / (2 * sigma_total**2)
    i = int(np.argmax(frac >= 0.632))
    return float(np.interp(0.632, frac[i - 1:i + 1], s[i - 1:i + 1, 0]))
