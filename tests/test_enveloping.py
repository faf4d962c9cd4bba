"""The tandem elliptical cam (jtire.enveloping) against closed forms, its fit, and the rigid ring rolling
over the cleat through it. The shell's quasi-static crossing that the cam is fitted to is tested on
the suite's E03 run (tests/test_drum_cleat.py)."""

import dataclasses
import math

import numpy as np
import pytest
import scipy.optimize

from jtire import enveloping as E
from jtire.rigid_ring import scenarios as sc
from jtire.rigid_ring import synthetic
from jtire.rigid_ring.params import derive
from jtire.rigid_ring.validation import compare, ring_metrics

R, H = 0.1, 0.02  # the E03 cleat: 200 mm diameter, 20 mm high
HALF = math.sqrt(R**2 - (R - H) ** 2)


def test_a_circular_cam_rides_the_cylinder_on_its_offset_curve():
    """c_e = 2 and a_e = b_e = rho: the cam is a circle of radius rho. While it touches the cleat's
    exposed arc its centre lies rho + R from the cleat's axis (at height H - R), so its lowest point
    is at H - R + sqrt((rho + R)^2 - X^2) - rho. The contact is looked for at 201 points across the
    chord (0.6 mm apart): the missed height is below (0.6 mm)^2 / (8 x 0.1 m) ~ 0.5 um."""
    rho = 0.3
    X = np.linspace(0.0, 0.05, 11)  # the contact stays on the exposed arc (its normal points above the road)
    exact = H - R + np.sqrt((rho + R) ** 2 - X**2) - rho
    got = np.array([float(E.cam_height(x, rho, rho, 2.0, R, H)) for x in X])
    assert np.max(np.abs(got - exact)) < 2e-6
    assert float(E.cam_height(0.0, rho, rho, 2.0, R, H)) == pytest.approx(H, abs=1e-12)  # crest under the centre


def test_a_narrow_cam_follows_the_cleat_and_no_cam_reaches_past_its_length():
    """A cam much narrower than the cleat is a point follower: w_c(X) = the cleat's own height. A cam of
    half length a_e does not touch the cleat once its centre is more than HALF + a_e away; centred over
    the cleat's edge it does (the cleat rises at a finite slope, the cam only quadratically)."""
    X = np.linspace(-0.9, 0.9, 19) * HALF
    got = np.array([float(E.cam_height(x, 1e-3, 0.5, 2.0, R, H)) for x in X])
    assert np.max(np.abs(got - np.sqrt(R**2 - X**2) + (R - H))) < 2e-5
    for a_e in (0.05, 0.2):
        assert float(E.cam_height(HALF + a_e + 1e-3, a_e, 0.3, 2.0, R, H)) == 0.0
        assert float(E.cam_height(HALF, a_e, 0.3, 2.0, R, H)) > 0.0


def test_tandem_is_the_mean_and_the_difference_of_its_cams():
    l_s, a_e, b_e, c_e = 0.2, 0.3, 0.25, 1.7
    for s in (-0.3, -0.12, 0.0, 0.05, 0.21):
        wf = float(E.cam_height(s + l_s / 2, a_e, b_e, c_e, R, H))
        wr = float(E.cam_height(s - l_s / 2, a_e, b_e, c_e, R, H))
        w, slope = (float(v) for v in E.effective(s, l_s, a_e, b_e, c_e, R, H))
        assert w == pytest.approx(0.5 * (wf + wr), abs=1e-15) and slope == pytest.approx((wf - wr) / l_s, abs=1e-12)
        # mirror symmetry of a symmetric cleat: w even, the slope odd in s
        wm, sm = (float(v) for v in E.effective(-s, l_s, a_e, b_e, c_e, R, H))
        assert wm == pytest.approx(w, abs=1e-12) and sm == pytest.approx(-slope, abs=1e-9)
        # dw/ds by forward differentiation against a central difference
        _, _, rate = (float(v) for v in E.effective_with_rate(s, l_s, a_e, b_e, c_e, R, H))
        h = 1e-6
        w_at = lambda x: float(E.effective(x, l_s, a_e, b_e, c_e, R, H)[0])  # noqa: E731
        fd = (w_at(s + h) - w_at(s - h)) / (2 * h)
        assert rate == pytest.approx(fd, abs=1e-3)
    assert E.reach(l_s, a_e, R, H) == pytest.approx(HALF + l_s / 2 + a_e)


