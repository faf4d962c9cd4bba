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
    branch: None, or (beta, tau): each sidewall spring (k_by on y_b - y_a, k_bgamma on gamma_b) with a
    Maxwell branch of stiffness beta k and relaxation time tau in parallel (internal states q, force
    beta k (x - q), dq/dt = (x - q) / tau), as `model.RigidRing`."""
    M, K, C = lateral_ring(tire, r_b, k_by, k_cy, k_bgamma, C_by, C_cy, C_bgamma)
    if branch is None or not branch[0]:
        f, z, _ = modes(M, K, C)
        return f, z
    beta, tau = branch
    d = np.array([[-1.0, 1.0, 0.0], [0.0, 0.0, 1.0]])  # the branches' deflections from (y_a, y_b, gamma_b)
    kb = beta * np.diag([k_by, k_bgamma])
    Mi = np.linalg.inv(M)
    A = np.zeros((8, 8))
    A[:3, 3:6] = np.eye(3)
    A[3:6, :3] = -Mi @ (K + d.T @ kb @ d)
    A[3:6, 3:6] = -Mi @ C
    A[3:6, 6:] = Mi @ d.T @ kb
    A[6:, :3] = d / tau
    A[6:, 6:] = -np.eye(2) / tau
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 1e-9]
    lam = lam[np.argsort(np.abs(lam))]
    return np.abs(lam) / (2 * math.pi), -lam.real / np.abs(lam)
