"""Static load sequences of the experiments: inflation, vertical load path, lateral load, belt holds.

A sequence is a stack of `Levels`, solved in order by one `lax.scan` (`run_levels`): one Newton
solver in the compiled program however many stages the experiment has (each solver instance
adds a long XLA compilation: docs/design-notes.md). Each level starts from the previous
solution, moved with the rim where the rim is held at a new position; the road is placed where
the previous state first touches it when asked; and the friction anchors follow the incremental
law of `residual`: each level's trial shear starts from the previous level's shear and position
(a point out of contact there has zero shear), so the tread shear is carried from level to level
as the dynamic bristles carry it.

    inflate_levels    rim held at 0, road far below: pressure 0 -> p in one solve
    vertical_levels   the road moved to first contact; the rim pressed down by d_touch with rim z
                      held (a regular solve although the tire only just touches), then rim z
                      free under each vertical load (E01: one load; E02: the curve)
    lateral_levels    rim y and z free: lateral loads at a constant vertical load (E09 static)
    belt_levels       rigid belt, rim held: belt loads (E05 / E07 / E08 holds)
and `static_path(model, params, pressure, *parts)` runs inflation + parts from the tire at rest.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..physics.contact import FlatRoad
from ..physics.geometry_ops import V
from ..state import TireState
from . import residual as R
from .newton import NewtonOptions, StaticInfo, empty_factor, solve_static_full

D_TOUCH = 1e-3  # m: the first, displacement-controlled press into the road
FAR = -10.0  # m: road height of levels without contact (the same surface type: one program)


class Levels(eqx.Module):
    """L levels of a static sequence (every field has the leading axis L).

    pressure (Pa); rim_force (6,) on free rim DOFs; rim_free (6,) 1/0; rim_position (6,) for the
    held DOFs; road_height (m; NaN = keep the previous level's); road_at_contact (1: put the road
    at the lowest tread point of the previous state); friction_on (1/0); reset_shear (1: anchor
    the tread where it is, unsheared); belt_load (6,) (only with a rigid belt); surface_arg: a
    number the level passes to `surface_at` besides the road height (NaN by default; E03 places its
    cleat with it).
    """

    pressure: jax.Array
    rim_force: jax.Array
    rim_free: jax.Array
    rim_position: jax.Array
    road_height: jax.Array
    road_at_contact: jax.Array
    friction_on: jax.Array
    reset_shear: jax.Array
    belt_load: jax.Array
    surface_arg: jax.Array

    @staticmethod
    def make(pressure, *, rim_force=None, rim_free=None, rim_position=None, road_height=np.nan,
             road_at_contact=0.0, friction_on=1.0, reset_shear=0.0, belt_load=None, surface_arg=np.nan, n=None):
        """Levels from per-level values or scalars broadcast to n levels."""
        f = lambda v: jnp.asarray(v, jnp.float64)  # noqa: E731
        vals = [f(pressure), f(road_height), f(road_at_contact), f(friction_on), f(reset_shear), f(surface_arg)]
        vecs = [f(np.zeros(6) if a is None else a) for a in (rim_force, rim_free, rim_position, belt_load)]
        n = n or max([v.shape[0] for v in vals if v.ndim == 1] + [v.shape[0] for v in vecs if v.ndim == 2] + [1])
        vals = [jnp.broadcast_to(v, (n,)) for v in vals]
        vecs = [jnp.broadcast_to(v, (n, 6)) for v in vecs]
        p, h, c, fr, rs, arg = vals
        force, free, pos, belt = vecs
        return Levels(p, force, free, pos, h, c, fr, rs, belt, arg)


def concat(*levels: Levels) -> Levels:
    return jax.tree_util.tree_map(lambda *a: jnp.concatenate(a), *levels)


def inflate_levels(pressure) -> Levels:
    return Levels.make(jnp.atleast_1d(jnp.asarray(pressure, jnp.float64)), road_height=FAR, friction_on=0.0)


def vertical_levels(pressure, loads, *, d_touch=D_TOUCH, friction=True) -> Levels:
    """The touch (road at first contact, rim z held at -d_touch), then loads (L,) N (down)."""
    loads = jnp.atleast_1d(jnp.asarray(loads, jnp.float64))
    fr = 1.0 if friction else 0.0
    touch = Levels.make(pressure, rim_position=np.array([0, 0, -d_touch, 0, 0, 0.0]) * jnp.ones(1)[:, None],
                        road_at_contact=1.0, friction_on=fr, n=1)
    force = jnp.zeros((loads.shape[0], 6)).at[:, 2].set(-loads)
    load = Levels.make(pressure, rim_force=force, rim_free=np.array([0, 0, 1.0, 0, 0, 0]), friction_on=fr,
                       n=loads.shape[0])
    return concat(touch, load)


def lateral_levels(pressure, vertical_load, lateral_loads, *, friction=True, reset_shear=False) -> Levels:
    """Lateral rim forces (L,) N (+y, to the left) at a constant vertical load (N, down), rim y and
    z free. reset_shear: the first lateral level anchors every tread point where it is."""
    return _push_levels(pressure, vertical_load, lateral_loads, 1, friction, reset_shear)


def fore_aft_levels(pressure, vertical_load, forces, *, friction=True) -> Levels:
    """Fore-aft rim forces (L,) N (+x, forward) at a constant vertical load (N, down), rim x and z
    free, its spin held (E14)."""
    return _push_levels(pressure, vertical_load, forces, 0, friction, False)


def _push_levels(pressure, vertical_load, loads, axis, friction, reset_shear) -> Levels:
    """Rim forces (L,) along rim coordinate `axis` (0: x, 1: y) at a constant vertical load, that
    coordinate and z free."""
    push = jnp.atleast_1d(jnp.asarray(loads, jnp.float64))
    n = push.shape[0]
    force = jnp.zeros((n, 6)).at[:, axis].set(push).at[:, 2].set(-jnp.asarray(vertical_load, jnp.float64))
    reset = jnp.zeros(n).at[0].set(1.0 if reset_shear else 0.0)
    return Levels.make(pressure, rim_force=force, rim_free=np.eye(6)[axis] + np.eye(6)[2],
                       friction_on=1.0 if friction else 0.0, reset_shear=reset, n=n)


def belt_levels(pressure, belt_loads) -> Levels:
    """Belt loads (L, 6) (force, moment about the belt's mass centre, like `Drive.belt_load`)."""
    b = jnp.atleast_2d(jnp.asarray(belt_loads, jnp.float64))
    return Levels.make(pressure, road_height=FAR, friction_on=0.0, belt_load=b, n=b.shape[0])


# ---- running ------------------------------------------------------------------------------------
def tread_points(model, y):
    return model.tread_points(model.assemble(y.x, y.q))


def anchors_of(model, y, surface, time=0.0):
    """Friction anchors that continue the tread shear of state y on `surface`."""
    P = tread_points(model, y)
    gap, _, _ = surface.query(P, time)
    return R.Anchors(P, y.bristle, gap)


def first_contact_height(model, y):
    """Road height (m) that just touches the lowest tread point of state y."""
    return jnp.min(tread_points(model, y).z)


def translated(y, dq):
    """State y moved rigidly by dq (3,) (nodes and rim)."""
    return eqx.tree_at(lambda s: (s.x, s.q), y, (y.x + V(dq[0], dq[1], dq[2]), y.q.at[:3].add(dq)))


def tire_on_rim(model, params, setup, y):
    """(6,) generalized force of the tire on the rim at y (N, N m): what a hub dynamometer reads
    (for a held rim, minus the force that holds it)."""
    b = None
    if setup.rigid_belt:
        from .newton import initial_u

        return R.residual_and_rim(model, params, setup, initial_u(model, setup, y))[1]
    return R.residual_and_rim(model, params, setup, R.pack(y.x, y.q, b))[1]


def contact_force(model, params, setup, y):
    """(3,) resultant of the contact forces on the tread at y (N)."""
    F, _, _ = R.contact(model, params, setup, tread_points(model, y))
    return F.sum().array()


class Path(eqx.Module):
    """Solved levels (leading axis L): ys (TireState), infos (StaticInfo), rim_force (L, 6): the
    force on the rim (applied on free DOFs, holding force on held ones), q (L, 6) rim
    coordinates, contact (L, 3) contact resultant (N), road_height (L,) m."""

    ys: TireState
    infos: StaticInfo
    rim_force: jax.Array
    q: jax.Array
    contact: jax.Array
    road_height: jax.Array


def flat_road_at(h, arg=None):
    """The default surface of a level: a still flat road at height h (m) (the level's surface_arg unused)."""
    return FlatRoad(height=h, velocity=jnp.zeros(3))


def run_levels(model, params, y0, levels: Levels, *, rigid_belt=False, opts=NewtonOptions(), road0=FAR,
               surface_at=flat_road_at):
    """Solve the levels in order from state y0 (a TireState). Returns a Path.

    surface_at(h, arg) -> the surface whose top is at height h (m), arg the level's surface_arg: a
    flat road (default), or e.g. a still drum with its cleat placed by arg (E03). The last
    factorization of each level preconditions the next (see `newton`)."""
    def setup_for(lv, y, h):
        road = surface_at(h, lv.surface_arg)
        return R.make_setup(lv.pressure, rim_force=lv.rim_force, rim_free=lv.rim_free, rim_position=lv.rim_position,
                            surface=road, anchors=anchors_of(model, y, road), friction_on=lv.friction_on,
                            belt_load=lv.belt_load if rigid_belt else None, rigid_belt=rigid_belt)

    def step(carry, lv):
        y, h_prev, P, valid = carry
        h = jnp.where(jnp.isnan(lv.road_height), h_prev, lv.road_height)
        h = jnp.where(lv.road_at_contact > 0, first_contact_height(model, y), h)
        y = eqx.tree_at(lambda s: s.bristle, y, jax.tree_util.tree_map(lambda b: b * (1 - lv.reset_shear), y.bristle))
        setup = setup_for(lv, y, h)
        held = lv.rim_free[:3] < 0.5
        guess = translated(y, jnp.where(held, lv.rim_position[:3] - y.q[:3], 0.0))  # moves with the rim
        y1, frim, info, P = solve_static_full(model, params, setup, guess, opts, (P, valid))
        f = jnp.where(lv.rim_free > 0, lv.rim_force, -frim)
        return (y1, h, P, jnp.asarray(True)), (y1, info, f, y1.q, contact_force(model, params, setup, y1), h)

    lv0 = jax.tree_util.tree_map(lambda a: a[0], levels)
    P0 = empty_factor(model, setup_for(lv0, y0, jnp.asarray(road0, jnp.float64)))
    carry = (y0, jnp.asarray(road0, jnp.float64), P0, jnp.asarray(False))
    _, out = jax.lax.scan(step, carry, levels)
    return Path(*out)


def static_path(model, params, pressure, *parts: Levels, rigid_belt=False, opts=NewtonOptions(),
                surface_at=flat_road_at):
    """Inflation from the tire at rest, then `parts` (Levels), in one scan, on the surfaces
    `surface_at(h, arg)` (`run_levels`). Returns a Path whose level 0 is the inflated state."""
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    return run_levels(model, params, y0, concat(inflate_levels(pressure), *parts), rigid_belt=rigid_belt, opts=opts,
                      surface_at=surface_at)
