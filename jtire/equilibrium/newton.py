"""solve_static: Newton's method on the static residual, with implicit derivatives.

Method (measured choices: benchmarks/bench_equilibrium.py, docs/speed.md, docs/design-notes.md).
Newton's method with the exact Jacobian, safeguarded by a backtracking line search on the weighted
residual norm (the contact penalty is sharp: a full step can push points deep into the road) and,
when no step lowers the residual, Marquardt damping (J + lam diag|J|). The Jacobian is assembled and
factored (`linalg`: colouring + block-cyclic banded solve) only when needed; in between, a Newton
step is solved by GMRES (`krylov`) with exact Jacobian-vector products, preconditioned by the last
factorization. Assembling costs ~120 Jacobian-vector products and factoring ~1 GFlop on the default
mesh; a GMRES step with a factor one load level old needs only a few products and solves. A new
factorization is made when GMRES needs more than `refresh_after` iterations or fails, when damping
is on, and (`factor_at_solution`) at the converged state, where it is the next load level's
preconditioner and the implicit derivative's Jacobian.
Dynamic relaxation / FIRE (thousands of explicit steps, each as costly as a residual) and a
Krylov method with a cheap preconditioner (the shell's membrane-to-bending stiffness ratio is
~1e4) were not competitive.

Tolerance. Converged when max |r| over the nodes and rim translations (N), and over rim and belt
rotations divided by the tire's outer radius (N m / m), is below rtol * load_scale, load_scale
the largest of the rim force, the belt force and the pressure force on the section (p * section
width * section height: 5.8e4-7.4e4 N at 120 psi). rtol = 1e-6 (~0.07 N): a residual force r
leaves a displacement error of about r / k on the softest stiffness that carries it; on the rim
(~1e6 N/m vertically, ~7e5 N/m laterally) that is ~1e-7 m, 1e-5 of the deflections measured.
A GMRES step is solved to `eta` relative (inexact Newton); convergence is always judged on the
true residual.

Implicit derivatives (`solve_static` is an `eqx.filter_custom_jvp`). At the solution
r(u*, p) = 0 for the inputs p (material, setup with loads, road and anchors, mesh arrays), so
du* = -J^-1 (dr/dp . dp): one forward-mode product of the residual with respect to the inputs
and one solve with the factorization at u* (made by the solve itself when differentiated). The
guess and the preconditioner have no tangent. Under jacfwd the factorization is shared by every
tangent (it depends on primals only); reverse mode works through JAX's transpose of that rule.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.tree_util as jtu
from jaxtyping import Array, Float

from ..errors import SimulationError
from ..state import TireState
from . import linalg as LA
from . import residual as R
from .krylov import gmres

RTOL = 1e-6
LS_C = 1e-4  # Armijo constant on the squared residual norm


class NewtonOptions(eqx.Module):
    """Solver settings. rtol: relative to load_scale; eta: GMRES relative tolerance; lam0: initial
    Marquardt damping (0 = plain Newton). Static: max_iter, max_halvings (line search), krylov
    (GMRES basis size; 0 = factor at every iteration), refresh_after (GMRES iterations that make
    the next iteration refactor), refresh_on_damping (a step the line search shortened makes the
    next iteration refactor; without it only a failed step or a slow GMRES does), factor_at_solution
    (also factor at the solution: the next level's preconditioner; always done when differentiating)."""

    rtol: Float[Array, ""] = eqx.field(default_factory=lambda: jnp.asarray(RTOL, jnp.float64))
    eta: Float[Array, ""] = eqx.field(default_factory=lambda: jnp.asarray(1e-4, jnp.float64))
    lam0: Float[Array, ""] = eqx.field(default_factory=lambda: jnp.asarray(0.0, jnp.float64))
    max_iter: int = eqx.field(static=True, default=40)
    max_halvings: int = eqx.field(static=True, default=12)
    krylov: int = eqx.field(static=True, default=40)
    refresh_after: int = eqx.field(static=True, default=25)
    refresh_on_damping: bool = eqx.field(static=True, default=True)
    factor_at_solution: bool = eqx.field(static=True, default=False)


class StaticInfo(eqx.Module):
    """iterations (Newton steps), factorizations (Jacobians assembled and factored), krylov
    (GMRES iterations in all), residual_max (N, weighted max |r| at the end), tolerance (N),
    load_scale (N), converged (bool)."""

    iterations: Array
    factorizations: Array
    krylov: Array
    residual_max: Array
    tolerance: Array
    load_scale: Array
    converged: Array


def section_size(model):
    """(width, height, outer radius) of the reference section, m."""
    x = model.x_ref
    r = jnp.sqrt(x.x**2 + x.z**2)
    return jnp.max(x.y) - jnp.min(x.y), jnp.max(r) - jnp.min(r), jnp.max(r)


def load_scale(model, setup):
    w, h, _ = section_size(model)
    s = jnp.maximum(jnp.linalg.norm(setup.rim_force[:3]), setup.pressure * w * h)
    if setup.belt_load is not None:
        s = jnp.maximum(s, jnp.linalg.norm(setup.belt_load[:3]))
    return s


def weights(model, setup):
    """(n,) residual weights: 1 on forces, 1 / outer radius on moments (rim and belt rotations)."""
    _, _, R_out = section_size(model)
    T, F = model.n_theta, model.n_s - 2
    rot = jnp.concatenate([jnp.ones(3), jnp.full(3, 1.0 / R_out)])
    return jnp.concatenate([jnp.ones(T * F * 3), rot] + ([rot] if setup.rigid_belt else []))


def _symmetric_border(setup):
    return not (setup.rigid_belt and setup.anchors is not None)


def empty_factor(model, setup):
    """A zero Factor of the right shapes (a placeholder before the first factorization)."""
    st = LA.structure(model, setup.n_border)
    shapes = jax.eval_shape(lambda: LA.factor(LA.BlockMatrix(
        jnp.zeros((st.N, st.G, st.G)), jnp.zeros((st.N, st.G, st.G)), jnp.zeros((st.N, st.G, st.G)),
        jnp.zeros((st.N, st.G, st.nb)), jnp.zeros((st.N, st.nb, st.G)), jnp.zeros((st.nb, st.nb)))))
    return jtu.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), shapes)


