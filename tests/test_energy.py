"""Energy is conserved with every damping off (symplectic Euler, constant pressure, rim held)."""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jtire import batch
from jtire.experiments.phases import FAR, Case, flat_road, inflate_branch, make_drive
from jtire.experiments.program import Phase, check_phase, phase
from jtire.physics.geometry_ops import V

from .test_drop import run_single_plan


def test_energy_conserved_without_damping(coarse_tire, protocol, e01_grid):
    """Inflate (settle damping on), then kick every node and run 50 ms (~2700 steps) with no damping
    at all: a plan of two phases run like any experiment (the suite's single-case program)."""
    p = coarse_tire.params.without_damping()
    tire = dataclasses.replace(coarse_tire, params=p)
    m = tire.model
    pressure = 8.27e5
    (dt,) = batch.stable_steps(m, [p], [pressure], float(protocol.settle_damping))
    dur = 0.05

    def kicked(c):
        def branch(y, t, mem):
            # a smooth radial velocity field (a breathing mode) of ~0.5 m/s on every free node
            r = jnp.sqrt(y.x.x**2 + y.x.z**2)
            y0 = eqx.tree_at(lambda s: s.v, y, V(0.5 * y.x.x / r, jnp.zeros_like(r), 0.5 * y.x.z / r))
            drive = make_drive(c.pressure, c.dt, surface=flat_road(-FAR), damping=0.0)
            return Phase(drive, y0, dur, jnp.inf), mem
        return [inflate_branch(c, protocol, flat_road(-FAR)), branch]

    outs, y_end, _ = run_single_plan(tire, protocol, Case.of(0.0, pressure, dt), kicked, {})
    check_phase("inflate", phase(outs, 0), m)
    free = phase(outs, 1)
    check_phase("free", free, m, require_settled=False)
    s = free.saved
    # the rim is held, so the kinetic energy relative to the rim frame is the absolute one
    E = np.asarray(s["ke"]) + np.asarray(s["strain_energy"]) - pressure * np.asarray(s["volume"])
    ke0 = float(np.asarray(s["ke"])[0])
    assert ke0 > 0.1
    # symplectic Euler: no secular drift, a bounded oscillation of order (dt w)^2 KE for the
    # excited modes; the mean over the last tenth equals the first tenth's to 1 % of the
    # kinetic energy put in, and the oscillation stays within 10 %
    drift = abs(E[-20:].mean() - E[:20].mean()) / ke0
    spread = (E.max() - E.min()) / ke0
    assert drift < 0.01, (drift, spread)
    assert spread < 0.1, spread
    assert float(y_end.dissipated) == pytest.approx(0.0, abs=1e-12)
    assert np.ptp(np.asarray(s["settle_work"])) == 0.0
