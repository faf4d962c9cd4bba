"""Designs of experiments, the quadratic response surface and the search-region rules."""

import numpy as np
import pytest

import jtire  # noqa: F401  (float64)
from jtire.errors import ConfigError
from jtire.surrogates import (
    Region,
    arsm_update,
    as_bounds,
    central_composite,
    fit_quadratic,
    inherit,
    latin_hypercube,
    maximin_fill,
    n_terms,
    second_best,
    sobol,
    srsm_update,
    star,
    to_bounds,
    to_unit,
)

# Exact-arithmetic identities checked in float64 after a least-squares solve: round-off only.
EXACT = 1e-9


def _quad(x):
    """A full quadratic in 3 variables of very different scales (interactions included)."""
    x = np.atleast_2d(x)
    return (1.5 + 2.0 * x[:, 0] - 0.3 * x[:, 1] + 1e-3 * x[:, 2] ** 2 + 0.7 * x[:, 0] * x[:, 1]
            + 3.0 * x[:, 0] ** 2 - 2e-2 * x[:, 1] * x[:, 2])


def _quad_grad(x):
    x = np.atleast_2d(x)
    return np.stack([2.0 + 0.7 * x[:, 1] + 6.0 * x[:, 0],
                     -0.3 + 0.7 * x[:, 0] - 2e-2 * x[:, 2],
                     2e-3 * x[:, 2] - 2e-2 * x[:, 1]], axis=1)


SCALE = np.array([1.0, 10.0, 100.0])


def test_full_quadratic_reproduced_exactly():
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(14, 3)) * SCALE
    s = fit_quadratic(x, _quad(x))
    assert s.kind == "full" and s.coef.size == n_terms(3, "full") == 10
    xt = rng.uniform(size=(20, 3)) * SCALE
    f_scale = np.ptp(_quad(xt))
    assert np.max(np.abs(s.predict(xt) - _quad(xt))) <= EXACT * f_scale
    assert np.max(np.abs(s.gradient(xt) - _quad_grad(xt))) <= EXACT * f_scale
    assert s.r2 == pytest.approx(1.0, abs=EXACT)
    assert s.loo_rmse <= EXACT * f_scale  # no model error: leave-one-out is exact too


def test_auto_basis_falls_back_to_reduced_and_linear():
    rng = np.random.default_rng(1)
    sep = lambda x: 1 + x[:, 0] - 2 * x[:, 1] ** 2 + 0.5 * x[:, 2] ** 2  # noqa: E731 (separable)
    x = rng.uniform(size=(8, 3))  # 8 < 10 full terms, >= 7 reduced terms
    s = fit_quadratic(x, sep(x))
    assert s.kind == "reduced"
    xt = rng.uniform(size=(5, 3))
    assert np.max(np.abs(s.predict(xt) - sep(xt))) <= EXACT
    assert fit_quadratic(x[:5], sep(x[:5])).kind == "linear"
    with pytest.raises(ConfigError):
        fit_quadratic(x[:3], sep(x[:3]))


def test_gradient_enhanced_fit_needs_far_fewer_points():
    # 4 points x (1 value + 3 slopes) = 16 equations fix the 10 coefficients
    rng = np.random.default_rng(2)
    x = rng.uniform(size=(4, 3)) * SCALE
    s = fit_quadratic(x, _quad(x), grad=_quad_grad(x))
    assert s.kind == "full"
    xt = rng.uniform(size=(20, 3)) * SCALE
    assert np.max(np.abs(s.predict(xt) - _quad(xt))) <= EXACT * np.ptp(_quad(xt))


def test_leave_one_out_matches_explicit_refits():
    rng = np.random.default_rng(3)
    x = rng.uniform(size=(12, 2))
    f = np.sin(3 * x[:, 0]) + x[:, 1] ** 3  # not quadratic: nonzero residuals
    s = fit_quadratic(x, f, kind="full")
    for i in range(12):
        keep = np.arange(12) != i
        si = fit_quadratic(x[keep], f[keep], kind="full", lower=s.centre - s.half_width,
                           upper=s.centre + s.half_width)
        assert s.loo_residuals[i] == pytest.approx(f[i] - si.predict(x[i])[0], rel=1e-8)
    assert s.press == pytest.approx(np.sum(s.loo_residuals**2), rel=1e-12)


