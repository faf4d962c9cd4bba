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
