"""Why the populated rigid ring and the shell model disagree (docs/rigid-ring.md §8): one markdown
bullet per FAILed comparison row, naming the cause with the numbers that show it, or saying plainly
that the cause was not established.

`diagnose(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None, ring_signals=None)` gives the bullets,
`explain(...)` (same arguments) the Diagnosis records behind them (metric, state, text). Both work from
  * the comparison rows (`validation.compare`: the shell's and the ring's value of every metric),
  * the condition's table row and what `params.derive` makes of it, put through the ring's own
    linearized equations (`modes`: numpy, the same equations as `model.RigidRing`, no simulation),
  * optionally the characterization folder `char_dir` (the shell's case folders: the E02
    load-deflection curve, the E04 drop record's reductions, the E03 spindle F_x record, the E10
    measurement window, the validation's steady references) and the shell's validation signals
    (`shell_signals`, as `validate.validate` returns them: the slip-step F_y against distance).
Every number in a bullet is computed from those inputs. A cause counts as established (FULL) when
the mechanism named, put into numbers, accounts for the disagreement within the metric's own
tolerance; PARTIAL when it closes more than half of it (the bullet then says the rest is not
established); otherwise (NONE) the bullet starts "cause not established" and gives what was checked.

Causes the checks look for (each found on the default mesh; see the module's tests for the cases):
  * drop bounce frequency and peak F_z: the load-deflection curve stiffens (tangent stiffness at
    the load above the secant k_sv the linear ring uses);
  * damping ratios: the damping value the table chose (two-peak or fit) against the one the shell's
    metric is (the fit), the ring's frequency entering zeta = C / (2 m omega), and the single time
    constant tau = C_tot / k_sv of §3 that makes the ring's belt damping grow with frequency;
  * drum fore-aft mode: k_bx (E13's, or the isotropy assumption k_bx = k_bz without E13);
  * drum peak-to-peak forces: the quasi-static swing the cam gives (k_vt w_max; 2 F_z slope_max)
    against the shell's and the ring's at speed;
  * lateral release: the reduced lateral model (m_tot on k_l) against the belt's own DOFs;
  * slip step: speed dependence of the shell, the step's transient against the shell's own steady
    solve at its speed (the validation's steady references), the E10 window not yet steady, the linear k_m against
    the curved M_z(alpha), and a first-order lag over sigma = k_f / k_l against a contact patch of
    finite length (stretched string: sigma_string = sigma - a).
"""

import dataclasses

import numpy as np

from .diagnosis_base import FULL, NONE, PARTIAL, _Context, _p  # noqa: F401  (FULL, PARTIAL: the states)
from .diagnosis_drop import (
    _belt_mode,
    _drop_bounce_f,
    _drop_peak,
    _drop_static,
    _drop_zeta,
)
from .diagnosis_drum import (
    _drum_fore_aft_f,
    _drum_fore_aft_zeta,
    _drum_peak_to_peak,
    _drum_vertical_f,
    _drum_vertical_zeta,
)
from .diagnosis_lateral import _lateral_f, _lateral_zeta, _step_force, _step_s63
from .modes import (  # noqa: F401
    belt_vertical_mode,
    fore_aft_modes,
    lateral_modes,
    string_step_s63,
    vertical_modes,
)
from .params import derive

CHECKS = {
    "drop.static_deflection_m": _drop_static,
    "drop.bounce_f_Hz": _drop_bounce_f,
    "drop.bounce_zeta": _drop_zeta,
    "drop.peak_F_z_N": _drop_peak,
    "drop.belt_mode_Hz": _belt_mode,
    "drum.vertical_mode_Hz": _drum_vertical_f,
    "drum.vertical_mode_zeta": _drum_vertical_zeta,
    "drum.fore_aft_mode_Hz": _drum_fore_aft_f,
    "drum.fore_aft_mode_zeta": _drum_fore_aft_zeta,
    "drum.F_z_peak_to_peak_N": lambda cx, c: _drum_peak_to_peak(cx, c, "z"),
    "drum.F_x_peak_to_peak_N": lambda cx, c: _drum_peak_to_peak(cx, c, "x"),
    "lateral.f_Hz": _lateral_f,
    "lateral.zeta": _lateral_zeta,
}


def _check_for(metric):
    if metric in CHECKS:
        return CHECKS[metric]
    if metric.startswith("step_"):
        tail = metric.split(".", 1)[1]
        if tail == "F_y_steady_N":
            return lambda cx, c: _step_force(cx, c, "F_y")
        if tail == "M_z_steady_Nm":
            return lambda cx, c: _step_force(cx, c, "M_z")
        if tail == "s63_m":
            return _step_s63
    return None


@dataclasses.dataclass(frozen=True)
class Diagnosis:
    metric: str
    rel_diff: float | None  # ring / shell - 1
    state: str  # FULL, PARTIAL or NONE (cause not established)
    text: str

    def bullet(self) -> str:
        rel = "" if self.rel_diff is None else f" {_p(self.rel_diff)}"
        text = self.text if self.state != NONE else "cause not established: " + self.text
        return f"- {self.metric}{rel}: {text}"


def explain(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None, ring_signals=None) -> list:
    """A Diagnosis for every FAIL row of `rows` (validation.compare's Comparison list), in their
    order, at the condition (load_N, pressure_Pa) of the characterization `char` (table.
    read_characterization). char_dir: the characterization folder, whose case folders add the
    shell's own records (None: the table alone). shell_signals: the shell's validation signals
    ({"step_5": (distance, F_y SAE), ...}, as validate.validate returns them), optional; ring_signals:
    the ring's (validation.ring_signals), optional."""
    fails = [c for c in rows if c.verdict == "FAIL"]
    if not fails:
        return []
    row = char.row(load_N, pressure_Pa)
    if row is None:
        return [Diagnosis(c.metric, c.rel_diff, NONE, "no table row at this condition") for c in fails]
    cx = _Context(char, row, derive(row, char.tire), {c.metric: c for c in rows}, char_dir, shell_signals or {},
                  load_N, pressure_Pa, ring_signals=ring_signals or {})
    out = []
    for c in fails:
        check = _check_for(c.metric)
        if check is None:
            state, text = NONE, "no diagnosis is implemented for this metric"
        else:
            try:
                state, text = check(cx, c)
            except (TypeError, ValueError, ZeroDivisionError, KeyError, AttributeError, IndexError, OSError,
                    np.linalg.LinAlgError) as e:  # a missing or malformed input: say so, never stop the report
                state, text = NONE, f"the check could not run ({type(e).__name__}: {e})"
        out.append(Diagnosis(c.metric, c.rel_diff, state, text))
    return out


def diagnose(char, load_N, pressure_Pa, rows, char_dir=None, shell_signals=None, ring_signals=None) -> list:
    """One markdown bullet per FAIL row (see explain): "- metric +x %: cause, with its numbers", or
    "- metric +x %: cause not established: what was checked, with its numbers"."""
    return [d.bullet() for d in explain(char, load_N, pressure_Pa, rows, char_dir, shell_signals, ring_signals)]