def _newton(model, params, setup, u0, P0, P0_valid, opts, factor_at_solution):
    """The Newton loop on the static residual. Returns (u, tire_on_rim (6,), info (7,) floats (zero
    tangents), factor)."""
    st = LA.structure(model, setup.n_border)
    sym = _symmetric_border(setup)

    def factor_of(lin, u, lam, aux):
        return damped_factor(LA.jacobian_from_linear(lin, u, st, sym), lam)

    return newton_krylov(lambda u: R.residual_and_rim(model, params, setup, u), factor_of, u0, P0, P0_valid,
                         weights(model, setup), load_scale(model, setup), opts, st, factor_at_solution, exact=True)


def damped_factor(A, lam):
    """Factor of A + lam diag|A| (Marquardt damping; lam = 0: A itself)."""
    dx, db = LA.diagonal(A)
    return LA.factor(LA.add_diagonal(A, lam * jnp.abs(dx), lam * jnp.abs(db)))


def newton_krylov(fun_rim, factor_of, u0, P0, P0_valid, w, scale, opts, st, factor_at_solution, exact):
    """Newton-Krylov with a lagged factored preconditioner, a backtracking line search and Marquardt
    damping (the module docstring). fun_rim(u) -> (residual (n,), aux: any pytree, e.g. the rim force);
    factor_of(lin, u, lam, aux) -> the Factor preconditioning the linearization `lin` at u (aux: the
    last accepted iterate's, zeros before the first); exact (static): that factor is the Jacobian
    itself, so a fresh one gives the Newton step directly, otherwise every step is GMRES.
    w: (n,) residual weights; scale: the load scale (N). Returns (u, aux, info (7,), factor)."""
    fun = lambda u: fun_rim(u)[0]  # noqa: E731
    tol = opts.rtol * scale
    rmax = lambda r: jnp.max(jnp.abs(w * r))  # noqa: E731
    merit = lambda r: jnp.sum((w * r) ** 2)  # noqa: E731

    def body(c):
        u, r, frim, it, lam, _, P, refresh, n_fac, n_kry = c
        refresh = refresh | (lam > 0) | (opts.krylov == 0)
        # one linearization per iteration serves the assembly (when refactoring) and GMRES
        r, lin = jax.linearize(fun, u)
        P = jax.lax.cond(refresh, lambda _: factor_of(lin, u, lam, frim), lambda _: P, None)

        def direct(_):  # P is J(u) (+ damping): the exact Newton step
            return -LA.solve_flat(st, P, r), jnp.asarray(0, jnp.int32)

        def krylov(_):
            d, k, rel = gmres(lin, lambda v: LA.solve_flat(st, P, v), -r, opts.eta, opts.krylov)
            return d, jnp.where(rel <= 0.5, k, opts.krylov + 1).astype(jnp.int32)  # > krylov: no usable step

        delta, k = jax.lax.cond(refresh, direct, krylov, None) if exact else krylov(None)
        n_fac = n_fac + refresh.astype(jnp.int32)
        phi0 = merit(r)

        # backtracking from the full step (the loop's first pass takes alpha = 1)
        def ls_cond(s):
            alpha, j, phi, _, _, _ = s
            bad = (~jnp.isfinite(phi)) | (phi > (1 - 2 * LS_C * alpha) * phi0)
            return (j == 0) | (bad & (j <= opts.max_halvings))

        def ls_body(s):
            alpha, j, _, _, _, _ = s
            a = jnp.where(j == 0, 1.0, 0.5 * alpha)
            un = u + a * delta
            rn, fn = fun_rim(un)
            return a, j + 1, merit(rn), un, rn, fn

        alpha, _, phi, un, rn, fn = jax.lax.while_loop(ls_cond, ls_body, (jnp.asarray(1.0), 0, jnp.inf, u, r, frim))
        accept = jnp.isfinite(phi) & (phi < phi0) & (k <= opts.krylov)
        u = jnp.where(accept, un, u)
        r = jnp.where(accept, rn, r)
        frim = jax.tree_util.tree_map(lambda a, b: jnp.where(accept, a, b), fn, frim)
        # Marquardt damping: off after full steps, raised when a direct step did not lower the
        # residual (a failed Krylov step first retries with a fresh factorization)
        lam = jnp.where(accept, jnp.where(alpha == 1.0, 0.1 * lam, lam),
                        jnp.where(refresh, jnp.maximum(10.0 * lam, 1e-6), lam))
        lam = jnp.where(lam < 1e-9, 0.0, lam)
        refresh_next = (~accept) | (k > opts.refresh_after)
        if opts.refresh_on_damping:
            refresh_next = refresh_next | (alpha < 1.0)
        return u, r, frim, it + 1, lam, rmax(r) <= tol, P, refresh_next, n_fac, n_kry + jnp.minimum(k, opts.krylov)

    def cond(c):
        _, _, _, it, lam, done, _, _, _, _ = c
        return (~done) & (it < opts.max_iter) & (lam < 1e6)

    # r starts unknown (the first iteration computes it): one residual program fewer to compile,
    # at the price of one Newton step on a guess that already satisfies the tolerance
    aux0 = jax.tree_util.tree_map(lambda a: jnp.zeros(a.shape, a.dtype), jax.eval_shape(fun_rim, u0)[1])
    c0 = (u0, jnp.full(st.n, jnp.inf), aux0, 0, opts.lam0, jnp.asarray(False), P0, ~P0_valid, 0, 0)
    u, r, frim, it, lam, done, P, refresh, n_fac, n_kry = jax.lax.while_loop(cond, body, c0)
    if factor_at_solution:  # every iteration ends with a step, so the last factor is never J(u*)
        _, lin = jax.linearize(fun, u)
        P = factor_of(lin, u, 0.0, frim)
        n_fac = n_fac + 1
    f = lambda a: jnp.asarray(a, jnp.float64)  # noqa: E731
    info = jnp.stack([f(it), f(n_fac), f(n_kry), rmax(r), tol, scale, f(done)])
    return u, frim, info, P


