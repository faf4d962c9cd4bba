"""Steady-rolling paths: inflation, first contact and loading at speed, then operating points.

Every level is one steady-rolling equilibrium (`steady.solve_rolling`) started from the previous
level's solution with its factorization as the first preconditioner; each is one call of a single
compiled program (`solve_level`), shared by every level, experiment and condition on the same model
and surface type (flat road or drum). The path:

    inflated    the rim held, the road out of reach, the spin prescribed (the flow's inertia acts)
    touching    the road moved to the lowest tread point; the rim pressed 1 mm into it (held)
    loaded      the rim free vertically under `n_load` equal load levels, the spin free (no torque)
then any operating points: a speed, a slip angle (the road's direction), a camber, a prescribed spin
(longitudinal slip against the free-rolling spin) or a drive torque.

Rolling needs the flow: a standing tire (Omega = 0) has no streamlines to carry the tread's shear
along, so loading happens at the rolling speed, which also puts the inertia of the flow in place.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.contact import FlatRoad
from ..physics.drum import Drum
from ..physics.geometry_ops import V
from . import residual as R
from . import rolling_residual as RR
from .newton import NewtonOptions, check_static
from .sequences import D_TOUCH
from .steady import solve_rolling

FAR = -10.0  # m: road (or drum top) height of the inflation level: out of reach, the same surface type
HOLD = np.array([0.0, 0, 0, 0, 0, 0])
LOADED = np.array([0.0, 0, 1, 0, 1, 0])  # rim z free under the load, the spin free (no drive torque)
LOADED_SPIN_HELD = np.array([0.0, 0, 1, 0, 0, 0])  # ... the spin prescribed (longitudinal slip)
# a shortened step does not by itself refactor: the factorization (~0.2 s on the default mesh) costs
# ~30 GMRES iterations, and a preconditioner gone stale shows as a slow GMRES, which does refactor
ROLLING_OPTIONS = NewtonOptions(max_iter=30, refresh_on_damping=False)
LOOSE = 1e-3  # relative residual of the levels on the way (inflation, contact, partial loads): guesses only


@dataclasses.dataclass(frozen=True)
class Road:
    """Where the tire rolls: kind "flat" (a flat track moving under the axle) or "drum" (a drum of
    `radius` m under the tire, its top at the road height, turning with the given surface speed)."""

    kind: str = "flat"
    radius: float = 0.0

    def surface(self, height, velocity):
        """The surface at `height` (m; the drum's top) moving with `velocity` (3,) m/s at the contact
        (ISO: -V along x for forward rolling; a slip angle turns it)."""
        f = lambda v: jnp.asarray(v, jnp.float64)  # noqa: E731
        if self.kind == "flat":
            return FlatRoad(height=f(height), velocity=f(velocity))
        r = f(self.radius)
        return Drum(radius=r, centre_x=f(0.0), centre_z=f(height) - r, omega=f(velocity)[0] / r)


def road_velocity(speed, slip_angle=0.0):
    """(3,) ISO velocity (m/s) of the road under a fixed axle for a wheel travelling at `speed` with
    SAE slip angle `slip_angle` (rad): positive when the wheel centre travels to the RIGHT of its
    heading. The wheel's ground velocity is V (cos a, -sin a, 0) in ISO (y left), so the road moves at
    minus that. The tire then slides right over the road, friction pushes it left: F_y(ISO) > 0, i.e.
    F_y(SAE) < 0 for a > 0 (cornering stiffness = -dF_y,SAE / d alpha > 0)."""
    a = jnp.asarray(slip_angle, dtype=jnp.float64)
    return jnp.stack([-speed * jnp.cos(a), speed * jnp.sin(a), jnp.zeros_like(a)], axis=-1)


def _level(model, params, setup, u, P, valid, opts):
    u1, info, P1 = solve_rolling(model, params, setup, u, opts, (P, valid))
    return u1, info, P1, observe(model, params, setup, u1)


_solve_level = eqx.filter_jit(_level)


def _committed(tree):
    """Every concrete array of tree committed to the current default device: a compiled program is
    specific to whether each input is committed, and a path mixes fresh arrays with earlier levels'
    outputs and a case's committed inputs (without it, one trace compiled several times
    over: docs/design-notes.md)."""
    dev = jax.config.jax_default_device or jax.devices()[0]

    def put(a):
        if isinstance(a, jax.core.Tracer) or not isinstance(a, (np.ndarray, jax.Array)):
            return a
        return jax.device_put(a, dev)

    return jax.tree_util.tree_map(put, tree)


def solve_level(model, params, setup, u, P, valid, opts):
    """One steady level, compiled once per mesh and structure (`_level` under filter_jit)."""
    return _solve_level(*_committed((model, params, setup, u, P, valid, opts)))


def observe(model, params, setup, u) -> dict:
    """What a level reports (traced): rim q (6,) (slot 4: the spin, rad/s), the tire's force on the rim
    (6,) (the hub), the contact force (3,) and moment about the wheel centre (3,), the spin (rad/s),
    the losses (W: rubber, tread normal damping, sliding) and the number of contact points touching."""
    _, d = RR.rolling_forces(model, params, setup, u)
    q = R.unpack(model, u, False)[1]
    keys = ("tire_on_rim", "contact_force", "contact_moment", "omega", "power_rubber", "power_contact_damping",
            "power_friction", "power_nodal_damping", "n_contact")
    return {"q": q} | {k: d[k] for k in keys}


def setup_of(pressure, surface, *, omega, rim_free, load=0.0, rim_position=HOLD, torque=0.0, friction_on=1.0,
             subpoints=8):
    force = jnp.zeros(6).at[2].set(-jnp.asarray(load, jnp.float64)).at[RR.SPIN].set(torque)
    return RR.make_rolling_setup(pressure, surface, omega=omega, rim_force=force, rim_free=rim_free,
                                 rim_position=rim_position, friction_on=friction_on, subpoints=subpoints)


class Path:
    """A steady-rolling path being solved, level by level: the current unknowns u, the factorization
    carried to the next level, every level's observations and Newton info (host lists), and the road
    height. `level(setup)` solves one more level and returns its observations."""

    def __init__(self, model, params, pressure, road: Road, opts: NewtonOptions = ROLLING_OPTIONS):
        self.model, self.params, self.pressure, self.road, self.opts = model, params, pressure, road, opts
        self.u, self.P, self.valid = None, None, jnp.asarray(False)
        self.height = jnp.asarray(FAR, jnp.float64)
        self.obs, self.infos, self.names = [], [], []
        self.values = []  # the operating point of each level (a slip angle, a slip; nan: none)

    def level(self, setup, name: str, loose: bool = False, value=float("nan")):
        """Solve one more level; loose: to LOOSE only (a level on the way, a guess for the next); value:
        its operating point (recorded in `values`, for naming a level that failed)."""
        from .newton import empty_factor

        if self.P is None:
            self.P = empty_factor(self.model, R.make_setup(self.pressure))
        params = self.params
        if loose:  # a guess for the next level: no derivatives through it (they follow from the last level)
            opts = eqx.tree_at(lambda o: o.rtol, self.opts, jnp.asarray(LOOSE, jnp.float64))
            params, setup = jax.lax.stop_gradient((params, setup))
        else:
            opts = self.opts
        self.u, info, self.P, ob = solve_level(self.model, params, setup, self.u, self.P, self.valid, opts)
        self.valid = jnp.asarray(True)
        self.obs.append(ob)
        self.infos.append(info)
        self.names.append(name)
        self.values.append(float(value))
        return ob

    def attempt(self, setup, name: str, loose: bool = False, keep_failure: bool = False, value=float("nan")):
        """(observations, ok): one more level, kept only if its Newton converged (ok True); a level that
        failed is dropped and the path restored to where it was (ok False), so that a continuation can
        retry with a smaller step (keep_failure: kept, for `check` to report). ok is None when the solve
        is traced (no host value to judge), and the level is kept as `level` keeps it."""
        saved = (self.u, self.P, self.valid)
        ob = self.level(setup, name, loose, value)
        try:
            ok = bool(self.infos[-1].converged)
        except jax.errors.ConcretizationTypeError:
            return ob, None
        if not ok and not keep_failure:
            del self.obs[-1], self.infos[-1], self.names[-1], self.values[-1]
            self.u, self.P, self.valid = saved
        return ob, ok

    @property
    def q(self):
        return R.unpack(self.model, self.u, False)[1]

    def tread_low(self):
        """Height (m) of the lowest tread point now (the road that just touches it)."""
        x, q = R.unpack(self.model, self.u, False)[:2]
        return jnp.min(self.model.tread_points(self.model.assemble(x, q.at[RR.SPIN].set(0.0))).z)

    def check(self, where):
        """Raise SimulationError naming the first level that did not converge (host)."""
        infos = jax.tree_util.tree_map(lambda *a: np.stack([np.asarray(v) for v in a]), *self.infos)
        check_static(infos, lambda k: f"{where}: steady rolling, {self.names[k]}")


def loaded_rolling(model, params, pressure, load, road: Road, speed, *, n_load: int = 3, slip_angle=0.0,
                   camber=0.0, omega0, subpoints: int = 8, opts: NewtonOptions = ROLLING_OPTIONS) -> Path:
    """Inflate, touch and load the tire at `speed` (m/s) on `road`, free rolling: a Path whose last
    level is the loaded, free-rolling steady state. omega0: the spin (rad/s) of the levels before the
    load carries it (speed / an estimated rolling radius)."""
    path = Path(model, params, pressure, road, opts)
    vel = road_velocity(speed, slip_angle)
    held = HOLD.copy()
    pos = jnp.zeros(6).at[3].set(camber)
    x0 = model.x_ref
    path.u = R.pack(x0, jnp.zeros(6).at[RR.SPIN].set(omega0))
    sub = dict(subpoints=subpoints)
    path.level(setup_of(pressure, road.surface(FAR, vel), omega=omega0, rim_free=held, rim_position=pos, **sub),
               "inflation", loose=True)
    path.height = path.tread_low()
    x, q = R.unpack(model, path.u, False)[:2]
    path.u = R.pack(x + V(0.0, 0.0, -D_TOUCH), q.at[2].add(-D_TOUCH))  # the guess moves with the held rim
    path.level(setup_of(pressure, road.surface(path.height, vel), omega=omega0, rim_free=held,
                        rim_position=pos.at[2].set(-D_TOUCH), **sub), "first contact", loose=True)
    for k in range(1, n_load + 1):
        path.level(setup_of(pressure, road.surface(path.height, vel), omega=omega0, rim_free=LOADED, load=load * k / n_load,
                            rim_position=pos, **sub), f"load {k}/{n_load}", loose=k < n_load)
    return path
