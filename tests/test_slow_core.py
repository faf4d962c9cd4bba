"""Slow checks (run with `python -m pytest -m slow`): mesh convergence and solver gradients.

Slow because each compiles programs of its own: the default and a finer mesh (minutes each), and a
forward-mode (jvp) program through the integration.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import pytest

from jtire import batch, solve, units as U
from jtire.experiments import phases
from jtire.state import TireState
from jtire.tire import make_tire

from .conftest import RATED, make_experiment, ok

pytestmark = pytest.mark.slow


def _k_sv(spec, protocol):
    tire = make_tire(spec)
    exp = make_experiment("vertical_stiffness", protocol, spec, ramp_s=0.3)
    (res,) = batch.run(exp, tire, [RATED], devices=1)
    return ok(res).quantities["k_sv_N_per_m"]


def test_mesh_convergence_of_vertical_stiffness(spec, protocol):
    """Refining the default mesh (64 x 17 nodes) to 96 x 29 moves k_sv by under 2 %."""
    k_default = _k_sv(spec, protocol)
    k_fine = _k_sv(dataclasses.replace(spec, n_theta=96, n_side=10, n_crown=8), protocol)
    assert abs(k_fine - k_default) / k_fine < 0.02, (k_default, k_fine)


def test_solver_derivative_matches_finite_differences(coarse_tire):
    """d(cavity volume after 10 ms of inflation)/d(crown belt modulus): forward-mode through
    diffeqsolve against a central difference (rel 1e-5: float64, smooth dynamics, h = 1e-4)."""
    m, p = coarse_tire.model, coarse_tire.params.without_damping()
    dt = solve.stable_step(m, p, 8e5, 300.0)
    drive = phases.make_drive(8e5, dt, pressure0=0.0, t0=0.0, t1=0.01, surface=phases.flat_road(-phases.FAR),
                              damping=300.0)
    y0 = TireState.at_rest(m, len(p.relaxation_times))
    ts = jnp.linspace(0.0, 0.01, solve.N_SAVE)

    @eqx.filter_jit
    def volume(scale):
        pp = eqx.tree_at(lambda q: q.E_circumferential, p, p.E_circumferential.at[-1].multiply(scale))
        res = solve.run_phase(m, pp, drive, y0, jnp.float64(0.0), jnp.float64(0.01), ts, jnp.float64(jnp.inf),
                              jnp.float64(1e-9), solve.MAX_STEPS)
        return res.saved["volume"][-1]

    _, tangent = jax.jvp(volume, (jnp.asarray(1.0),), (jnp.asarray(1.0),))
    h = 1e-4
    fd = (volume(jnp.asarray(1 + h)) - volume(jnp.asarray(1 - h))) / (2 * h)
    assert float(tangent) == pytest.approx(float(fd), rel=1e-5)
    assert float(tangent) < 0  # a stiffer belt grows less under pressure


def test_footprint_shortens_with_pressure_on_the_default_mesh(spec, protocol):
    conds = [dict(pressure_Pa=p * U.PSI, load_N=RATED["load_N"]) for p in (70.0, 120.0, 150.0)]
    exp = make_experiment("footprint", protocol, spec)
    res = batch.run(exp, make_tire(spec), conds)
    lengths = [ok(r).quantities["contact_length_m"] for r in res]
    assert lengths[0] > lengths[1] > lengths[2], lengths
