"""Modes of a linear mass-spring-damper system in numpy: shared by the parameter identification
(`params`, which solves for dampers that give measured damping ratios) and `modes`."""

import math

import numpy as np


def modes(M, K, C):
    """(f_n Hz, zeta, eigenvectors (n, k) of the positions) of M q'' + C q' + K q = 0, oscillatory
    modes only, sorted by frequency."""
    n = M.shape[0]
    Mi = np.linalg.inv(M)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-Mi @ K, -Mi @ C]])
    lam, vec = np.linalg.eig(A)
    keep = lam.imag > 1e-9
    lam, vec = lam[keep], vec[:n, keep]
    order = np.argsort(np.abs(lam))
    lam, vec = lam[order], vec[:, order]
    return np.abs(lam) / (2 * math.pi), -lam.real / np.abs(lam), vec


def lateral_ring(tire, r_b, k_by, k_cy, k_bgamma, C_by, C_cy, C_bgamma):
    """(M, K, C) of the ring's lateral release (E09: rim y free, camber held, patch stuck): rim m_a on
    the sidewall (k_by, C_by) to the belt m_b, I_bx (camber k_bgamma, C_bgamma) standing on the tread
    k_cy || C_cy at the lever arm r_b. Coordinates (y_a, y_b, gamma_b)."""
    M = np.diag([tire.m_tot_kg - tire.m_b_kg, tire.m_b_kg, tire.I_bx_kgm2])

    def mat(kb, kc, kg):
        return np.array([[kb, -kb, 0.0], [-kb, kb + kc, kc * r_b], [0.0, kc * r_b, kg + kc * r_b * r_b]])

    return M, mat(k_by, k_cy, k_bgamma), mat(C_by, C_cy, C_bgamma)


def lateral_ring_modes(tire, r_b, k_by, k_cy, k_bgamma, C_by, C_cy, C_bgamma, branch=None):
    """(f_n Hz, zeta) of the ring's lateral release (`lateral_ring`), oscillatory modes by frequency.
    branch: None, or (beta, tau): each sidewall spring (k_by on y_b - y_a, k_bgamma on gamma_b) with
    Maxwell branches of stiffness beta k and relaxation time tau in parallel (internal states q, force
    beta k (x - q), dq/dt = (x - q) / tau), as `model.RigidRing`; beta, tau scalars (one branch, the
    model's) or equal-length sequences (several, for comparisons)."""
    M, K, C = lateral_ring(tire, r_b, k_by, k_cy, k_bgamma, C_by, C_cy, C_bgamma)
    betas, taus = (np.zeros(0), np.zeros(0)) if branch is None else (np.atleast_1d(x).astype(float) for x in branch)
    d = np.array([[-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # the branches' deflections from (y_a, y_b, gamma_b)
    Mi = np.linalg.inv(M)
    n = 6 + 2 * betas.size
    A = np.zeros((n, n))
    A[:3, 3:6] = np.eye(3)
    A[3:6, 3:6] = -Mi @ C
    k_tot = K.copy()
    for j, (beta, tau) in enumerate(zip(betas, taus)):
        kb = beta * np.diag([k_by, k_bgamma])
        k_tot += d.T @ kb @ d
        i = 6 + 2 * j
        A[3:6, i:i + 2] = Mi @ d.T @ kb
        A[i:i + 2, :3] = d / tau
        A[i:i + 2, i:i + 2] = -np.eye(2) / tau
    A[3:6, :3] = -Mi @ k_tot
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 1e-9]
    lam = lam[np.argsort(np.abs(lam))]
    return np.abs(lam) / (2 * math.pi), -lam.real / np.abs(lam)
