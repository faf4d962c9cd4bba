"""Sensitivities: d(quantity)/d(ln parameter), as a table, a heat map and singular values.

The simulator's Jacobian J = dq/dtheta (theta = ln parameter; a linearly searched one, theta = p,
has its column multiplied by p, so that it too is dq/d ln p) at one point is reported as is
(units of the quantity per unit relative change of the parameter) and as elasticities
E = J / q = d ln q / d ln p (dimensionless: +1 means "1 % more parameter, 1 % more quantity").

Identifiability: the singular values s_1 >= ... of the targets' elasticity matrix (m x d, rows
weighted as in the objective) say how many directions in parameter space the targets can see.
There are at most m = 4 (four numbers cannot fix more); a direction with s_k / s_1 below
`rel_tol` moves the targets by less than that fraction of the best-seen direction and counts as
unidentified. The right singular vectors name the parameter combinations.
"""

from pathlib import Path

import numpy as np

from ...io import atomic_savefig, atomic_write_csv, atomic_write_json

__all__ = ["Sensitivity", "compute", "identifiability", "write_sensitivity", "plot_heatmap"]


class Sensitivity:
    """values (q,), jacobian (q, d) = dq/dtheta, elasticity (q, d), at theta (d,)."""

    def __init__(self, names, quantities, theta, values, jacobian):
        self.names, self.quantities = tuple(names), tuple(quantities)
        self.theta = np.asarray(theta, float)
        self.values = np.asarray(values, float)
        self.jacobian = np.asarray(jacobian, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.elasticity = self.jacobian / self.values[:, None]


def compute(sim, theta, quantities=None) -> Sensitivity:
    """Ask the simulator for values and Jacobian of `quantities` (default: its responses)."""
    q = tuple(sim.response_names if quantities is None else quantities)
    theta = np.asarray(theta, float)
    vals, jac = sim.jacobian(theta, None if q == tuple(sim.response_names) else q)
    jac = np.array(jac, float)
    for j in range(sim.space.d):  # a linear parameter (theta = p): dq/dp p = dq/d ln p
        if getattr(sim.space, "is_linear", lambda _: False)(j):
            jac[:, j] *= theta[j]
    return Sensitivity(sim.space.names, q, theta, vals, jac)


def identifiability(elasticity, weights=None, rel_tol: float = 1e-2) -> dict:
    """Singular values of the (weighted) target elasticities (m, d) and what they imply.

    Returns {"singular_values": (k,), "relative": s / s_1, "n_identified": count with
    s_k / s_1 >= rel_tol, "directions": (k, d) right singular vectors, "rel_tol"}.
    """
    e = np.asarray(elasticity, float)
    if weights is not None:
        e = np.sqrt(np.asarray(weights, float))[:, None] * e
    _, s, vt = np.linalg.svd(e, full_matrices=False)
    rel = s / s[0] if s.size and s[0] > 0 else np.zeros_like(s)
    return {"singular_values": s, "relative": rel, "n_identified": int(np.sum(rel >= rel_tol)),
            "directions": vt, "rel_tol": rel_tol}


def plot_heatmap(sens: Sensitivity, path, title: str = "") -> Path:
    """Heat map of the elasticities d ln q / d ln p (quantities x parameters)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    e = sens.elasticity
    q, d = e.shape
    lim = float(np.nanmax(np.abs(e))) or 1.0
    fig, ax = plt.subplots(figsize=(max(6.0, 0.45 * d + 2.5), max(2.5, 0.45 * q + 1.8)))
    im = ax.imshow(e, cmap="RdBu_r", vmin=-lim, vmax=lim, aspect="auto")
    for i in range(q):
        for j in range(d):
            if abs(e[i, j]) >= 0.005 * lim:
                ax.text(j, i, f"{e[i, j]:.2f}", ha="center", va="center", fontsize=6)
    ax.set_xticks(range(d), [n.replace("parts.", "") for n in sens.names], rotation=70,
                  ha="right", fontsize=7)
    ax.set_yticks(range(q), sens.quantities, fontsize=8)
    fig.colorbar(im, ax=ax, label="d ln(quantity) / d ln(parameter)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return atomic_savefig(fig, path, dpi=120)


def write_sensitivity(sens: Sensitivity, out_dir, ident: dict | None = None, title: str = "") -> dict:
    """sensitivity.csv (long table), sensitivity.json, sensitivity.png in out_dir."""
    out_dir = Path(out_dir)
    rows = [[q, n, float(v), float(sens.jacobian[i, j]), float(sens.elasticity[i, j])]
            for i, (q, v) in enumerate(zip(sens.quantities, sens.values))
            for j, n in enumerate(sens.names)]
    paths = {"csv": atomic_write_csv(out_dir / "sensitivity.csv",
                                     ["quantity", "parameter", "value_SI", "dq_dlnp_SI",
                                      "elasticity"], rows)}
    doc = {"theta": sens.theta, "parameters": list(sens.names), "quantities": list(sens.quantities),
           "values": sens.values, "jacobian": sens.jacobian, "elasticity": sens.elasticity}
    if ident is not None:
        doc["identifiability"] = {k: v for k, v in ident.items()}
    paths["json"] = atomic_write_json(out_dir / "sensitivity.json", doc)
    paths["figure"] = plot_heatmap(sens, out_dir / "sensitivity.png", title)
    return paths
