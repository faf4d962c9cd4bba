"""Time integration (diffrax), the stable step, settling and instability detection.

The integrator is symplectic (semi-implicit) Euler at a constant step, written as a diffrax
solver so that diffeqsolve's loop, saving, events and adjoints are used as they are. diffrax's own
SemiImplicitEuler needs velocity-independent forces; ours are not (viscoelasticity, contact
damping), and the Maxwell branches and bristles are integrated exactly inside the step.

The step is derived, not guessed: dt = safety * (2 / w_max) (sqrt(1 + z^2) - z), the stability
limit of the explicit scheme with damping ratio z at the highest frequency w_max, which is found
by power iteration on M^-1 K (Hessian-vector products of the elastic + pressure potential, Maxwell
branches at their instantaneous stiffness, the tread contact added). The rule lands close to the
real limit (docs/design-notes.md); we use safety 0.8.

A phase runs until its end time, or until it settles (kinetic energy relative to the rim below a
tolerance, after the ramps), or until it blows up (a node faster than V_MAX or a non-finite
value): both are diffrax events, so the run stops at once and says which happened and when.
"""

from typing import ClassVar

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .errors import SimulationError
from .materials import prony_weights
from .physics import rim
from .physics.geometry_ops import V, cross, dot
from .physics.rigid_belt import belt_motion
from .physics.vector_field import evaluate

MAX_STEPS = 2**21  # a bound on steps per phase (~40 s of simulated time at the default step)
V_MAX = 150.0  # m/s: no node of a tire below 100 km/h moves faster; beyond it the run is unstable
SAFETY = 0.8
# Settled needs the free rim DOFs in force balance: |m a| <= RESIDUAL_REL |applied| + RESIDUAL_ABS per DOF
# (N or N m). 0.1 % of the load is far below every reported quantity's own accuracy.
RESIDUAL_REL = 1e-3
RESIDUAL_ABS = 1.0


class SymplecticEuler(diffrax.AbstractSolver):
    """Semi-implicit Euler for TireState with velocity-dependent forces (args = model, params, drive)."""

    term_structure: ClassVar = diffrax.AbstractTerm
    interpolation_cls: ClassVar = diffrax.LocalLinearInterpolation

    def order(self, terms):
        return 1

    def init(self, terms, t0, t1, y0, args):
        return None

    def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
        model, params, drive = args
        upd, _ = evaluate(model, params, drive, t0, y0)
        y1 = y0.advance(upd, t1 - t0, drive)
        return y1, None, dict(y0=y0, y1=y1), None, diffrax.RESULTS.successful

    def func(self, terms, t0, y0, args):
        model, params, drive = args
        return evaluate(model, params, drive, t0, y0)[0]


def kinetic_energy(model, y):
    """Kinetic energy (J) of the free nodes relative to the rim frame, plus the rim's own."""
    v_rel = y.v - rim.frame_velocity(y.q, y.qd, y.x)
    ke = 0.5 * jnp.sum(model.node_mass * dot(v_rel, v_rel))
    M = jnp.concatenate([jnp.full(3, model.rim_mass), model.rim_inertia])
    return ke + 0.5 * jnp.sum(M * y.qd**2)


def force_balanced(model, drive, t, y):
    """The force-residual half of "settled": the free rim DOFs are not accelerating (|m a| small) and
    the settle damping carries no load (|c sum m v_rel| small), each within RESIDUAL_REL of the applied
    load + RESIDUAL_ABS. Kinetic energy alone is not enough: a turning point of a ringing state, or
    the slow overdamped creep of a soft mode, has little kinetic energy while the damping or the
    rim's inertia still holds part of the load (E09 on the coarse ring "settled" with part of its
    lateral force in the damping: docs/design-notes.md)."""
    applied = jnp.abs(drive.rim_force(t))
    if drive.belt_loaded:
        applied = applied + jnp.abs(drive.belt_load(t))
    tol = RESIDUAL_REL * applied + RESIDUAL_ABS
    m_rim = jnp.concatenate([jnp.full(3, model.rim_mass), model.rim_inertia])
    v_rel = y.v - rim.frame_velocity(y.q, y.qd, y.x) * drive.damp_rim_frame
    f_damp = (v_rel * (drive.settle_damping * model.node_mass)).sum().array()
    return jnp.all(jnp.abs(m_rim * y.aq) <= tol) & jnp.all(jnp.abs(f_damp) <= tol[:3])


