"""Steady rolling in the experiments (E06, E10, E12 with method = "steady", the default).

The tire is inflated, touched down and loaded at the rolling speed (`equilibrium.rolling`), then
solved at each operating point (a slip angle, a longitudinal slip) by continuation from the last:
every level a steady-rolling equilibrium, nothing integrated in time, so there is no settling to
tune and no ripple to average. What a level reports (`equilibrium.rolling.observe`) is stacked per
level; the reductions read the last loaded level and the operating points.
"""

import jax
import numpy as np

from .. import equilibrium as EQ
from ..equilibrium import rolling as ER
from ..errors import UnderResolved
from ..schema import Field
from .static_path import static_summary

# Fields every steady experiment's table has. 8 points per segment: doubling them changes E12's drag
# and lost power by a few percent (bench_steady.py; docs/design-notes.md).
STEADY_FIELDS = {
    "steady_subpoints": Field(int, 1, 2, 32, 8, "contact points per segment along the streamlines (steady)"),
    "steady_load_levels": Field(int, 1, 1, 12, 2, "load levels of the steady loading at speed"),
}
# The two readings of the loss (hub force, lost power over speed) differ by the discretization of the
# flow, most where the patch spans fewest segments (docs/steady-rolling.md, docs/design-notes.md).
# Beyond this the flow is too coarse for either reading and the result is an error.
ENERGY_BALANCE_TOL = 0.15


def check_subpoints(name, table, tire_spec):
    """The steady contact sampling must refine the tire's own (a whole multiple of it)."""
    from ..errors import ConfigError

    k, own = int(table["steady_subpoints"]), int(tire_spec.contact_subpoints)
    if k % own:
        raise ConfigError(f"{name}.steady_subpoints = {k}: must be a multiple of the tire's mesh.contact_subpoints "
                          f"= {own}")
    return k


def omega_guess(outer_radius, speed):
    """A first spin (rad/s) for the levels before the load carries the tire: R0 less 1 cm."""
    return speed / (outer_radius - 0.01)


def loaded(model, params, case, road, speed, *, subpoints, n_load, outer_radius, slip_angle=0.0):
    """The free-rolling loaded path at `speed` (a `equilibrium.rolling.Path`)."""
    return ER.loaded_rolling(model, params, case.pressure, case.load, road, speed, n_load=n_load,
                             slip_angle=slip_angle, omega0=omega_guess(outer_radius, speed), subpoints=subpoints)


def stacked(path, indices=None) -> dict:
    """The path's level observations and Newton infos stacked (leading axis: level), as arrays."""
    idx = range(len(path.obs)) if indices is None else indices
    stack = lambda items: jax.tree_util.tree_map(lambda *a: jax.numpy.stack(a), *[items[i] for i in idx])  # noqa: E731
    return {"levels": stack(path.obs), "infos": stack(path.infos)}


SWEEP_HINT = ("a smaller step did not help; a steady state may not exist there (docs/steady-rolling.md: what it "
               "leaves out), or try method = \"transient\"")


def sweep_name(kind, values, unit_factor, unit):
    """Names of a sweep's levels from their operating points (`Path.values`): "slip angle 6 deg"."""
    vals = np.asarray(values, float)
    return lambda k: f"{kind} {unit_factor * vals[k]:.3g} {unit}"


def sweep_outputs(path, n: int) -> dict:
    """The Newton infos and operating points of the path's levels from n on (a sweep's), for the
    reduction: it names a failed level by its operating point (`sweep_name`)."""
    return {"sweep_infos": stacked(path, range(n, len(path.obs)))["infos"], "sweep_values": jax.numpy.asarray(path.values[n:])}


def level_names(n_load: int) -> list:
    return ["inflation", "first contact"] + [f"load {k}/{n_load}" for k in range(1, n_load + 1)]


def summary(where, infos, names, hint: str = "try smaller load steps") -> tuple:
    """(checks, info) of solved levels (Newton infos stacked per level, host arrays) named `names` (a
    list, or a callable level index -> name); raises SimulationError naming the first level that did
    not converge."""
    infos = jax.tree_util.tree_map(np.asarray, infos)
    name = names if callable(names) else (lambda k: names[k])
    EQ.check_static(infos, lambda k: f"{where}: steady rolling, {name(k)}", hint=hint)
    checks, info = static_summary(infos, method="steady")
    return checks, info | {"levels": int(len(infos.converged))}


def lost_power(level):
    """Every loss of a level (or stacked levels), W: Maxwell branches, tread normal damping, sliding and
    the study's nodal damping (0 unless the tire file turns it on). Traced or host arrays."""
    return (level["power_rubber"] + level["power_contact_damping"] + level["power_friction"]
            + level["power_nodal_damping"])


def losses(level) -> dict:
    """The lost powers (W) of one level: Maxwell branches, tread normal damping, sliding, the study's
    nodal damping, in all."""
    rub, damp, fric, nodal = (float(level[k]) for k in ("power_rubber", "power_contact_damping",
                                                        "power_friction", "power_nodal_damping"))
    return {"viscoelastic_power_W": rub, "tread_damping_power_W": damp, "rubber_power_W": rub + damp,
            "friction_power_W": fric, "nodal_damping_power_W": nodal,
            "dissipated_power_W": rub + damp + fric + nodal}


