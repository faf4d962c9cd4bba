"""Search-region management for sequential response-surface optimization.

Two rules move a box region (lower, upper) inside the global design box:

- ARSM (Wang, Dong & Aitchison 2001): the threshold is the second-best value seen; the new
  region is the bounding box of the part of the current region where the surrogate is at or
  below the threshold. Here that part is estimated by dense Sobol sampling of the surrogate.
- SRSM pan-and-zoom (Stander & Craig 2002): the region moves its centre to the new optimum
  (pan) and shrinks by a factor that depends on how far the optimum moved and whether it
  oscillates (zoom).

Safeguards on the ARSM rule (ours, each for a failure seen on test functions): the best point
is kept inside; every width stays >= `min_width`; one update never shrinks a width below
`min_shrink` times its old value (one bad surrogate cannot collapse the region); after a
proposal that failed to improve, the region zooms on the best point instead of trusting the
surface's sub-level set; and when the best point sits on an inner face of the region, the region
pans across that face and grows (plain ARSM only shrinks, so it could never follow a valley out
of an early region). Points that stay inside a shrunk region are inherited (Wang 2003), which
saves evaluations. All coordinates here are unit coordinates (the global box is [0, 1]^d by
default).
"""

import dataclasses

import numpy as np

from ..errors import ConfigError
from .doe import sobol

__all__ = ["Region", "second_best", "inherit", "arsm_update", "srsm_update", "safeguard"]


@dataclasses.dataclass(frozen=True)
class Region:
    """A box search region. lower, upper: (d,). move: (d,) last normalized pan (SRSM) or None."""

    lower: np.ndarray
    upper: np.ndarray
    move: np.ndarray | None = None

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower

    @property
    def centre(self) -> np.ndarray:
        return 0.5 * (self.lower + self.upper)

    @classmethod
    def unit(cls, d: int) -> "Region":
        return cls(np.zeros(int(d)), np.ones(int(d)))


def second_best(f) -> float:
    """The ARSM threshold: the second-smallest finite value in f (the smallest if only one)."""
    v = np.sort(np.asarray(f, dtype=float)[np.isfinite(f)])
    if v.size == 0:
        raise ConfigError("second_best: no finite function values")
    return float(v[1] if v.size > 1 else v[0])


def inherit(x, region: Region, rtol: float = 1e-12) -> np.ndarray:
    """Boolean mask (n,) of the points x (n, d) inside the region (Wang 2003 inheritance)."""
    x = np.atleast_2d(np.asarray(x, dtype=float))
    tol = rtol * np.maximum(region.width, 1.0)
    return np.all((x >= region.lower - tol) & (x <= region.upper + tol), axis=1)


def _fit_box(lo, hi, width, inside_lo, inside_hi):
    """Grow [lo, hi] symmetrically to `width` per axis, then shift it inside the box
    [inside_lo, inside_hi]."""
    c = 0.5 * (lo + hi)
    half = 0.5 * np.maximum(hi - lo, width)
    half = np.minimum(half, 0.5 * (inside_hi - inside_lo))
    c = np.clip(c, inside_lo + half, inside_hi - half)
    return c - half, c + half


def safeguard(lower, upper, best_x, old: Region, min_width, min_shrink, glo, ghi):
    """Apply the safeguards to a proposed box; returns (lower, upper).

    The box is stretched to contain best_x, then widened (about its centre, then shifted
    back inside the global box [glo, ghi]) so each width >= max(min_width, min_shrink * old
    width). The widening can only pull best_x further inside, never out.
    """
    lo = np.minimum(np.asarray(lower, float), best_x)
    hi = np.maximum(np.asarray(upper, float), best_x)
    need = np.maximum(min_width, min_shrink * old.width)
    lo, hi = _fit_box(lo, hi, need, glo, ghi)
    # shifting to respect the global box may leave best_x just outside by round-off
    return np.minimum(lo, best_x), np.maximum(hi, best_x)


def _check(min_width, min_shrink):
    if not 0.0 < min_width <= 1.0:
        raise ConfigError(f"min_width = {min_width}: must be in (0, 1] (unit coordinates)")
    if not 0.0 <= min_shrink <= 1.0:
        raise ConfigError(f"min_shrink = {min_shrink}: must be in [0, 1]")


def _pan_from_faces(lo, hi, best_x, old: Region, glo, ghi, grow, rel=1e-2):
    """Where best_x sits on a face of the old region that is not a face of the global box, the
    optimum may lie beyond that face, which a rule that only shrinks could never reach: along
    those axes, centre the box on best_x with `grow` times the OLD width (a pan, as in SRSM; the
    growth lets the region travel along a long valley as a trust region does after a step cut
    short by its boundary), inside the global box."""
    near_lo = (best_x - old.lower <= rel * old.width) & (old.lower > glo)
    near_hi = (old.upper - best_x <= rel * old.width) & (old.upper < ghi)
    pan = near_lo | near_hi
    half = np.where(pan, np.minimum(0.5 * grow * old.width, 0.5 * (ghi - glo)), 0.5 * (hi - lo))
    c = np.clip(best_x, glo + half, ghi - half)
    return np.where(pan, c - half, lo), np.where(pan, c + half, hi), pan


