"""Right-preconditioned GMRES with a fixed basis size, for Newton steps with a lagged factorization.

The Newton solver factors the Jacobian only now and then; in between, a step solves J(u) d = -r
with exact Jacobian-vector products and the older factorization as preconditioner (a factor one
load level old brings GMRES to 1e-10 in a few iterations: docs/design-notes.md). Right
preconditioning (x = M^-1 y) minimizes the true residual |J d + r|, the quantity the inexact
Newton method needs; the basis vectors' preconditioned images are kept (as in flexible GMRES) so
the solution costs no extra preconditioner solve. lineax's GMRES preconditions on the left and
restarts; a small one here also reports its iteration count, which decides when to refactor.
"""

import jax
import jax.numpy as jnp


def gmres(matvec, psolve, b, rtol, m: int):
    """Solve matvec(x) = b to |matvec(x) - b| <= rtol |b| with at most m iterations (static).

    matvec, psolve: (n,) -> (n,); psolve applies the preconditioner's inverse. Returns (x,
    iterations, relative residual reached).
    """
    n = b.shape[0]
    beta = jnp.linalg.norm(b)
    safe = jnp.where(beta > 0, beta, 1.0)
    V = jnp.zeros((m + 1, n), b.dtype).at[0].set(b / safe)
    Z = jnp.zeros((m, n), b.dtype)
    Rm = jnp.zeros((m + 1, m), b.dtype)  # the Hessenberg matrix, rotated to upper triangular
    cs = jnp.zeros(m, b.dtype)
    sn = jnp.zeros(m, b.dtype)
    g = jnp.zeros(m + 1, b.dtype).at[0].set(beta)

    def cond(c):
        j, _, _, _, _, _, g = c
        return (j < m) & (jnp.abs(g[j]) > rtol * beta)

    def body(c):
        j, V, Z, Rm, cs, sn, g = c
        z = psolve(V[j])
        w = matvec(z)
        # classical Gram-Schmidt, twice (rows of V beyond j are zero, so they add nothing)
        h = V @ w
        w = w - h @ V
        h2 = V @ w
        w = w - h2 @ V
        h = h + h2
        hn = jnp.linalg.norm(w)
        V = V.at[j + 1].set(w / jnp.where(hn > 0, hn, 1.0))
        col = h.at[j + 1].set(hn)

        def rot(i, col):  # the earlier Givens rotations
            a, bb = col[i], col[i + 1]
            return col.at[i].set(cs[i] * a + sn[i] * bb).at[i + 1].set(-sn[i] * a + cs[i] * bb)

        col = jax.lax.fori_loop(0, j, rot, col)
        a, bb = col[j], col[j + 1]
        den = jnp.sqrt(a * a + bb * bb)
        c_, s_ = jnp.where(den > 0, a / den, 1.0), jnp.where(den > 0, bb / den, 0.0)
        col = col.at[j].set(den).at[j + 1].set(0.0)
        gj = g[j]
        g = g.at[j].set(c_ * gj).at[j + 1].set(-s_ * gj)
        return j + 1, V, Z.at[j].set(z), Rm.at[:, j].set(col), cs.at[j].set(c_), sn.at[j].set(s_), g

    j, V, Z, Rm, cs, sn, g = jax.lax.while_loop(cond, body, (0, V, Z, Rm, cs, sn, g))
    used = jnp.arange(m) < j
    R = jnp.where(used[:, None] & used[None, :], Rm[:m], jnp.eye(m, dtype=b.dtype))
    y = jax.scipy.linalg.solve_triangular(R, jnp.where(used, g[:m], 0.0), lower=False)
    return y @ Z, j, jnp.abs(g[j]) / safe


def gmres_restarted(matvec, psolve, b, rtol, m: int, max_restarts: int):
    """gmres(m) restarted from its last iterate until |matvec(x) - b| <= rtol |b| or max_restarts
    cycles (static). Returns x."""
    beta = jnp.linalg.norm(b)

    def cond(c):
        k, _, res = c
        return (k < max_restarts) & (res > rtol * beta)

    def body(c):
        k, x, _ = c
        r = b - matvec(x)
        dx, _, _ = gmres(matvec, psolve, r, rtol * beta / jnp.maximum(jnp.linalg.norm(r), 1e-300), m)
        x = x + dx
        return k + 1, x, jnp.linalg.norm(b - matvec(x))

    _, x, _ = jax.lax.while_loop(cond, body, (0, jnp.zeros_like(b), jnp.asarray(jnp.inf, b.dtype)))
    return x