def tangent_parts(prim, tangents):
    """(dyn, static, tangents of dyn) of the primal pytrees: a missing tangent (None) is zeros, so the
    residual's JVP sees one tangent per inexact leaf."""
    def fill(t, p):
        if t is None:
            return jtu.tree_map(lambda a: jnp.zeros_like(a) if eqx.is_inexact_array(a) else None, p)
        return jtu.tree_map(lambda ti, pi: (jnp.zeros_like(pi) if eqx.is_inexact_array(pi) else None) if ti is None
                            else ti, t, p, is_leaf=lambda a: a is None)

    tang = tuple(fill(t, p) for t, p in zip(tangents, prim))
    dyn, static = eqx.partition(prim, eqx.is_inexact_array)
    tdyn, _ = eqx.partition(tang, eqx.is_inexact_array)
    return dyn, static, tdyn


@eqx.filter_custom_jvp
def _solve(model, params, setup, u0, P0, P0_valid, opts):
    return _newton(model, params, setup, u0, P0, P0_valid, opts, opts.factor_at_solution)


@_solve.def_jvp
def _solve_jvp(primals, tangents):
    model, params, setup, u0, P0, P0_valid, opts = primals
    tm, tp, ts = tangents[:3]
    u, frim, info, P = _newton(model, params, setup, u0, P0, P0_valid, opts, True)
    st = LA.structure(model, setup.n_border)
    dyn, static, tdyn = tangent_parts((model, params, setup), (tm, tp, ts))

    def res(d, u_):
        m, p, s = eqx.combine(d, static)
        return R.residual_and_rim(m, p, s, u_)

    _, (dr, _) = jax.jvp(lambda d: res(d, u), (dyn,), (tdyn,))
    du = -LA.solve_flat(st, P, dr)
    _, (_, dfrim) = jax.jvp(res, (dyn, u), (tdyn, du))
    return (u, frim, info, P), (du, dfrim, jnp.zeros_like(info), jtu.tree_map(jnp.zeros_like, P))