def test_prediction_variance_of_a_line_matches_textbook_formula():
    # straight-line regression: var(yhat(x0)) = s^2 (1/n + (x0 - xbar)^2 / Sxx)
    rng = np.random.default_rng(4)
    x = np.linspace(0.0, 2.0, 9)[:, None]
    y = 1.0 + 0.5 * x[:, 0] + 0.1 * rng.normal(size=9)
    s = fit_quadratic(x, y, kind="linear")
    resid = y - s.predict(x)
    s2 = np.sum(resid**2) / (9 - 2)
    x0 = np.array([[0.3], [1.7], [3.0]])
    expected = s2 * (1 / 9 + (x0[:, 0] - x.mean()) ** 2 / np.sum((x[:, 0] - x.mean()) ** 2))
    np.testing.assert_allclose(s.variance(x0), expected, rtol=1e-10)


def test_argmin_interior_and_on_the_box():
    c = np.array([0.3, 0.6])
    x = latin_hypercube(10, 2, seed=0)
    f = np.sum((x - c) ** 2 * [1.0, 4.0], axis=1)
    s = fit_quadratic(x, f)
    xm, fm = s.argmin([0, 0], [1, 1], seed=0)
    np.testing.assert_allclose(xm, c, atol=1e-6)  # L-BFGS-B default tolerance on a bowl
    xb, _ = s.argmin([0.5, 0.0], [1.0, 1.0], seed=0)  # minimum cut off by the box
    np.testing.assert_allclose(xb, [0.5, 0.6], atol=1e-6)


def test_hessian_and_argmin_of_a_saddle():
    x = central_composite(2) * 2 - 1  # 9 points on [-1, 1]^2
    f = x[:, 0] ** 2 - x[:, 1] ** 2 + 0.5 * x[:, 0] * x[:, 1] + 0.1 * x[:, 1]
    s = fit_quadratic(x, f)
    np.testing.assert_allclose(s.hessian(), [[2.0, 0.5], [0.5, -2.0]], atol=EXACT)
    xm, fm = s.argmin([-1, -1], [1, 1], seed=0)
    # on the face x1 = -1: minimize x0^2 - 0.5 x0 -> x0 = 0.25, f = 0.0625 - 0.125 - 1 - 0.1
    np.testing.assert_allclose(xm, [0.25, -1.0], atol=1e-9)
    assert fm == pytest.approx(-1.1625, abs=1e-9)


def test_designs():
    n, d = 7, 3
    x = latin_hypercube(n, d, seed=5)
    # one point per stratum of width 1/n in every coordinate
    for j in range(d):
        assert sorted(np.floor(x[:, j] * n).astype(int)) == list(range(n))
    np.testing.assert_array_equal(x, latin_hypercube(n, d, seed=5))  # seeded
    s = sobol(16, d, seed=1)
    assert s.shape == (16, d) and np.all((s >= 0) & (s <= 1))
    ccd = central_composite(d)
    assert ccd.shape == (2**d + 2 * d + 1, d)
    assert np.all(np.isin(ccd, [0.0, 0.5, 1.0]))  # face-centred: levels 0, 1/2, 1 only
    rot = central_composite(2, "rotatable")
    # inscribed rotatable: axial points on the faces, corners at 0.5 +- 0.5 / sqrt(2)
    assert np.max(rot) == pytest.approx(1.0) and np.min(rot) == pytest.approx(0.0)
    assert rot[0, 0] == pytest.approx(0.5 - 0.5 / np.sqrt(2))
    st = star(d)
    assert st.shape == (2 * d + 1, d)
    sep = lambda x: 2 - x[:, 0] + x[:, 1] ** 2 + 3 * x[:, 2] ** 2  # noqa: E731
    assert fit_quadratic(st, sep(st), kind="reduced").r2 == pytest.approx(1.0)
    lo, hi = as_bounds([1.0, -5.0, 1e5], [2.0, 5.0, 1e7])
    np.testing.assert_allclose(to_unit(to_bounds(x, lo, hi), lo, hi), x, atol=1e-15)
    with pytest.raises(ConfigError):
        as_bounds([0.0, 1.0], [1.0, 1.0])