def test_the_host_tandem_is_the_traced_one():
    """`effective_many` (numpy, what the fit calls on the host) and `effective` traced by JAX (what the
    ring's road input calls) are one formula: equal to round-off at every position, across and past
    the cleat."""
    import jax

    cam = (0.2, 0.3, 0.25, 1.7)
    s = np.linspace(-0.6, 0.6, 61)
    w_np, sl_np = E.effective_many(s, *cam, R, H)
    w_jx, sl_jx = jax.vmap(lambda x: E.effective(x, *cam, R, H))(s)
    np.testing.assert_allclose(w_np, np.asarray(w_jx), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sl_np, np.asarray(sl_jx), rtol=1e-12, atol=1e-13)
    assert np.max(w_np) > 0.5 * H and w_np[0] == 0.0  # the bump is there, and ends


def test_fit_reproduces_a_known_tandem():
    """Data made by a known tandem: the fit reproduces its effective height to 1 % of the bump and its
    slope to 0.01 (the parameters themselves trade off on one cleat; the curve is what is identified)."""
    truth = (0.18, 0.35, 0.3, 2.2)
    s = np.linspace(-0.44, 0.44, 45)
    w, slope = (np.asarray(v) for v in E.effective_many(s, *truth, R, H))
    f = E.fit(s, w, slope, R, H, a=0.1, R0=0.55)
    assert f.rms_height_m < 0.01 * np.max(w) and f.rms_slope < 0.01
    assert f.max_height_m == pytest.approx(np.max(w))
    we, se = (np.asarray(v) for v in E.effective_many(s, f.l_s, f.a_e, f.b_e, f.c_e, R, H))
    assert np.max(np.abs(we - w)) < 0.02 * np.max(w)


@pytest.fixture(scope="module")
def d():
    ch = synthetic.characterization()
    return dataclasses.replace(derive(ch.rated_row(), ch.tire), ellips=(0.15, 0.35, 0.3, 2.0))


def test_ring_rolling_slowly_over_the_cam_is_quasi_static(d):
    """At 1 m/s the rim-locked ring's spindle F_z follows the static law of its springs with the road
    raised by the cam's w: z_a = w + R0 - rho_r(F) - F / k_bz held at its loaded value (solved for F).
    What is left is the belt's inertia and the dampers at the crossing's rate (~3 Hz against a 60-70 Hz
    belt mode: (3/65)^2 ~ 0.2 %; C_vr dw/dt ~ 1e2 N): 2 % of the force's rise."""
    r = sc.drum_cleat(d, speed=1.0, sample_rate=2000.0)
    s = r.signals
    t0 = d.tire.unloaded_radius_m
    fz0 = d.load_N
    za0 = t0 - d.residual_deflection(fz0) - fz0 / d.k_bz

    def f_static(w):
        return scipy.optimize.brentq(lambda f: w + t0 - d.residual_deflection(f) - f / d.k_bz - za0, 0.2 * fz0, 5 * fz0)

    w = np.asarray(s["road_z_m"])
    fz = np.asarray(s["spindle_F_z_N"])
    pred = np.array([f_static(x) for x in w])
    rise = np.max(pred) - fz0
    assert rise > 0.1 * fz0  # the cleat is felt
    assert np.max(np.abs(fz - pred)) < 0.02 * rise
    assert r.info["enveloping"].startswith("tandem")
    # the validation figure counts time from the crest under the rim centre: the symmetric cam's w
    # peaks there (to one sample, 0.5 ms = 0.5 mm of travel)
    from jtire.rigid_ring.validation import ring_signals

    t_fig, _ = ring_signals({"drum": r})["drum"]
    assert abs(t_fig[int(np.argmax(w))]) <= 0.5e-3 + 1e-12


def test_validation_judges_peak_to_peak_only_through_the_cam(d):
    """With the cam the drum-cleat's peak-to-peak forces are ring metrics (judged at 20 %); with a point
    contact they are not given, and the rows say "not compared"."""
    shell = {"drum.F_z_peak_to_peak_N": 3e4, "drum.F_x_peak_to_peak_N": 2e4}
    with_cam = ring_metrics({"drum": sc.drum_cleat(d)})
    point = ring_metrics({"drum": sc.drum_cleat(dataclasses.replace(d, ellips=None))})
    assert "drum.F_z_peak_to_peak_N" in with_cam and "drum.F_z_peak_to_peak_N" not in point
    rows = {c.metric: c for c in compare(shell, point)}
    assert rows["drum.F_z_peak_to_peak_N"].verdict == "not compared"
    rows = {c.metric: c for c in compare(shell, with_cam)}
    assert rows["drum.F_z_peak_to_peak_N"].verdict in ("pass", "FAIL") and rows["drum.F_z_peak_to_peak_N"].tolerance == 0.2
