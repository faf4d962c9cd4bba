"""The slip step's readings (`jtire.slip_reading`), shared by the shell's step, the ring's and the
validation: closed forms on synthetic records."""

import math

import numpy as np
import pytest

from jtire import slip_reading, validate
from jtire.errors import ConfigError

SIGMA = 0.3  # m, relaxation length of the synthetic build-up
F_SS = -9000.0  # N, its steady F_y


def _record(distance=3.0, n=4001, ring=0.0, f_Hz=15.0, speed=15.0, decay=0.0):
    """A first-order build-up 1 - exp(-s / sigma) plus an undamped (or decaying) ringing of relative
    amplitude `ring` at f_Hz seen at `speed`; M_z the same shape at 1/30 of F_y."""
    s = np.linspace(0.0, distance, n)
    osc = ring * np.sin(2 * math.pi * f_Hz * s / speed + 0.7) * np.exp(-decay * s)
    fy = F_SS * (1 - np.exp(-s / SIGMA) + osc)
    return s, fy, -fy / 30.0


def test_first_order_build_up_reads_sigma_and_its_steady_level():
    s, fy, mz = _record()
    r = slip_reading.readings(s, fy, mz)
    # 63.2 % of the level is reached at sigma (1 - e^-1 = 0.6321); at 10 sigma the tail is settled to 5e-5,
    # and the linear interpolation between samples 0.75 mm apart is good to 1e-4 of sigma
    assert r["F_y_steady_SAE_N"] == pytest.approx(F_SS, rel=1e-4)
    assert r["M_z_steady_SAE_Nm"] == pytest.approx(-F_SS / 30, rel=1e-4)
    assert r["s63_m"] == pytest.approx(SIGMA * -math.log(1 - slip_reading.S63), rel=1e-3)
    assert r["overshoot"] == pytest.approx(0.0, abs=1e-4)
    assert r["steady_tail_m"] == pytest.approx(0.05 * 3.0)


def test_a_whole_period_of_the_ringing_reads_the_level_a_shorter_window_does_not():
    # 3 % ringing at 15 Hz, 15 m/s: a period is 1 m. The last 5 % (0.15 m) is a seventh of it
    s, fy, mz = _record(ring=0.03)
    short = slip_reading.readings(s, fy, mz)
    whole = slip_reading.readings(s, fy, mz, slip_reading.tail_for(15.0, 15.0))
    assert abs(short["F_y_steady_SAE_N"] / F_SS - 1) > 0.005  # the phase it ends on: +0.65 % here
    # over one period the sine averages out exactly; what is left is the build-up: 4e-4 over s = 2..3 m
    assert whole["F_y_steady_SAE_N"] / F_SS - 1 == pytest.approx(0.0, abs=2e-3)
    assert whole["steady_tail_m"] == pytest.approx(1.0)


def test_a_window_past_half_the_record_is_refused():
    s, fy, mz = _record(distance=1.5)
    with pytest.raises(ConfigError, match="half the 1.5 m"):
        slip_reading.readings(s, fy, mz, 1.0)
    with pytest.raises(ConfigError, match="must be > 0"):
        slip_reading.readings(s, fy, mz, 0.0)


def test_the_validations_window_is_one_lateral_period_rolled():
    assert validate.step_tail(15.0, 13.58) == pytest.approx(15.0 / 13.58)
    assert validate.step_tail(5.0, None) is None  # no E09 frequency: the last 5 %
    assert slip_reading.tail_for(5.0, float("nan")) is None
