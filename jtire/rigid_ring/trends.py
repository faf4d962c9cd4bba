"""Trend verdicts on a characterization: does each quantity move the way physics says it should?

Each check looks along one axis (pressure at every fixed load, or load at every fixed pressure) and
asks for a strict rise (or fall) between every pair of neighbouring conditions. Verdict "pass" when
every sequence of >= 2 values moves that way, "FAIL" when any step does not (the numbers are
given, never hidden), "not tested" when no sequence has two values. The E10 symmetry check
F_y(-a) = -F_y(a) needs curves with negative angles (else "not tested"); it passes when
max |F_y(a) + F_y(-a)| over the mirrored pairs is within SYMMETRY_TOL of the curve's peak |F_y|.
"""

import dataclasses

import numpy as np

from .. import units as U
from .table import Characterization

SYMMETRY_TOL = 0.02  # fraction of peak |F_y|: a few per cent covers the shell model's steady-state noise

# (quantity key, label, direction +1 rise / -1 fall, along "pressure" or "load")
CHECKS = (
    ("k_sv_N_per_m", "k_sv rises with pressure", +1, "pressure"),
    ("k_dv_N_per_m", "k_dv rises with pressure", +1, "pressure"),
    ("first_mode_Hz", "f (E03) rises with pressure", +1, "pressure"),
    ("k_btheta_Nm_per_rad", "k_btheta rises with pressure", +1, "pressure"),
    ("k_by_N_per_m", "k_by rises with pressure", +1, "pressure"),
    ("k_bgamma_Nm_per_rad", "k_bgamma rises with pressure", +1, "pressure"),
    ("k_l_N_per_m", "k_l rises with pressure", +1, "pressure"),
    ("contact_length_m", "footprint length falls with pressure", -1, "pressure"),
    ("contact_length_m", "footprint length rises with load", +1, "load"),
    ("k_f_N_per_rad", "k_f rises with load", +1, "load"),
    ("sigma_m", "sigma rises with load", +1, "load"),
    ("rolling_resistance_N", "rolling resistance (E12) rises with load", +1, "load"),
)


@dataclasses.dataclass(frozen=True)
class Verdict:
    check: str
    verdict: str  # "pass", "FAIL", "not tested"
    numbers: str  # the sequences the verdict rests on
    failures: tuple  # human-readable failing steps


def _sequences(char: Characterization, key: str, along: str) -> list:
    """[(fixed value label, [(x, value), ...] sorted by x)] with missing values dropped."""
    fixed = char.loads() if along == "pressure" else char.pressures()
    out = []
    for f in fixed:
        pts = []
        for r in char.rows:
            same = np.isclose(r.load_N if along == "pressure" else r.pressure_Pa, f, rtol=1e-9)
            v = r.get(key)
            if same and v is not None:
                pts.append((r.pressure_Pa if along == "pressure" else r.load_N, v))
        label = f"{f / U.G0:.1f} kg" if along == "pressure" else f"{f / U.PSI:.0f} psi"
        out.append((label, sorted(pts)))
    return out


def _xlabel(x, along):
    return f"{x / U.PSI:.0f} psi" if along == "pressure" else f"{x / U.G0:.1f} kg"


def monotone(char: Characterization, key: str, label: str, direction: int, along: str) -> Verdict:
    seqs = _sequences(char, key, along)
    tested = [(lab, pts) for lab, pts in seqs if len(pts) >= 2]
    if not tested:
        return Verdict(label, "not tested", f"fewer than 2 values of {key} along {along} at any fixed condition", ())
    fails, parts = [], []
    for lab, pts in tested:
        parts.append(f"at {lab}: " + ", ".join(f"{_xlabel(x, along)} {v:.5g}" for x, v in pts))
        for (x0, v0), (x1, v1) in zip(pts, pts[1:]):
            if not direction * (v1 - v0) > 0:
                fails.append(f"at {lab}: {_xlabel(x0, along)} {v0:.5g} -> {_xlabel(x1, along)} {v1:.5g}")
    return Verdict(label, "FAIL" if fails else "pass", "; ".join(parts), tuple(fails))


def symmetry(char: Characterization, tol: float = SYMMETRY_TOL) -> Verdict:
    label = "F_y(-alpha) = -F_y(alpha) (E10)"
    parts, fails = [], []
    for r in sorted(char.rows, key=lambda r: (r.load_N, r.pressure_Pa)):
        c = r.curves
        if c is None:
            continue
        a, f = np.asarray(c.slip_angle_deg), np.asarray(c.lateral_force_N)
        pairs = [(x, i, int(np.flatnonzero(np.isclose(a, -x, atol=1e-9))[0]))
                 for i, x in enumerate(a) if x > 0 and np.any(np.isclose(a, -x, atol=1e-9))]
        if not pairs:
            continue
        peak = max(float(np.max(np.abs(f))), 1e-12)
        worst = max(abs(f[i] + f[j]) for _, i, j in pairs) / peak
        where = f"{r.load_N / U.G0:.1f} kg / {r.pressure_Pa / U.PSI:.0f} psi"
        parts.append(f"{where}: max |F_y(a) + F_y(-a)| / peak = {worst:.3g} over {len(pairs)} pairs")
        if worst > tol:
            fails.append(where)
    if not parts:
        return Verdict(label, "not tested", "no E10 curve has negative slip angles", ())
    return Verdict(label, "FAIL" if fails else "pass", "; ".join(parts) + f" (tolerance {tol:g})", tuple(fails))


def verdicts(char: Characterization) -> list:
    return [monotone(char, *c) for c in CHECKS] + [symmetry(char)]


def markdown(vs) -> str:
    lines = ["| trend | verdict | numbers |", "|---|---|---|"]
    for v in vs:
        lines.append(f"| {v.check} | {v.verdict} | {v.numbers} |")
    return "\n".join(lines) + "\n"
