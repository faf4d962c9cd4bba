"""Energy is conserved with every damping off (symplectic Euler, constant pressure, rim held)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jtire import solve
from jtire.experiments import phases
from jtire.physics.geometry_ops import V


def test_energy_conserved_without_damping(coarse_tire):
    m = coarse_tire.model
    p = coarse_tire.params.without_damping()
    pressure = 8.27e5
    proto = phases.Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-4, inflate_ramp=0.04, inflate_max=0.4,
                                           load_ramp=0.1, settle_max=0.1))
    dt = solve.stable_step(m, p, pressure, 300.0)
    inf = phases.inflate(m, p, pressure, dt, proto, solve.MAX_STEPS)
    solve.check_phase("inflate", inf, m)
    # kick: a smooth radial velocity field (a breathing mode) of ~0.5 m/s on every free node
    x = inf.y.x
    r = jnp.sqrt(x.x**2 + x.z**2)
    kick = V(0.5 * x.x / r, jnp.zeros_like(r), 0.5 * x.z / r)
    y0 = eqx.tree_at(lambda s: s.v, inf.y, kick)
    drive = phases.make_drive(pressure, dt, proto, surface=phases.far_road(), damping=0.0)
    t0 = float(inf.t_end)
    dur = 0.05  # ~2700 steps
    ts = jnp.linspace(t0, t0 + dur, solve.N_SAVE)
    res = solve.run_phase_jit(m, p, drive, y0, jnp.asarray(t0), jnp.asarray(t0 + dur), ts, jnp.asarray(jnp.inf),
                              proto.ke_tol, solve.MAX_STEPS)
    s = jax.tree_util.tree_map(np.asarray, res.saved)
    E = s["ke"] + s["strain_energy"] - pressure * s["volume"]
    ke0 = s["ke"][0]
    assert ke0 > 0.1
    # symplectic Euler: no secular drift, a bounded oscillation of order (dt w)^2 KE for the
    # excited modes; the mean over the last tenth equals the first tenth's to 1 % of the
    # kinetic energy put in, and the oscillation stays within 10 %
    drift = abs(E[-20:].mean() - E[:20].mean()) / ke0
    spread = (E.max() - E.min()) / ke0
    assert drift < 0.01, (drift, spread)
    assert spread < 0.1, spread
    assert float(res.y.dissipated) == pytest.approx(0.0, abs=1e-12)
