"""The static Jacobian as a block-cyclic banded matrix with a dense border, and its direct solve.

Structure (`Structure`, static). The free nodes form a ring of T segments of B = 3 (S-2) DOFs.
A force term couples segments i and j only when some term reads both: hinges and shear quads
reach one or two segments, a contact point between segments i and i+1 reads the normals of
i-1 .. i+2, so |i - j| <= d with d = 3 (2 with one contact point per segment), cyclically. The
rim (6) and, with a rigid belt, the belt pose (6) are a border of nb DOFs coupled to every
segment.

Assembly (`jacobian`): columns by forward-mode products with a segment colouring (segments of one
colour are >= 2d+1 apart, so their columns never share a row block): n_colours * B + nb
Jacobian-vector products of the residual, all from one `jax.linearize` and one `vmap`. The border
rows come from nb products with the transposed linearization (the columns of a colour sum over
the whole ring in the border rows). For the default mesh (T = 64, B = 45, d = 3): 8 colours,
366 products instead of 2,886.

Solve (`factor`, `solve`): segments are grouped into super-blocks of g >= d segments (padded with
identity DOFs to a multiple of g, at most g - d of them), which makes the ring block-tridiagonal and cyclic in blocks of
G = g B. Super-block 0 joins the border ("outer" DOFs, W = G + nb); the chain 1 .. N-1 is
eliminated by block LU (partial pivoting inside each block, none across blocks: the Jacobian of a
stable equilibrium is close to symmetric positive definite), then the W x W Schur complement is
factored densely. The factor keeps explicit block inverses, so a solve is a few dozen small
matrix products; one factorization serves any number of right-hand sides (Newton and Krylov
steps, implicit derivatives). Cost for the default mesh: ~1 GFlop per factorization, ~5 MFlop per
solve.
"""

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np


class Structure(NamedTuple):
    """Static layout of the Jacobian (Python ints and numpy arrays only)."""

    T: int  # segments
    B: int  # DOFs per segment
    nb: int  # border DOFs
    d: int  # coupling distance in segments
    g: int  # segments per super-block
    N: int  # super-blocks (padded ring: N g >= T)
    colour: tuple  # (T,) colour of every segment
    n_colours: int
    F: int  # free nodes per segment
    dj: int  # coupling distance along the section (nodes)

    @property
    def cj(self) -> int:
        """Colours along the section: nodes >= 2 dj + 1 apart share one."""
        return min(2 * self.dj + 1, self.F)

    @property
    def n_seeds(self) -> int:
        return self.n_colours * self.cj * 3 + self.nb

    @property
    def G(self) -> int:
        return self.g * self.B

    @property
    def n(self) -> int:
        return self.T * self.B + self.nb