def require_energy_balance(where, drag, power, speed, n_theta, tol=None) -> float:
    """Relative difference of the hub drag and the lost power over the speed; UnderResolved beyond tol
    (default ENERGY_BALANCE_TOL; `batch.run` then reruns the case on a ring with more segments)."""
    tol = ENERGY_BALANCE_TOL if tol is None else tol
    ref = power / speed
    if ref <= 0:
        return 0.0
    diff = (drag - ref) / ref
    if not abs(diff) <= tol:
        raise UnderResolved(f"{where}: the hub drag {drag:.4g} N and the lost power over the speed {ref:.4g} N "
                            f"differ by {100 * diff:+.2f} % (tolerance {100 * tol:g} %) on {n_theta} segments: the "
                            f"flow is under-resolved (the patch spans too few segments; raise the mesh's n_theta)",
                            n_theta)
    return diff


def level(out, k) -> dict:
    """Level k's observations (host numpy)."""
    return jax.tree_util.tree_map(lambda a: np.asarray(a)[k], out["levels"])


MAX_ANGLE_STEP = 2.0 * np.pi / 180  # rad: continuation steps in slip angle (past the peak the force saturates)
# A continuation step whose Newton fails is retried at half its length, at most this many times per
# operating point (2 deg down to 0.125 deg); beyond that the failure stands and the summary names it.
# Measured on a calibrated tire (E10, 70 psi, 6937.5 kg) the failure at 6 deg is one of the tight
# tolerance, not of the step: loose levels up to 5.99 deg converge (docs/steady-rolling.md).
MAX_HALVINGS = 4


def continue_to(path, setup_at, start, end, name_at, *, max_step, max_halvings=MAX_HALVINGS):
    """Solve `path` from the operating point `start` (solved already) to `end` in steps of at most
    `max_step`, the levels before `end` loosely (guesses, not reported). setup_at(b): the level's
    setup at the value b; name_at(b): its name. A step that does not converge is undone and the step
    halved for the rest of the way; after `max_halvings` halvings a failed level is kept, for the
    summary to report. Returns (observations at `end`, converged: True, False,
    or None where the solve is traced and there is nothing to judge)."""
    if end == start:  # the point itself solved again: no step to halve
        max_halvings = 0
    n = max(1, int(np.ceil(abs(end - start) / max_step - 1e-9)))
    nominal = (end - start) / n
    b, step, failures = start, nominal, 0
    while True:
        last = abs(end - b) <= abs(step) * (1 + 1e-9)
        b1 = end if last else b + step
        ob, ok = path.attempt(setup_at(b1), name_at(b1), loose=not last, keep_failure=failures >= max_halvings,
                              value=b1)
        failed = ok is not None and not ok
        if failed and failures < max_halvings:
            step, failures = step / 2, failures + 1
            continue
        if last or failed:
            return ob, (None if ok is None else not failed)
        b = b1


def sweep_through(path, setup_at, start, points, name_at, *, max_step=None):
    """Observations at each of `points` in turn, continued from `start` (solved already) by
    `continue_to` (steps of at most max_step; None: one step per point). A point that still fails
    ends the sweep: the points beyond it repeat its observations. Returns (observations, flags:
    solved True, False, or None where traced), one per point."""
    obs, solved, failed, prev = [], [], None, start
    for p in points:
        if failed is not None:
            obs.append(failed)
            solved.append(False)
            continue
        step = abs(p - prev) if max_step is None else max_step
        ob, ok = continue_to(path, setup_at, prev, p, name_at, max_step=step if step > 0 else 1.0)
        obs.append(ob)
        solved.append(ok)
        failed = ob if ok is False else None
        prev = p
    return obs, solved


def slip_angle_sweep(path, angles, speed, load, *, subpoints, max_step=MAX_ANGLE_STEP) -> tuple:
    """Observations at each SAE slip angle of `angles` (rad, any order), continued from the loaded
    free-rolling state of `path` at 0: outwards through the positive angles, then again from 0 through
    the negative ones (`sweep_through`: steps of at most `max_step`, halved where Newton fails; the
    levels between are solved loosely, not reported; a side stops at an angle that still fails).
    Returns (one observation dict per angle, one flag per angle: solved True, False, or None where
    traced), in the order given."""
    start = (path.u, path.P, path.valid)

    def setup_at(b):
        return ER.setup_of(path.pressure, path.road.surface(path.height, ER.road_velocity(speed, b)),
                           omega=path.q[4], rim_free=ER.LOADED, load=load, subpoints=subpoints)

    out, solved = {}, {}
    for sign in (1.0, -1.0):
        path.u, path.P, path.valid = start
        side = sorted((float(v) for v in angles if v * sign > 0 or (v == 0 and sign > 0)), key=abs)
        obs, ok = sweep_through(path, setup_at, 0.0, side, lambda b: f"slip angle {np.degrees(b):.3g} deg",
                                max_step=max_step)
        out |= dict(zip(side, obs))
        solved |= dict(zip(side, ok))
    return [out[float(a)] for a in angles], [solved[float(a)] for a in angles]
