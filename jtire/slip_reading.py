"""The readings of a slip-angle step record (F_y and M_z, SAE, over the rolled distance s, s = 0 at the
step): steady F_y and M_z, the distance s63 to 63 % of the steady F_y, the overshoot, and the tail's
spread. One function for the shell's step (`experiments.slip_step`), the ring's
(`rigid_ring.scenarios.slip_step`) and the validation that compares them, so both sides are read alike.

The steady values are means over the record's last `tail_m` metres (default: its last 5 %). The
validation passes one period of the tire's lateral mode rolled at the step's speed (V / f_lateral):
both records still ring in that mode at their ends, and a mean over a whole period of it is the level
it rings about, where a window shorter than the period (the last 5 % of a 3 m record at 15 m/s is
10 ms, a seventh of a 15 Hz period) takes whatever phase the ringing ends on.
"""

import numpy as np

from .errors import ConfigError

S63 = 0.632  # the fraction of the steady F_y whose distance is the relaxation length's reading
TAIL_FRACTION = 0.05  # the default window: the last 5 % of the record


def tail_for(speed: float, f_lateral_Hz: float | None) -> float | None:
    """One period of the lateral mode rolled at `speed` (m): V / f; None without a frequency."""
    if f_lateral_Hz is None or not np.isfinite(f_lateral_Hz) or f_lateral_Hz <= 0:
        return None
    return float(speed) / float(f_lateral_Hz)


def readings(s, fy, mz, tail_m: float | None = None) -> dict:
    """{F_y_steady_SAE_N, M_z_steady_SAE_Nm, s63_m, overshoot, F_y_tail_drift_rel, steady_tail_m} of one
    step record. tail_m: the steady window at the record's end (m; None: its last 5 %); a window longer
    than half the record is refused (it would reach into the build-up). s63 is None when F_y never
    reaches 63 % of its steady value after the step."""
    s, fy, mz = (np.asarray(x, float) for x in (s, fy, mz))
    span = float(s[-1] - max(float(s[0]), 0.0))
    w = TAIL_FRACTION * span if tail_m is None else float(tail_m)
    if not 0 < w <= 0.5 * span:
        raise ConfigError(f"steady window {w:g} m: must be > 0 and at most half the {span:g} m rolled after the step")
    tail = s >= s[-1] - w
    fy_ss, mz_ss = float(fy[tail].mean()), float(mz[tail].mean())
    frac = fy / fy_ss
    hit = np.flatnonzero((frac >= S63) & (s > 0))
    s63 = None
    if hit.size and hit[0] > 0:
        i = int(hit[0])
        s63 = float(np.interp(S63, [frac[i - 1], frac[i]], [s[i - 1], s[i]]))
    return {"F_y_steady_SAE_N": fy_ss, "M_z_steady_SAE_Nm": mz_ss, "s63_m": s63,
            "overshoot": float(np.max(frac[s > 0]) - 1.0), "F_y_tail_drift_rel": float(np.ptp(fy[tail]) / abs(fy_ss)),
            "steady_tail_m": w}
