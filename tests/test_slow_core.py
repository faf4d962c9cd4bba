"""Slow checks (run with `python -m pytest -m slow`): mesh convergence and solver gradients."""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import pytest

from jtire import solve, units as U
from jtire.experiments import phases, static
from jtire.tire import make_tire

pytestmark = pytest.mark.slow


def _k_sv(spec, protocol):
    tire = make_tire(spec)
    cond = dict(pressure_Pa=120 * U.PSI, load_N=4625 * U.G0)
    res = static.run_vertical_stiffness(tire, cond, protocol, 60e3, cond["load_N"], 0.3, (10e3, 60e3))
    return res.quantities["k_sv_N_per_m"]


def test_mesh_convergence_of_vertical_stiffness(spec, protocol):
    """Refining the default mesh (64 x 17 nodes) to 96 x 29 moves k_sv by under 2 %."""
    k_default = _k_sv(spec, protocol)
    k_fine = _k_sv(dataclasses.replace(spec, n_theta=96, n_side=10, n_crown=8), protocol)
    assert abs(k_fine - k_default) / k_fine < 0.02, (k_default, k_fine)


def test_solver_derivative_matches_finite_differences(coarse_tire):
    """d(cavity volume after 10 ms of inflation)/d(crown belt modulus): forward-mode through
    diffeqsolve against a central difference (rel 1e-5: float64, smooth dynamics, h = 1e-4)."""
    m, p = coarse_tire.model, coarse_tire.params.without_damping()
    proto = phases.Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-9, inflate_ramp=0.01, inflate_max=0.01,
                                           load_ramp=0.1, settle_max=0.1))
    dt = solve.stable_step(m, p, 8e5, 300.0)

    @eqx.filter_jit
    def volume(scale):
        pp = eqx.tree_at(lambda q: q.E_circumferential, p, p.E_circumferential.at[-1].multiply(scale))
        res = phases.inflate(m, pp, 8e5, dt, proto, solve.MAX_STEPS)
        return res.saved["volume"][-1]

    _, tangent = jax.jvp(volume, (jnp.asarray(1.0),), (jnp.asarray(1.0),))
    h = 1e-4
    fd = (volume(jnp.asarray(1 + h)) - volume(jnp.asarray(1 - h))) / (2 * h)
    assert float(tangent) == pytest.approx(float(fd), rel=1e-5)
    assert float(tangent) < 0  # a stiffer belt grows less under pressure


def test_footprint_shortens_with_pressure_on_the_default_mesh(spec, protocol):
    from jtire import sweep

    conds = [dict(pressure_Pa=p * U.PSI, load_N=4625 * U.G0) for p in (70.0, 120.0, 150.0)]
    res = sweep.run_static_batch(make_tire(spec), conds, protocol, "footprint", {})
    lengths = [r.quantities["contact_length_m"] for r in res]
    assert lengths[0] > lengths[1] > lengths[2], lengths
