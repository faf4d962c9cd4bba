"""solve_rolling: Newton-Krylov on the steady-rolling residual, with implicit derivatives.

The steady residual (`rolling_residual`) couples each segment to the whole ring upstream of it (the
Maxwell stresses and the tread shear are carried along the streamlines), so its Jacobian is not
banded and is never assembled. Each Newton step is solved by GMRES with exact Jacobian-vector
products, preconditioned by a factored banded approximation: the static Jacobian at the current
state (long-term moduli, the tread held by friction anchors where it now is: its stick and slip
stiffness), plus the inertia of the flowing material, with the rim's rows and columns taken exactly
from the steady linearization where the static one has no counterpart: the spin's column (`linalg.with_column`). The viscous and transport couplings the
approximation leaves out are a fraction of the elastic ones (loss factors ~0.1), so GMRES needs few
iterations. The loop itself is the static solver's (`newton.newton_krylov`: line search, lagged
refactorization, convergence judged on the true residual at the same tolerance).

Implicit derivatives: at the solution r(u*, p) = 0, so du* = -J^-1 (dr/dp . dp); the solve with J is
restarted GMRES with the same preconditioner inside `lax.custom_linear_solve`, which JAX transposes
(the transposed products and preconditioner), so forward mode (jacfwd) and reverse mode (grad,
jacrev) both work through `solve_rolling`. (lineax's GMRES stagnated on some transposed solves.)
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.tree_util as jtu

from . import linalg as LA
from . import residual as R
from . import rolling_residual as RR
from .krylov import gmres_restarted
from .newton import (NewtonOptions, StaticInfo, damped_factor, empty_factor, load_scale, newton_krylov,
                     tangent_parts, weights)

IMPLICIT_RTOL = 1e-10  # relative residual of the derivative solves: tangents to ~1e-9, far below FD noise
IMPLICIT_BASIS, IMPLICIT_RESTARTS = 40, 10


def preconditioner_residual(model, params, setup, u, z):
    """The banded approximation's residual around the state u: the static residual with the tread
    anchored where it is, sheared by z (the steady shear at the fine points, V of (N,)), the spin
    angle free (its row: the rim's elastic torque), plus the inertia of the flow at u's spin."""
    x, q, omega = RR._unknowns(model, setup, u)
    omega = jax.lax.stop_gradient(omega)
    # the model's own contact points (the fine streamline sampling's every k-th): cheaper to assemble
    P = model.tread_points(model.assemble(x, q))
    k = setup.subpoints // model.n_sub
    coarse = lambda a: a.reshape(model.n_theta, setup.subpoints, -1)[:, ::k].reshape(-1)  # noqa: E731
    anchors = jax.lax.stop_gradient(R.Anchors(P, z.map(coarse), setup.surface.query(P, 0.0)[0]))
    ss = R.StaticSetup(setup.pressure, setup.rim_force, setup.rim_free.at[RR.SPIN].set(1.0), setup.rim_position,
                       setup.surface, setup.gravity, jnp.zeros(()), setup.friction_on, anchors)
    dtheta = 2 * jnp.pi / model.n_theta

    spin = u.shape[0] - 6 + RR.SPIN
    u_spin = jax.lax.stop_gradient(u[spin])

    def fun(v):
        x_ = R.unpack(model, v, False)[0]
        lap = (x_.roll(-1, 0) - x_ * 2.0 + x_.roll(1, 0)) * (model.node_mass * omega**2 / dtheta**2)
        # the spin slot as a spin angle about u's state (0 there): its row is the rim's elastic torque
        return R.residual(model, params, ss, v.at[spin].add(-u_spin)) + R.pack(lap, jnp.zeros(6))

    return fun


def _rolling_newton(model, params, setup, u0, P0, P0_valid, opts, factor_at_solution):
    st = LA.structure(model, setup.n_border)
    spin = st.T * st.B + RR.SPIN
    e_spin = jnp.zeros(st.n).at[spin].set(1.0)

    def factor_of(lin, u, lam, aux):
        # ring and rim rows from the static approximation (symmetric border); the spin's column exact
        _, lin_pre = jax.linearize(preconditioner_residual(model, params, setup, u, aux[1]), u)
        A = LA.with_column(LA.jacobian_from_linear(lin_pre, u, st, True), st, RR.SPIN, lin(e_spin))
        return damped_factor(A, lam)

    def fun_aux(u):
        r, d = RR.rolling_forces(model, params, setup, u)
        return r, (d["tire_on_rim"], d["z"])

    return newton_krylov(fun_aux, factor_of, u0, P0, P0_valid, weights(model, setup), load_scale(model, setup),
                         opts, st, factor_at_solution, exact=False)


@eqx.filter_custom_jvp
def _solve(model, params, setup, u0, P0, P0_valid, opts):
    u, _, info, P = _rolling_newton(model, params, setup, u0, P0, P0_valid, opts, opts.factor_at_solution)
    return u, info, P


def implicit_solve(model, params, setup, u, P, b):
    """J(u)^-1 b for the steady residual's Jacobian at u: restarted GMRES preconditioned by the factor
    P. A `lax.custom_linear_solve`, so JAX differentiates and transposes it as the linear solve it is:
    reverse mode solves J^T with the transposed products and preconditioner."""
    st = LA.structure(model, setup.n_border)
    _, lin = jax.linearize(lambda v: RR.rolling_residual(model, params, setup, v), u)
    pre = lambda v: LA.solve_flat(st, P, v)  # noqa: E731
    pre_t = lambda v: jax.linear_transpose(pre, v)(v)[0]  # noqa: E731

    def solve(mv, rhs):
        return gmres_restarted(mv, pre, rhs, IMPLICIT_RTOL, IMPLICIT_BASIS, IMPLICIT_RESTARTS)

    def transpose_solve(vm, rhs):
        return gmres_restarted(vm, pre_t, rhs, IMPLICIT_RTOL, IMPLICIT_BASIS, IMPLICIT_RESTARTS)

    return jax.lax.custom_linear_solve(lin, b, solve, transpose_solve)


@_solve.def_jvp
def _solve_jvp(primals, tangents):
    model, params, setup, u0, P0, P0_valid, opts = primals
    tm, tp, ts = tangents[:3]
    u, _, info, P = _rolling_newton(model, params, setup, u0, P0, P0_valid, opts, True)
    dyn, static, tdyn = tangent_parts((model, params, setup), (tm, tp, ts))

    def res(d):
        m, p, s = eqx.combine(d, static)
        return RR.rolling_residual(m, p, s, u)

    _, dr = jax.jvp(res, (dyn,), (tdyn,))
    du = -implicit_solve(model, params, setup, u, P, dr)
    return (u, info, P), (du, jnp.zeros_like(info), jtu.tree_map(jnp.zeros_like, P))


def solve_rolling(model, params, setup, u_guess, opts: NewtonOptions = NewtonOptions(), precond=None):
    """Steady rolling of `setup` from the flat unknowns u_guess (`residual.pack(x, q)` with q[4] the
    spin guess). precond: (Factor, valid flag) from an earlier solve. Returns (u, StaticInfo, factor);
    u is differentiable (forward and reverse) with respect to params, setup and the model's arrays."""
    if precond is None:
        precond = (empty_factor(model, R.make_setup(setup.pressure)), jnp.asarray(False))
    u, info, P = _solve(model, params, setup, u_guess, precond[0], precond[1], opts)
    i32 = lambda a: a.astype(jnp.int32)  # noqa: E731
    return u, StaticInfo(i32(info[0]), i32(info[1]), i32(info[2]), info[3], info[4], info[5], info[6] > 0.5), P