def structure(model, nb: int) -> Structure:
    T, B = model.n_theta, 3 * (model.n_s - 2)
    d = 3 if model.n_sub > 1 else 2
    spacing = 2 * d + 1
    # colour i mod c with the fewest colours c that keep equal colours >= spacing apart round the ring
    dist = lambda i, j: min(abs(i - j), T - abs(i - j))  # noqa: E731
    c = next(c for c in range(min(spacing, T), T + 1)
             if all(dist(i, j) >= spacing for i in range(T) for j in range(i + c, T, c)))
    colour = [i % c for i in range(T)]
    # super-blocks of g >= d segments; the padding (identity DOFs closing the last block) must
    # leave >= d real segments there, or the wrap would couple non-neighbouring super-blocks
    g = d
    while (-T) % g > g - d:
        g += 1
    N = -(-T // g)
    if N < 3:  # a ring too short to be a chain of blocks: one dense block
        g, N = T, 1
    return Structure(T, B, nb, d, g, N, tuple(colour), max(colour) + 1, model.n_s - 2, 2)


def _seeds(st: Structure):
    """(n_seeds, n) tangent seeds: one per node colour (segment colour, section colour) and
    component, then one per border DOF."""
    T, F, nb = st.T, st.F, st.nb
    ci = np.asarray(st.colour)[:, None] == np.arange(st.n_colours)[None, :]  # (T, n_colours)
    cj = (np.arange(F) % st.cj)[:, None] == np.arange(st.cj)[None, :]  # (F, cj)
    S = np.einsum("ta,fb,ce->abetfc", ci, cj, np.eye(3)).reshape(-1, T * F * 3)
    top = np.concatenate([S, np.zeros((S.shape[0], nb))], axis=1)
    bottom = np.concatenate([np.zeros((nb, T * F * 3)), np.eye(nb)], axis=1)
    return np.concatenate([top, bottom], axis=0)


def _gather_plan(st: Structure):
    """Static indices turning the compressed columns into the padded super-block diagonal, upper
    and lower blocks: for super-block pair (I, I + off) and local segments (a, b), the colour of
    the column segment, the row segment, and whether the pair is within the coupling distance."""
    T, g, N, d = st.T, st.g, st.N, st.d
    col = np.asarray(st.colour)
    plans = []
    for off in (0, 1, -1):
        c_idx = np.zeros((N, g, g), np.int32)
        r_idx = np.zeros((N, g, g), np.int32)
        mask = np.zeros((N, g, g))
        for I in range(N):
            J = (I + off) % N
            for a in range(g):
                for b in range(g):
                    sa, sb = I * g + a, J * g + b
                    if sa < T and sb < T and min(abs(sa - sb), T - abs(sa - sb)) <= d and (N > 1 or off == 0):
                        c_idx[I, a, b], r_idx[I, a, b], mask[I, a, b] = col[sb], sa, 1.0
        plans.append((c_idx, r_idx, mask))
    return plans


class BlockMatrix(eqx.Module):
    """The padded Jacobian: D, Up, Lo (N, G, G) = A[I, I], A[I, I+1], A[I, I-1] (cyclic);
    Cb (N, G, nb) border columns, Rb (N, nb, G) border rows, E (nb, nb) the corner."""

    D: jax.Array
    Up: jax.Array
    Lo: jax.Array
    Cb: jax.Array
    Rb: jax.Array
    E: jax.Array


def jacobian(fun, u, st: Structure, symmetric_border: bool = True):
    """(fun(u), BlockMatrix of d fun / d u) for a residual with the structure `st`."""
    r, lin = jax.linearize(fun, u)
    return r, jacobian_from_linear(lin, u, st, symmetric_border)


def jacobian_from_linear(lin, u, st: Structure, symmetric_border: bool = True):
    """BlockMatrix of the linear map `lin` (a linearization at u).

    symmetric_border: the border rows are the transposed border columns (exact when only forces
    with a potential couple the border to the ring: always for the rim; for a rigid belt unless
    friction acts on its tread). Otherwise they come from the transposed linearization
    (reverse-over-reverse: as long to compile as the columns).
    """
    T, B, nb, g, N = st.T, st.B, st.nb, st.g, st.N
    cols = jax.vmap(lin)(jnp.asarray(_seeds(st)))  # (n_seeds, n): row k = J seed_k
    if symmetric_border:
        rows = jnp.concatenate([cols[st.n_seeds - nb:, : T * B], cols[st.n_seeds - nb:, T * B:].T], axis=1)
    else:
        rows = jax.vmap(jax.linear_transpose(lin, u))(jnp.eye(st.n)[T * B:])[0]  # (nb, n)
    F, cj = st.F, st.cj
    # comp[colour, section colour, component, row segment, row dof]
    comp = cols[: st.n_seeds - nb, : T * B].reshape(st.n_colours, cj, 3, T, B)
    comp = comp[:, np.arange(F) % cj]  # (n_colours, F, 3, T, B): column dof (node, comp) of its colour
    jr = np.repeat(np.arange(F), 3)
    near = jnp.asarray((np.abs(np.arange(F)[:, None, None] - jr[None, None, :]) <= st.dj).astype(float))  # (F, 1, B)
    comp = comp * near[:, :, None, :]
    blocks = []
    for c_idx, r_idx, mask in _gather_plan(st):
        blk = comp[c_idx, :, :, r_idx, :]  # (N, g, g, F, 3, B): [.., col node, col comp, row dof]
        blk = blk.reshape(N, g, g, B, B) * jnp.asarray(mask)[..., None, None]
        blocks.append(jnp.transpose(blk, (0, 1, 4, 2, 3)).reshape(N, g * B, g * B))
    D, Up, Lo = blocks
    pad = N * g - T
    # identity on the padding DOFs (segments T .. N g - 1 of the last super-block)
    eye_pad = np.zeros((N, g * B))
    eye_pad[-1, (g - pad) * B:] = 1.0 if pad else 0.0
    D = D + jax.vmap(jnp.diag)(jnp.asarray(eye_pad))
    Cb, Rb, E = _border(st, cols[st.n_seeds - nb:], rows)
    return BlockMatrix(D, Up, Lo, Cb, Rb, E)


def _border(st: Structure, cols, rows):
    """Padded border blocks (Cb, Rb, E) from the border's columns and rows, each (nb, n)."""
    T, B, nb, g, N = st.T, st.B, st.nb, st.g, st.N
    pad = N * g - T
    padv = lambda a: jnp.concatenate([a, jnp.zeros((pad * B,) + a.shape[1:], a.dtype)]) if pad else a  # noqa: E731
    Cb = padv(cols[:, : T * B].T).reshape(N, g * B, nb)
    Rb = jnp.transpose(padv(rows[:, : T * B].T).reshape(N, g * B, nb), (0, 2, 1))
    return Cb, Rb, rows[:, T * B:]


def with_column(A: BlockMatrix, st: Structure, k: int, col) -> BlockMatrix:
    """A with its border column k replaced by `col` (n,), e.g. an exact Jacobian column (one product)
    in an approximate matrix."""
    T, B, g, N = st.T, st.B, st.g, st.N
    pad = N * g - T
    ring = jnp.concatenate([col[: T * B], jnp.zeros(pad * B, col.dtype)]).reshape(N, g * B)
    return eqx.tree_at(lambda a: (a.Cb, a.E), A, (A.Cb.at[:, :, k].set(ring), A.E.at[:, k].set(col[T * B:])))


def add_diagonal(A: BlockMatrix, dx, db):
    """A + diag: dx (N, G) on the ring (padded layout), db (nb,) on the border."""
    return eqx.tree_at(lambda a: (a.D, a.E), A,
                       (A.D + jax.vmap(jnp.diag)(dx), A.E + jnp.diag(db)))


def diagonal(A: BlockMatrix):
    """(N, G) ring and (nb,) border diagonals."""
    return jnp.diagonal(A.D, axis1=1, axis2=2), jnp.diag(A.E)


def to_padded(st: Structure, v):
    """(n,) -> ((N, G) ring, (nb,) border)."""
    T, B, pad = st.T, st.B, st.N * st.g - st.T
    ring = jnp.concatenate([v[: T * B], jnp.zeros(pad * B, v.dtype)]).reshape(st.N, st.G)
    return ring, v[T * B:]


def from_padded(st: Structure, ring, border):
    return jnp.concatenate([ring.reshape(-1)[: st.T * st.B], border])


class Factor(eqx.Module):
    """The factored matrix, as explicit block inverses (a solve is then matrix products only,
    and every leaf is a float array, so a factor can pass through a custom JVP and a scan)."""

    Sinv: jax.Array  # (N-1, G, G) inverses of the chain's pivot blocks S_k
    M: jax.Array  # (N-1, G, G) S_k^-1 Up_k (the last one zero)
    Lo: jax.Array  # (N-1, G, G) chain sub-diagonal blocks (the first one zero)
    Y: jax.Array  # (N-1, G, W) chain^-1 times the outer columns
    Rw: jax.Array  # (N-1, W, G) outer rows on the chain
    Zinv: jax.Array  # (W, W) inverse of the outer DOFs' Schur complement


def _inv(A):
    lu_piv = jsl.lu_factor(A)
    return jsl.lu_solve(lu_piv, jnp.eye(A.shape[-1], dtype=A.dtype))


def _chain_sweep(Sinv, M, Lo, F):
    """Solve the chain's block-tridiagonal system for right-hand sides F (N-1, G, K)."""
    def fwd(gp, xs):
        si, lo, f = xs
        gk = si @ (f - lo @ gp)
        return gk, gk

    _, gs = jax.lax.scan(fwd, jnp.zeros_like(F[0]), (Sinv, Lo, F))

    def bwd(yn, xs):
        gk, m = xs
        yk = gk - m @ yn
        return yk, yk

    _, ys = jax.lax.scan(bwd, jnp.zeros_like(F[0]), (gs, M), reverse=True)
    return ys


def factor(A: BlockMatrix) -> Factor:
    N, G = A.D.shape[0], A.D.shape[1]
    nb = A.E.shape[0]
    if N == 1:
        e = jnp.zeros((0, G, G))
        Z = jnp.block([[A.D[0], A.Cb[0]], [A.Rb[0], A.E]])
        return Factor(e, e, e, jnp.zeros((0, G, G + nb)), jnp.zeros((0, G + nb, G)), _inv(Z))
    D, Up, Lo = A.D[1:], A.Up[1:], A.Lo[1:]
    k = jnp.arange(1, N)
    first, last = (k == 1)[:, None, None], (k == N - 1)[:, None, None]
    to0 = jnp.where(first, Lo, 0.0) + jnp.where(last, Up, 0.0)  # A[k, 0]
    from0 = jnp.where(first, A.Up[0][None], 0.0) + jnp.where(last, A.Lo[0][None], 0.0)  # A[0, k]
    Cw = jnp.concatenate([to0, A.Cb[1:]], axis=2)  # (N-1, G, W)
    Rw = jnp.concatenate([from0, A.Rb[1:]], axis=1)  # (N-1, W, G)
    # chain block LU: S_k = D_k - Lo_k S_{k-1}^-1 Up_{k-1}; the first chain block's Lo points to
    # block 0 and the last one's Up too (both outer), so they leave the chain
    Lo_c = Lo.at[0].set(0.0)
    Up_c = Up.at[-1].set(0.0)

    def step(Mp, xs):
        d, lo, up = xs
        si = _inv(d - lo @ Mp)
        m = si @ up
        return m, (si, m)

    _, (Sinv, M) = jax.lax.scan(step, jnp.zeros((G, G)), (D, Lo_c, Up_c))
    Y = _chain_sweep(Sinv, M, Lo_c, Cw)
    Ew = jnp.block([[A.D[0], A.Cb[0]], [A.Rb[0], A.E]])
    Z = Ew - jnp.einsum("kwg,kgv->wv", Rw, Y)
    return Factor(Sinv, M, Lo_c, Y, Rw, _inv(Z))


def solve(fac: Factor, ring, border):
    """Solve A v = rhs for rhs given padded: ring (N, G[, K]), border (nb[, K]). Same layout out."""
    vec = ring.ndim == 2
    if vec:
        ring, border = ring[..., None], border[..., None]
    h = jnp.concatenate([ring[0], border], axis=0)  # outer rhs (W, K)
    G = ring.shape[1]
    if fac.Sinv.shape[0] == 0:
        w = fac.Zinv @ h
        out_ring, out_b = w[None, :G], w[G:]
    else:
        t = _chain_sweep(fac.Sinv, fac.M, fac.Lo, ring[1:])
        w = fac.Zinv @ (h - jnp.einsum("kwg,kgj->wj", fac.Rw, t))
        y = t - jnp.einsum("kgw,wj->kgj", fac.Y, w)
        out_ring = jnp.concatenate([w[None, :G], y], axis=0)
        out_b = w[G:]
    if vec:
        return out_ring[..., 0], out_b[..., 0]
    return out_ring, out_b


def solve_flat(st: Structure, fac: Factor, v):
    """Solve with a flat right-hand side (n,) or (n, K)."""
    if v.ndim == 2:
        ring, border = jax.vmap(lambda a: to_padded(st, a), in_axes=1, out_axes=(2, 1))(v)
        out_r, out_b = solve(fac, ring, border)
        return jax.vmap(lambda a, b: from_padded(st, a, b), in_axes=(2, 1), out_axes=1)(out_r, out_b)
    return from_padded(st, *solve(fac, *to_padded(st, v)))


def to_dense(st: Structure, A: BlockMatrix):
    """(n, n) dense matrix of a BlockMatrix (for tests and small problems)."""
    N, G, nb = st.N, st.G, st.nb
    D = jnp.zeros((N * G + nb, N * G + nb))
    for I in range(N):
        rows = slice(I * G, (I + 1) * G)
        D = D.at[rows, I * G:(I + 1) * G].add(A.D[I])
        if N > 1:
            J, K = (I + 1) % N, (I - 1) % N
            D = D.at[rows, J * G:(J + 1) * G].add(A.Up[I]).at[rows, K * G:(K + 1) * G].add(A.Lo[I])
        D = D.at[rows, N * G:].set(A.Cb[I]).at[N * G:, rows].set(A.Rb[I])
    D = D.at[N * G:, N * G:].set(A.E)
    keep = jnp.asarray(np.concatenate([np.arange(st.T * st.B), N * G + np.arange(nb)]))
    return D[keep][:, keep]