def test_maximin_fill_stays_inside_and_away():
    have = np.array([[0.5, 0.5]])
    new = maximin_fill(3, have, [0.4, 0.4], [0.6, 0.6], seed=0)
    assert np.all((new >= 0.4) & (new <= 0.6))
    # the first new point is as far as possible from the centre: a corner of the box
    assert np.max(np.abs(new[0] - 0.5)) == pytest.approx(0.1, abs=0.01)


class _Bowl:
    """Surface stand-in: q(x) = |x - c|^2, whose sub-level set {q <= r^2} is a ball."""

    def __init__(self, c):
        self.c = np.asarray(c)

    def predict(self, x):
        return np.sum((np.atleast_2d(x) - self.c) ** 2, axis=1)


def test_arsm_region_is_box_around_sub_level_set():
    c, r = np.array([0.4, 0.55]), 0.1
    new = arsm_update(Region.unit(2), _Bowl(c), r**2, best_x=c, seed=0, min_shrink=0.0,
                      n_samples=4096)
    pad = 4096 ** -0.5  # one sample spacing, the documented padding
    assert np.all(new.lower <= c - r + 1e-12) and np.all(new.upper >= c + r - 1e-12)
    assert np.all(new.lower >= c - r - 2 * pad) and np.all(new.upper <= c + r + 2 * pad)


def test_arsm_region_safeguards():
    c = np.array([0.4, 0.55])
    best = np.array([0.9, 0.1])  # the surface is wrong about where the best point is
    new = arsm_update(Region.unit(2), _Bowl(c), 1e-4, best_x=best, seed=0, min_shrink=0.5)
    assert np.all(inherit(best[None], new))
    assert np.all(new.width >= 0.5 - 1e-12)  # one step shrinks at most by min_shrink
    tiny = arsm_update(Region.unit(2), _Bowl(c), 0.0, best_x=c, seed=0, min_width=0.05,
                       min_shrink=0.0)
    np.testing.assert_allclose(tiny.width, 0.05)
    # zoom after a failed proposal: width min_shrink * old, centred on the best point
    z = arsm_update(Region.unit(2), _Bowl(c), 1.0, best_x=c, seed=0, min_shrink=0.5, zoom=True)
    np.testing.assert_allclose(z.width, 0.5)
    np.testing.assert_allclose(z.centre, c)


def test_arsm_region_pans_across_an_inner_face():
    old = Region(np.array([0.2, 0.2]), np.array([0.4, 0.4]))
    best = np.array([0.4, 0.3])  # on the upper face of axis 0, which is not a global face
    new = arsm_update(old, _Bowl(best), 1e-3, best_x=best, seed=0, pan_growth=2.0)
    assert new.centre[0] == pytest.approx(0.4) and new.width[0] == pytest.approx(0.4)
    assert new.upper[0] > old.upper[0]  # it left the old region, which plain ARSM cannot


def test_srsm_pan_and_zoom():
    reg = Region(np.array([0.2, 0.2]), np.array([0.6, 0.6]))
    z = srsm_update(reg, reg.centre, eta=0.6)  # optimum at the centre: pure zoom by eta
    np.testing.assert_allclose(z.width, 0.6 * reg.width)
    np.testing.assert_allclose(z.centre, reg.centre)
    edge = np.array([0.6, 0.4])  # on the edge of axis 0 (|d| = 1), centre of axis 1
    p1 = srsm_update(reg, edge, eta=0.6, gamma_pan=1.0, gamma_osc=0.6)
    # no history yet: c = 0, gamma = (1 + 0.6) / 2 = 0.8, lambda = 0.8 on axis 0
    np.testing.assert_allclose(p1.width, [0.8 * 0.4, 0.6 * 0.4])
    p2 = srsm_update(p1, p1.upper * [1, 0] + p1.centre * [0, 1], eta=0.6)
    assert p2.width[0] == pytest.approx(p1.width[0])  # panning twice the same way: gamma_pan = 1


def test_inherit_and_threshold():
    reg = Region(np.array([0.2, 0.2]), np.array([0.5, 0.5]))
    x = np.array([[0.3, 0.3], [0.2, 0.5], [0.6, 0.3]])
    np.testing.assert_array_equal(inherit(x, reg), [True, True, False])
    assert second_best([3.0, np.nan, 1.0, 2.0]) == 2.0
