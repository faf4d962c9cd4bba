"""Effective road of a tire rolling over a round cleat: the tandem elliptical cam (Schmeitz 2004, the
enveloping model of MF-Swift), and its fit to a quasi-static cleat crossing.

A cam is the lower half of a super-ellipse (|xi / a_e|^c_e + |z / b_e|^c_e = 1) that slides over the
road profile without penetrating it; w_c(X) is the height of its lowest point when its centre stands
at X. Two cams l_s apart (front at s + l_s/2, rear at s - l_s/2) give the effective road under a
contact point at s: height w = (w_f + w_r) / 2 and forward slope dw/dx = (w_f - w_r) / l_s.

s is the contact point's position relative to the cleat's crest along the road (m; < 0 while the
cleat lies ahead). The cleat is a cylinder of radius r standing h above a flat road. The drum's own
curvature is left out: the effective road is what the cleat adds to the surface under the tire.

`fit` identifies (l_s, a_e, b_e, c_e) from the shell model's quasi-static crossing (E03, method
"static": the rim under the constant load, frictionless, the cleat stepped through the patch): the
rim's lift is the effective height and -F_x / F_z the effective slope, each point of which the
tandem must reproduce.
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from .physics.drum import cleat_half_chord

N_CHORD = 201  # points across the cleat's chord where each cam's contact is looked for
NAMES = ("l_s", "a_e", "b_e", "c_e")
SLOPE_WEIGHT = 0.1  # of the slope's residuals against the height's (see `fit`)


def cleat_height(x, r, h, xp=jnp):
    """Height (m) of a cylinder of radius r standing h above the road, at x from its crest (0 outside).
    xp: the array module (jax.numpy, traced; numpy for the host's fit)."""
    half = xp.sqrt(xp.clip(r**2 - (r - h) ** 2, 0.0, None))
    return xp.where(xp.abs(x) < half, xp.sqrt(xp.clip(r**2 - x**2, 0.0, None)) - (r - h), 0.0)


def cam_height(X, a_e, b_e, c_e, r, h, xp=jnp):
    """Height (m) of the lowest point of a cam centred at X over the cleat (0 on the flat road); X
    a scalar, or a column (n, 1) for n positions at once."""
    half = xp.sqrt(xp.clip(r**2 - (r - h) ** 2, 0.0, None))
    x = xp.linspace(-1.0, 1.0, N_CHORD) * half
    xi = xp.abs(x - X) / a_e
    inside = xi < 1.0
    rise = b_e * (1.0 - xp.clip(1.0 - xp.where(inside, xi, 0.0) ** c_e, 1e-30, None) ** (1.0 / c_e))
    lift = xp.where(inside, cleat_height(x, r, h, xp) - rise, 0.0)
    return xp.maximum(xp.max(lift, axis=-1), 0.0)


def effective(s, l_s, a_e, b_e, c_e, r, h, xp=jnp):
    """(w, dw/dx) of the tandem under a contact point at s (module docstring)."""
    wf = cam_height(s + 0.5 * l_s, a_e, b_e, c_e, r, h, xp)
    wr = cam_height(s - 0.5 * l_s, a_e, b_e, c_e, r, h, xp)
    return 0.5 * (wf + wr), (wf - wr) / l_s


def effective_many(s, l_s, a_e, b_e, c_e, r, h):
    """(w, dw/dx) at every contact point of s (n,), in numpy: the fit calls it thousands of times on
    the host, and a JAX call there would queue behind the simulation holding the default device."""
    return effective(np.asarray(s, float)[:, None], l_s, a_e, b_e, c_e, r, h, np)


def effective_with_rate(s, l_s, a_e, b_e, c_e, r, h):
    """(w, slope, dw/ds) at s: dw/ds (the height's rate along the road) by forward differentiation."""
    (w, slope), (dw, _) = jax.jvp(lambda x: effective(x, l_s, a_e, b_e, c_e, r, h), (s,), (jnp.ones_like(s),))
    return w, slope, dw


def reach(l_s, a_e, r, h):
    """Distance (m) from the cleat's crest beyond which the tandem does not touch it."""
    return cleat_half_chord(r, h) + 0.5 * l_s + a_e


@dataclasses.dataclass(frozen=True)
class EnvelopingFit:
    l_s: float  # distance between the cams (m)
    a_e: float  # cam half length (m)
    b_e: float  # cam half height (m)
    c_e: float  # cam exponent
    rms_height_m: float  # rms of w(model) - w(shell) over the crossing
    rms_slope: float  # rms of the slope's misfit
    max_height_m: float  # largest effective height the shell showed
    on_bound: tuple  # names of the parameters that ended on a bound

    def as_dict(self) -> dict:
        return dataclasses.asdict(self) | {"on_bound": list(self.on_bound)}


def fit(s, w, slope, r, h, a, R0) -> EnvelopingFit:
    """Least-squares tandem cam to a quasi-static crossing: s (n,) contact positions relative to the
    crest (m), w (n,) effective heights (m), slope (n,) effective slopes; r, h the cleat; a the
    contact half length and R0 the tire's radius (m), which scale the bounds and the start. The
    height is what is fitted (residuals scaled by the cleat's height); the slope (scaled by its
    largest |value|) enters at SLOPE_WEIGHT, enough to settle what the height leaves free.
    Weighing both alike, the tandem cannot follow the shell's crossing: it gives up its peak
    (docs/rigid-ring.md, "Enveloping")."""
    import scipy.optimize

    s, w, slope = (np.asarray(v, float) for v in (s, w, slope))
    sw = max(float(h), 1e-6)
    ss = max(float(np.max(np.abs(slope))), 1e-3)
    lo = np.array([0.05 * a, 0.02 * R0, 1.05 * h, 1.0])
    hi = np.array([4.0 * a, 2.0 * R0, 2.0 * R0, 8.0])
    starts = [np.clip(np.array(x), lo, hi) for x in ([1.6 * a, 0.5 * R0, 0.5 * R0, 2.0], [0.8 * a, 1.5 * R0, 1.5 * R0, 1.5],
                                                       [1.2 * a, 2.0 * R0, 1.5 * R0, 1.5])]

    def resid(x):
        we, se = effective_many(s, *x, r, h)
        return np.concatenate([(np.asarray(we) - w) / sw, SLOPE_WEIGHT * (np.asarray(se) - slope) / ss])

    best = None
    for start in starts:
        res = scipy.optimize.least_squares(resid, start, bounds=(lo, hi), method="trf", x_scale="jac", diff_step=1e-4,
                                           max_nfev=400)
        if best is None or res.cost < best.cost:
            best = res
    x = best.x
    we, se = (np.asarray(v) for v in effective_many(s, *x, r, h))
    span = hi - lo
    bound = tuple(n for n, v, a_, b_, d in zip(NAMES, x, lo, hi, span) if v - a_ < 1e-3 * d or b_ - v < 1e-3 * d)
    return EnvelopingFit(*(float(v) for v in x), rms_height_m=float(np.sqrt(np.mean((we - w) ** 2))),
                         rms_slope=float(np.sqrt(np.mean((se - slope) ** 2))), max_height_m=float(np.max(w)),
                         on_bound=bound)
