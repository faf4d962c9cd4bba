"""The rigid ring's tread string (jtire.rigid_ring.model, contact = "string") against closed forms:
its Chebyshev nodes, its frequency response against the exact brush and stretched string, and the
numpy linearization of the drum-cleat's fore-aft motion (modes.fore_aft_modes) against jax's of the
model itself, for both contacts."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jtire.rigid_ring import scenarios as sc
from jtire.rigid_ring import synthetic
from jtire.rigid_ring.model import (
    _D_TREAD,
    _W_TREAD,
    N_TREAD,
    Drive,
    RigidRing,
    linearize,
    modes,
    string_rates,
)
from jtire.rigid_ring.modes import fore_aft_modes
from jtire.rigid_ring.params import RigidRingParams, derive


def test_chebyshev_nodes_are_exact_for_polynomials():
    n = N_TREAD
    xi = (1.0 - np.cos(np.pi * np.arange(n + 1) / n)) / 2.0  # 0 (leading edge) .. 1
    for k in range(n + 1):
        # differentiation exact to degree n, Clenshaw-Curtis integration to degree n (n even: n + 1)
        assert _D_TREAD @ xi**k == pytest.approx(k * xi ** max(k - 1, 0) if k else np.zeros(n + 1), abs=1e-11)
        assert _W_TREAD @ xi**k == pytest.approx(1.0 / (k + 1), abs=1e-13)


def _string_response(a, V, sigma_s, omegas):
    """F / v_c at each omega of the string's own linear rates (jax), as c = 1."""
    lead = sigma_s is not None

    def rates(x, v):
        dl, dn, _, _ = string_rates(x[0], x[1:], v, V, a, sigma_s)
        return jnp.concatenate([jnp.reshape(dl, (1,)), dn])

    def force(x):
        return string_rates(x[0], x[1:], 0.0, V, a, sigma_s)[2]

    x0 = jnp.zeros(N_TREAD + 1)
    A = np.asarray(jax.jacfwd(rates)(x0, 0.0))
    B = np.asarray(jax.jacfwd(rates, argnums=1)(x0, 0.0))
    C = np.asarray(jax.jacfwd(force)(x0))
    if not lead:  # the leading edge is held at 0: drop its (zero) row and column
        A, B, C = A[1:, 1:], B[1:], C[1:]
    return np.array([C @ np.linalg.solve(1j * w * np.eye(B.size) - A, B) for w in omegas])


def _exact(a, V, sigma_s, omegas):
    """The continuous string's F / v_c: the leading edge e1 = v / (i w + V / sigma_s) (0 for a brush),
    e(xi) = e1 exp(-i w xi / V) + v (1 - exp(-i w xi / V)) / (i w), F = sigma_s (e1 + e(2a)) + int e."""
    xi = np.linspace(0.0, 2 * a, 20001)
    out = []
    for w in omegas:
        s = 1j * w
        e1 = 0.0 if sigma_s is None else 1.0 / (s + V / sigma_s)
        e = e1 * np.exp(-s * xi / V) + (1 - np.exp(-s * xi / V)) / s
        out.append((0.0 if sigma_s is None else sigma_s * (e1 + e[-1])) + np.trapezoid(e, xi))
    return np.asarray(out)


@pytest.mark.parametrize("sigma_s", [None, 0.05, 0.3])
def test_string_frequency_response_matches_the_continuous_string(sigma_s):
    a, V = 0.1, 13.9
    T = 2 * a / V
    theta = np.array([0.05, 0.5, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0])  # omega x transit time 2a / V
    w = theta / T
    got, ref = _string_response(a, V, sigma_s, w), _exact(a, V, sigma_s, w)
    scale = abs(ref[0])
    # 6 Chebyshev nodes: within 1 % of the steady response up to omega 2a/V = 10 (measured 0.55 % for
    # the brush; 60 Hz at 13.9 m/s on a 0.2 m patch is 5.4), 0.1 % up to 6
    err = np.abs(got - ref) / scale
    assert err.max() < 1e-2
    assert err[theta <= 6].max() < 1e-3
    # the point of the string: at omega 2a/V = 5.4 the brush dissipates a fifth of what a lag over a does
    if sigma_s is None:
        th = 2 * math.pi * 60.0 * T
        lag = 1.0 / (1.0 + (th / 2) ** 2)  # Re of the lag's response, relative to its steady one
        brush = np.real(_string_response(a, V, None, [th / T])[0]) / scale
        assert brush < 0.3 * lag


@pytest.fixture(scope="module")
def d():
    ch = synthetic.characterization()
    return derive(ch.rated_row(), ch.tire)


@pytest.mark.parametrize("contact", ["string", "lag"])
def test_fore_aft_modes_in_numpy_match_the_models_linearization(d, contact):
    V = 50 / 3.6
    m = RigidRing(RigidRingParams.from_derived(d), "reduced", contact)
    eq = sc.vertical_equilibrium(d, d.load_N)
    y0 = sc._state(z_a=eq["z_a"], z_b=eq["z_b"], v_theta_a=V / d.r_e, v_theta_b=V / d.r_e)
    fn, zeta = modes(linearize(m, Drive.make(free=("theta_a",), V=V), y0), ("x_b", "theta_b", "theta_a"), ("u",))
    ref = fore_aft_modes(d, V, contact=contact)
    # two routes to the same eigenvalues (hand-written matrices vs jax.jacfwd of the vector field)
    assert fn == pytest.approx([f for f, _, _ in ref], rel=1e-8)
    assert zeta == pytest.approx([z for _, z, _ in ref], rel=1e-7)


def test_string_static_stiffness_at_standstill(d):
    """At V = 0 nothing is carried through the patch: a uniform deflection e is the static state and
    the force is k_cy e (the lag's tread spring), so the lateral release starts in equilibrium."""
    m = RigidRing(RigidRingParams.from_derived(d), "ring", "string")
    e = 2e-3
    y0 = sc._state(e=e, z_b=d.tire.unloaded_radius_m - 0.01)
    f = m.forces(0.0, y0, Drive.make())
    assert float(f["F_y"]) == pytest.approx(-d.k_cy * e, rel=1e-12)
    assert np.asarray(f["tread_dot"]) == pytest.approx(np.zeros(2 + 2 * N_TREAD), abs=1e-15)