def observe(model, params, drive, t, y):
    """Reduced outputs saved along a run (a few dozen numbers, never the full state)."""
    upd, d = evaluate(model, params, drive, t, y)
    F, P = d["F"], d["P"]
    belt = belt_motion(y.x, model.x_ref, model.node_mass, model.belt_mask)
    in_contact = d["gap"] < 0
    return dict(
        q=y.q, qd=y.qd,
        contact_force=F.sum().array(),
        contact_moment=cross(P - V(y.q[0], y.q[1], y.q[2]), F).sum().array(),
        n_contact=jnp.sum(in_contact.astype(float)),
        ke=kinetic_energy(model, y),
        dissipated=y.dissipated,
        settle_work=y.settle_work,
        friction_work=y.friction_work,
        pressure=d["pressure"],
        rim_force=drive.rim_force(t),
        tire_on_rim=d["tire_on_rim"],
        volume=d["volume"],
        strain_energy=d["strain_energy"],
        belt_disp=belt[0],
        belt_rot=belt[1],
        drum=y.drum,
    )


def max_frequency(model, params, pressure, n_iter: int = 60):
    """Highest natural frequency (rad/s) of the free nodes, by power iteration on M^-1/2 K M^-1/2.

    K is the Hessian of the elastic (instantaneous: long-term + Maxwell branches) and pressure
    potential at the reference shape; the tread contact is added as if every tread node touched.
    """
    cb = prony_weights(params.relaxation_times).sum()
    K_inst = model.stiffness(params) * (1.0 + cb * model.strain_loss(params))
    q0 = jnp.zeros(6)

    def potential(x):
        X = model.assemble(x, q0)
        d = model.strains(X) - model.s0
        return 0.5 * jnp.sum(K_inst * d * d) - pressure * model.volume(X)

    grad = jax.grad(potential)
    sqrt_m = jnp.sqrt(model.node_mass)

    def matvec(u):
        return jax.jvp(grad, (model.x_ref,), (u / sqrt_m,))[1] / sqrt_m

    vnorm = lambda u: jnp.sqrt(jnp.sum(dot(u, u)))  # noqa: E731

    def body(_, u):
        w = matvec(u)
        return w / vnorm(w)

    u0 = V.of(jax.random.normal(jax.random.PRNGKey(0), (3,) + model.node_mass.shape))  # fixed seed: deterministic dt
    u = jax.lax.fori_loop(0, n_iter, body, u0 / vnorm(u0))
    lam = jnp.sum(dot(u, matvec(u)))
    k_n, _, _ = model.contact_stiffness(params)
    tread_mass = model.node_mass[:, np.asarray(model.tread_cols) - 1].min()
    lam_c = model.n_sub * k_n.max() / tread_mass
    return jnp.sqrt(lam * 1.05 + lam_c)  # 5 %: power iteration approaches lambda_max from below


_max_frequency_jit = eqx.filter_jit(max_frequency)


def stable_step(model, params, pressure, damping_ratio_rate: float = 0.0, safety: float = SAFETY) -> float:
    """Constant step (s) for the explicit scheme; damping_ratio_rate is the mass-proportional
    damping coefficient c (1/s), giving zeta = c / (2 w_max) at the highest mode."""
    w = float(_max_frequency_jit(model, params, jnp.asarray(pressure, float)))
    z = damping_ratio_rate / (2 * w)
    return safety * (2.0 / w) * (np.sqrt(1 + z * z) - z)


class PhaseResult(eqx.Module):
    y: object  # TireState at the end
    t_end: jax.Array
    saved: dict
    settled: jax.Array  # the settle event fired
    blew_up: jax.Array  # the instability event fired
    n_steps: jax.Array
    frames: dict = None  # frame fields at frame_ts (None unless asked for: `jtire run --frames`)