def arsm_update(
    region: Region,
    surface,
    threshold: float,
    best_x,
    seed: int,
    min_width: float = 1e-3,
    min_shrink: float = 0.5,
    n_samples: int = 4096,
    glo=None,
    ghi=None,
    zoom: bool = False,
    pan_growth: float = 2.0,
) -> Region:
    """ARSM region: bounding box of {x in region : surface(x) <= threshold}, safeguarded.

    surface: anything with predict(x (m, d)) -> (m,) in unit coordinates.
    threshold: the cut-off, normally `second_best` of the values seen.
    best_x: (d,) best point seen; it stays inside.
    glo, ghi: (d,) global box (default [0, 1]^d).
    The sampled sub-level set underestimates the true one by up to one sample spacing, so the
    box is padded by that spacing (width * n_samples^(-1/d)) before the safeguards. The new
    region stays inside the current one (ARSM reduces), except along axes where the best point
    sits on a face of the current region inside the global box: there it pans (`_pan_from_faces`).
    zoom: the surface's last proposal failed to improve on the best point, so its sub-level
    set is not to be trusted: no width may then exceed min_shrink times its old value, and the
    capped axes are centred on best_x (the data are trusted over the surface).
    pan_growth: width factor of a pan (>= 1).
    """
    _check(min_width, min_shrink)
    best_x = np.asarray(best_x, dtype=float)
    d = best_x.size
    glo = np.zeros(d) if glo is None else np.asarray(glo, float)
    ghi = np.ones(d) if ghi is None else np.asarray(ghi, float)
    cand = region.lower + sobol(n_samples, d, seed) * region.width
    below = cand[surface.predict(cand) <= threshold]
    if below.shape[0] == 0:
        lo = hi = best_x  # the surface sits above the threshold everywhere: zoom on the best
    else:
        pad = region.width * n_samples ** (-1.0 / d)
        lo = np.maximum(below.min(axis=0) - pad, region.lower)
        hi = np.minimum(below.max(axis=0) + pad, region.upper)
    if zoom:
        cap = min_shrink * region.width
        zlo, zhi = _fit_box(best_x - 0.5 * cap, best_x + 0.5 * cap, cap, region.lower, region.upper)
        wide = (hi - lo) > cap
        lo, hi = np.where(wide, zlo, lo), np.where(wide, zhi, hi)
    lo, hi = safeguard(lo, hi, best_x, region, min_width, min_shrink, region.lower, region.upper)
    plo, phi, _ = _pan_from_faces(lo, hi, best_x, region, glo, ghi, pan_growth)
    return Region(plo, phi, None)


def srsm_update(
    region: Region,
    new_centre,
    glo=None,
    ghi=None,
    eta: float = 0.6,
    gamma_pan: float = 1.0,
    gamma_osc: float = 0.6,
    min_width: float = 1e-3,
) -> Region:
    """Successive response surface pan-and-zoom (Stander & Craig 2002).

    d_i = 2 (x_new - x_centre) / range is the normalized move; c_i = d_i d_i(previous) tells
    panning (c > 0) from oscillation (c < 0); gamma = (gamma_pan (1 + c^) + gamma_osc (1 - c^)) / 2
    with c^ = sign(c) sqrt|c|; the contraction is lambda_i = eta + |d_i| (gamma - eta), so a
    region zooms by eta when the optimum stays at its centre and pans at full size when the
    optimum sits on its edge moving the same way twice. The new box is centred on new_centre and
    shifted inside the global box [glo, ghi] (default [0, 1]^d).
    """
    _check(min_width, 0.0)
    x = np.asarray(new_centre, dtype=float)
    glo = np.zeros_like(x) if glo is None else np.asarray(glo, float)
    ghi = np.ones_like(x) if ghi is None else np.asarray(ghi, float)
    move = np.clip(2.0 * (x - region.centre) / region.width, -1.0, 1.0)
    c = np.zeros_like(move) if region.move is None else move * region.move
    c_hat = np.sign(c) * np.sqrt(np.abs(c))
    gamma = 0.5 * (gamma_pan * (1.0 + c_hat) + gamma_osc * (1.0 - c_hat))
    lam = eta + np.abs(move) * (gamma - eta)
    half = 0.5 * np.maximum(lam * region.width, min_width)
    lo, hi = _fit_box(x - half, x + half, 2 * half, glo, ghi)
    return Region(np.minimum(lo, x), np.maximum(hi, x), move)