def solve_static(model, params, setup, y_guess, opts: NewtonOptions = NewtonOptions(), precond=None):
    """Static equilibrium of `setup` from the guess `y_guess` (a TireState: x and q are used; a
    rigid belt starts from the rigid fit of y_guess's belt nodes).

    Returns (TireState at rest: v = 0, qd = 0, Maxwell stresses 0, bristle = the static tread
    shear, energies 0; StaticInfo). Differentiable (forward and reverse) with respect to params,
    setup and the model's arrays by the implicit function theorem; traceable and vmappable (under
    vmap, lax.cond runs both the Krylov and the direct branch). A failure is in-band
    (`info.converged` False); `check_static` raises on the host.
    """
    y, _, info, _ = solve_static_full(model, params, setup, y_guess, opts, precond)
    return y, info


def solve_static_full(model, params, setup, y_guess, opts: NewtonOptions = NewtonOptions(), precond=None):
    """solve_static that also returns the tire's force on the rim (6,) (N, N m; for held DOFs minus
    the holding force) and the last factorization. precond: (Factor, valid flag) from an earlier
    solve, the first preconditioner. Returns (y, tire_on_rim, info, factor)."""
    u0 = initial_u(model, setup, y_guess)
    if precond is None:
        precond = (empty_factor(model, setup), jnp.asarray(False))
    u, frim, info, P = _solve(model, params, setup, u0, precond[0], precond[1], opts)
    x, q, z = R.state_parts(model, params, setup, u)
    nb = len(params.relaxation_times)
    zero = jnp.zeros((), jnp.float64)
    y = TireState(x, x.map(jnp.zeros_like), q, jnp.zeros(6), jnp.zeros((nb, model.s0.shape[0])), z, zero, zero, zero,
                  jnp.zeros(6), jnp.zeros(2))
    i32 = lambda a: a.astype(jnp.int32)  # noqa: E731
    out = StaticInfo(i32(info[0]), i32(info[1]), i32(info[2]), info[3], info[4], info[5], info[6] > 0.5)
    return y, frim, out, P


def initial_u(model, setup, y):
    """Flat unknowns from a state: x and q as given (held rim DOFs are put at their target by the
    first step), the rigid belt's pose b from the belt nodes' rigid fit (0 on the reference)."""
    b = None
    if setup.rigid_belt:
        from ..physics.rigid_belt import belt_motion

        d, rot = belt_motion(y.x, model.x_ref, model.node_mass, model.belt_mask)
        b = jnp.concatenate([d, rot])
    return R.pack(y.x, y.q, b)


def check_static(info: StaticInfo, where, hint: str = "try smaller load steps"):
    """Host-side verdict: raise SimulationError naming the load level when a solve did not converge.

    info may be batched (a load path): the first failed entry is named. `where`: a text, e.g.
    "E01 load 45.4 kN", or for a path a callable level index -> text.
    """
    import numpy as np

    conv = np.atleast_1d(np.asarray(info.converged))
    if conv.all():
        return
    k = int(np.argmin(conv))
    pick = lambda a: float(np.atleast_1d(np.asarray(a))[k])  # noqa: E731
    name = where(k) if callable(where) else where
    raise SimulationError(
        f"{name}: static equilibrium not found after {int(pick(info.iterations))} Newton iterations: residual "
        f"{pick(info.residual_max):.3g} N above the tolerance {pick(info.tolerance):.3g} N "
        f"(load scale {pick(info.load_scale):.4g} N); {hint}")