def run_phase(model, params, drive, y0, t0, t1, ts, settle_after, ke_tol, max_steps: int, frame_ts=None,
              adjoint=None):
    """Integrate one phase from t0 to at most t1 (traced scalars); save `observe` at ts.

    Stops early when settled (t >= settle_after and KE < ke_tol) or unstable. Pass
    settle_after = inf to run the whole phase. max_steps is static; with the forward-mode adjoint
    it is only a bound (nothing is allocated per step), so every phase uses MAX_STEPS and shares
    one compiled program. Derivatives are forward mode (jax.jvp / jacfwd over a few parameters; the
    cost: docs/design-notes.md).
    frame_ts: optional times at which to also save whole frames (`jtire.frames.frame_fields`: nodes,
    contact pressure on the phase's own surface, strain-energy density, rim pose); samples after an
    early end are inf. None (the default) adds nothing to the program.
    adjoint: None (forward mode) or a diffrax adjoint for reverse mode (`experiments.program.reverse_mode`:
    RecursiveCheckpointAdjoint, a fixed number of stored states, the rest recomputed).
    """
    def blow(t, y, args, **kw):
        speed = jnp.max(jnp.maximum(jnp.maximum(jnp.abs(y.v.x), jnp.abs(y.v.y)), jnp.abs(y.v.z)))
        return ~(speed < V_MAX) | ~jnp.all(jnp.isfinite(y.q))

    def settled(t, y, args, **kw):
        return (t >= settle_after) & (kinetic_energy(model, y) < ke_tol) & force_balanced(model, drive, t, y)

    fn = lambda t, y, args: observe(model, params, drive, t, y)  # noqa: E731
    subs = [diffrax.SubSaveAt(t1=True), diffrax.SubSaveAt(ts=ts, fn=fn)]
    if frame_ts is not None:
        from .frames import frame_fields

        def frame_fn(t, y, args):
            nodes, p, energy = frame_fields(model, params, y, jnp.nan, t, surface=drive.surface)
            x = jnp.stack([y.x.x, y.x.y, y.x.z], axis=-1)
            return {"t": t, "x": x, "q": y.q, "nodes": nodes, "contact_pressure_Pa": p, "energy_density_J_per_m2": energy}

        subs.append(diffrax.SubSaveAt(ts=frame_ts, fn=frame_fn))
    saveat = diffrax.SaveAt(subs=subs)
    term = diffrax.ODETerm(lambda t, y, args: y)  # unused: the solver evaluates the model itself
    sol = diffrax.diffeqsolve(
        term, SymplecticEuler(), t0, t1, drive.dt, y0, args=(model, params, drive), saveat=saveat,
        stepsize_controller=diffrax.ConstantStepSize(), max_steps=max_steps,
        event=diffrax.Event([blow, settled]), throw=False,
        adjoint=diffrax.ForwardMode() if adjoint is None else adjoint,
    )
    y_end = jax.tree_util.tree_map(lambda a: a[0], sol.ys[0])
    mask = sol.event_mask if sol.event_mask is not None else [jnp.array(False), jnp.array(False)]
    return PhaseResult(y=y_end, t_end=sol.ts[0][0], saved=sol.ys[1], settled=mask[1], blew_up=mask[0],
                       n_steps=sol.stats["num_steps"], frames=sol.ys[2] if frame_ts is not None else None)


# One compiled program per (model, surface type, loop size, drive options), shared by every phase
# and experiment that has them: a phase is the unit of compilation (compiling whole experiments
# costs far more: docs/design-notes.md; phases are reused across all of them).
run_phase_jit = eqx.filter_jit(run_phase)
N_SAVE = 201  # saved samples per phase (static: one size for every phase, so one compilation)


def check_phase(name: str, res: PhaseResult, model, require_settled: bool = True):
    """Host-side verdict on a finished phase: raise SimulationError saying where and when."""
    if bool(res.blew_up) or not np.all(np.isfinite(np.asarray(res.y.x.x))):
        v = np.stack([np.asarray(res.y.v.x), np.asarray(res.y.v.y), np.asarray(res.y.v.z)])
        speed = np.linalg.norm(np.nan_to_num(v, nan=np.inf), axis=0)
        i, j = np.unravel_index(np.argmax(speed), speed.shape)
        from .mesh import PART_NAMES

        part = PART_NAMES[model.node_part_t[j + 1]]
        raise SimulationError(
            f"{name}: unstable at t = {float(res.t_end):.5f} s: node speed {speed[i, j]:.3g} m/s "
            f"(limit {V_MAX} m/s) at segment {i}, section node {j + 1} ({part})")
    if require_settled and not bool(res.settled):
        ke = float(kinetic_energy(model, res.y))
        raise SimulationError(
            f"{name}: did not settle by t = {float(res.t_end):.4f} s: kinetic energy {ke:.3g} J "
            f"above the tolerance (raise the phase's max time or the settle damping)")
