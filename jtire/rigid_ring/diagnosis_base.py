"""What the rigid-ring diagnosis (`diagnosis`) works from: the shell's case folders, the condition's
context (its table row, what `params.derive` makes of it, the comparison rows), number formatting,
and the verdict rule every check shares (FULL / PARTIAL / NONE)."""

import dataclasses
import math

import numpy as np

from .. import results
from .params import derive

# ------------------------------------------------------------------ the shell's case folders


def _case(char_dir, experiment, load_N, pressure_Pa):
    """(result.json dict, signals {column: array} or None) of an experiment's case at a condition
    in a characterization folder, or (None, None)."""
    if char_dir is None:
        return None, None
    d = results.find_case(results.cases_dir(char_dir, experiment), load_N, pressure_Pa)
    return (None, None) if d is None else (results.read_result(d), results.read_signals(d))


@dataclasses.dataclass
class _Context:
    char: object
    row: object
    d: object
    rows: dict  # metric -> Comparison
    char_dir: object
    shell_signals: dict
    load_N: float
    pressure_Pa: float
    ring_signals: dict = dataclasses.field(default_factory=dict)
    _cache: dict = dataclasses.field(default_factory=dict)

    def case(self, experiment):
        if experiment not in self._cache:
            self._cache[experiment] = _case(self.char_dir, experiment, self.load_N, self.pressure_Pa)
        return self._cache[experiment]

    def val(self, metric, side):
        c = self.rows.get(metric)
        return None if c is None else getattr(c, side)

    def rederive(self, **q):
        """derive() of this condition's row with some quantities replaced (SI keys of the table)."""
        return derive(dataclasses.replace(self.row, q=self.row.q | q), self.char.tire)

    def load_curve(self):
        """(F (n,), deflection (n,), source) of the load-deflection curve at this pressure: the E02
        record when the case folder has it, else the table's secant k_sv over the grid's loads
        (through the origin); None with fewer than two loads."""
        res, sig = self.case("vertical_stiffness")
        if sig is not None and "load_N" in sig and "deflection_m" in sig:
            F, x = sig["load_N"], sig["deflection_m"]
            ok = np.isfinite(F) & np.isfinite(x)
            if ok.sum() >= 3:
                return F[ok], x[ok], "the E02 load-deflection record"
        pts = sorted((r.load_N, r.load_N / r.get("k_sv_N_per_m")) for r in self.char.rows
                     if math.isclose(r.pressure_Pa, self.pressure_Pa, rel_tol=1e-6) and r.get("k_sv_N_per_m"))
        if len(pts) < 2:
            return None
        F, x = (np.array([0.0] + [p[i] for p in pts]) for i in (0, 1))
        return F, x, "the table's k_sv over the grid's loads"

    def tangent_stiffness(self):
        """(k_t at the condition's load, source) from load_curve(), or None."""
        c = self.load_curve()
        if c is None:
            return None
        F, x, src = c
        kt = np.gradient(F, x)
        return float(np.interp(self.load_N, F, kt)), src


# ------------------------------------------------------------------ formatting


def _p(x):
    return f"{100 * x:+.1f} %"


def _n(x, unit="", digits=4):
    if x is None:
        return "—"
    a = abs(x)
    for f, pre in ((1e6, "M"), (1e3, "k")):
        if a >= f and unit and unit[0] in "N":
            return f"{x / f:.{digits}g} {pre}{unit}"
    return f"{x:.{digits}g}" + (f" {unit}" if unit else "")


def _within(x, y, tol):
    return x is not None and y is not None and y != 0 and abs(x / y - 1) <= tol


# ------------------------------------------------------------------ one check per metric family
# Each returns (state, text): FULL when the named mechanism, in numbers, accounts for the
# disagreement within the metric's tolerance; PARTIAL when it accounts for most of it (the text then
# says what is left unexplained); NONE when it does not (the bullet then says "cause not established").

FULL, PARTIAL, NONE = "full", "partial", "none"


def _verdict(pred, shell, ring, tol):
    """FULL if pred is within tol of shell, PARTIAL if it closes more than half the ring's gap
    (in log terms, so a factor and its inverse count alike)."""
    if _within(pred, shell, tol):
        return FULL
    if pred and shell and ring and pred / shell > 0 and ring / shell > 0 and \
            abs(math.log(pred / shell)) < 0.5 * abs(math.log(ring / shell)):
        return PARTIAL
    return NONE


def _damping(cx, c, key, key_2p, key_fit, f_metric, experiment):
    """A free-decay damping ratio: the shell's metric is its damped-sine fit, the ring carries the
    table's chosen value (the two-peak one when the decay had two clean peaks), and zeta = C/(2 m
    omega) is taken at each side's own frequency."""
    C, c2p, cfit = cx.row.get(key), cx.row.get(key_2p), cx.row.get(key_fit)
    if C is None or not cfit:
        return NONE, f"the table lacks {key_fit} to compare the damping the ring carries with the shell's fit"
    which = "two-peak" if c2p is not None and math.isclose(C, c2p, rel_tol=1e-9) else "chosen"
    f_s, f_r = cx.val(f_metric, "shell"), cx.val(f_metric, "ring")
    obs = c.ring / c.shell
    ratio_c = C / cfit
    txt = (f"the ring carries the {which} {key.split('_N')[0]} = {_n(C, 'N s/m')}, x {ratio_c:.3g} the damped-sine fit "
           f"{_n(cfit, 'N s/m')} the shell's zeta comes from")
    pred_ratio = ratio_c
    if f_s and f_r:
        pred_ratio *= f_s / f_r
        txt += (f"; and zeta = C/(2 m omega) is taken at the ring's {_n(f_r, 'Hz')}, not the shell's {_n(f_s, 'Hz')} "
                f"(x {f_s / f_r:.3g})")
    txt += f": together x {pred_ratio:.3g}, observed x {obs:.3g}"
    state = _verdict(pred_ratio, obs, 1.0, c.tolerance)
    res, _ = cx.case(experiment)
    air = (res or {}).get("checks", {}).get("airborne_after_first_contact_fraction")
    if air and which == "two-peak" and abs(ratio_c - 1) > c.tolerance:
        txt += (f". The two methods differ on the shell's own record: {100 * air:.0f} % of it after first contact is "
                f"airborne, a decay that is not that of a linear oscillator")
    if state == PARTIAL:
        txt += "; the rest is not established"
    return state, txt
