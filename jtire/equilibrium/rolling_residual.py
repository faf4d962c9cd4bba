"""The steady-rolling residual: the tire's force balance in steady-state transport (Eulerian) form.

The mesh stands still around the axle while the material flows through it at the spin rate Omega
(`docs/steady-rolling.md`). Node i of the ring holds whatever material is at the angle theta_i now;
in a steady state that shape is constant, and a material point passes from label i+1 to label i
(forward rolling turns the bottom of the tire towards -x, so material moves to decreasing theta) in
dt = dtheta / Omega. From the shape alone follow
  velocities   v = -Omega dX/dtheta (central differences around the ring, beads and ghosts too),
  inertia      m a = m Omega^2 (x_{i+1} - 2 x_i + x_{i-1}) / dtheta^2 (centripetal and Coriolis in one:
               the frame does not rotate, so the acceleration of the flowing material is all there is),
  Maxwell      each branch stress integrated exactly along its streamline around the ring (periodic:
               a circulant solve), the strain rate constant over each passage between labels,
  bristles     each tread column's shear carried through the contact patch from the leading edge, the
               slip of each passage its exact displacement relative to the road (on the passage that
               enters the patch, only the part spent touching), saturated at mu F_n.
The residual is minus the net force on every degree of freedom (`residual.py`'s convention), so the
static residual is its Omega -> 0 limit. The unknowns are `residual.pack(x, q)` with one change: the
rim's spin slot q[4] holds Omega (the rim is axisymmetric, its spin angle is immaterial), and its row
is the rim's torque balance (free rolling: no drive torque) or, with the spin prescribed, a dummy.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..materials import prony_weights
from ..physics import tread
from ..physics.contact import OMEGA_REF, RAMP_EPS, AbstractSurface
from ..physics.geometry_ops import V, cross, dot, smooth_ramp, smooth_step
from . import residual as R

SPIN = 4  # the rim slot that holds Omega
# the friction cone's smoothing: exact below (1 - SLIDING_BAND) mu F_n, mu F_n exactly above (1 + band),
# C2 between. A smoothing that shaves every passage (the static contact's p-norm) would add up along
# the streamline: the finer the sampling, the lower the sliding force
SLIDING_BAND = 0.02
OMEGA_MIN = 1e-6  # rad/s: below it the tire is treated as standing (no transport)
FORCE_EPS = 1.0  # N: width of the smooth clip of a contact point's normal force at zero


def soft_positive(f, eps):
    """max(f, 0), made C1 over [-eps, eps] ((f + eps)^2 / 4 eps there): Newton needs a smooth residual."""
    c = jnp.clip(f, -eps, eps)
    return jnp.where(f > eps, f, (c + eps) ** 2 / (4 * eps))


class RollingSetup(eqx.Module):
    """Everything imposed on a tire in steady rolling, as arrays (setups vmap and differentiate).

    pressure: Pa. rim_force: (6,) on free rim DOFs (N, N m; slot 4 the drive torque about +y).
    subpoints (static): contact points per segment along the streamlines (a multiple of the model's
    own): the patch's leading and trailing edges pass between labels, so the steady contact needs a
    finer sampling than a transient, whose points move through the patch.
    rim_free: (6,) 1 free, 0 held at rim_position (m, rad; slot 3 the camber angle); slot 4: 1 = the
    spin Omega is an unknown fixed by the torque balance, 0 = Omega prescribed (`omega`).
    omega: rad/s, forward rolling positive (the prescribed spin, or the first guess of a free one).
    surface: the road or drum, moving (FlatRoad.velocity, Drum.omega). gravity: (3,) m/s^2.
    friction_on: 1 or 0, multiplies the friction coefficient.
    """

    pressure: Float[Array, ""]
    rim_force: Float[Array, " 6"]
    rim_free: Float[Array, " 6"]
    rim_position: Float[Array, " 6"]
    omega: Float[Array, ""]
    surface: AbstractSurface
    gravity: Float[Array, " 3"]
    friction_on: Float[Array, ""]
    subpoints: int = eqx.field(static=True, default=8)

    @property
    def n_border(self) -> int:
        return 6

    @property
    def rigid_belt(self) -> bool:
        return False

    @property
    def belt_load(self):
        return None


def make_rolling_setup(pressure, surface, *, omega, rim_force=np.zeros(6), rim_free=np.zeros(6),
                       rim_position=np.zeros(6), gravity=np.zeros(3), friction_on=1.0, subpoints=8):
    """RollingSetup from numbers or arrays (every leaf float64)."""
    f = lambda v: jnp.asarray(v, jnp.float64)  # noqa: E731
    return RollingSetup(f(pressure), f(rim_force), f(rim_free), f(rim_position), f(omega), surface, f(gravity),
                        f(friction_on), int(subpoints))


def ring_index(model) -> np.ndarray:
    """(T, m) indices into the flat strain vector: row i holds every strain at segment i (each strain
    family is a (T, k) array flattened row-major, `TireModel.strains`)."""
    T, S = model.n_theta, model.n_s
    widths = (S - 1, S - 2, S - 1, S, S - 2)
    cols, off = [], 0
    for k in widths:
        cols.append(off + np.arange(T)[:, None] * k + np.arange(k)[None, :])
        off += T * k
    return np.concatenate(cols, axis=1)


def ring_diff(a, dtheta):
    """Central difference d a / d theta of per-segment values (leading axis: the ring)."""
    return (jnp.roll(a, -1, 0) - jnp.roll(a, 1, 0)) / (2 * dtheta)


def circulant_transport(a, b):
    """Periodic solution of s_i = a s_{i+1} + b_i around a ring (0 <= a < 1 per branch).

    a: (B,); b: (B, T, m). s_i = sum_k a^k b_{i+k} / (1 - a^T): one (T, T) circulant per branch."""
    T = b.shape[1]
    k = (np.arange(T)[None, :] - np.arange(T)[:, None]) % T
    C = a[:, None, None] ** k[None] / (1.0 - a[:, None, None] ** T)
    return jnp.einsum("bij,bjm->bim", C, b)


def maxwell_stresses(model, params, s, omega, dt):
    """(B, n) branch stresses of the steady flow of the strain field s (n,), and their power (W).

    The material strain rate is the rate of the strain field along the streamline, sdot = -omega
    ds/dtheta (central differences of the strains themselves: a rate taken from node velocities
    instead would stretch the inextensible belt where its curvature changes, at the patch edges).
    Along a streamline sigma' = -sigma / tau + K_b sdot(t); over one passage (time dt, label i+1 ->
    i) at the constant rate sdot = (S_i - S_{i+1}) / dt the exact update is
        sigma_i = a sigma_{i+1} + K_b tau (1 - a) sdot,  a = e^{-dt/tau},
    a periodic recurrence solved exactly (`circulant_transport`)."""
    idx = ring_index(model)
    tau = jnp.asarray(params.relaxation_times, jnp.float64)
    cb = jnp.asarray(prony_weights(params.relaxation_times))
    K = model.stiffness(params)
    Kb = (cb[:, None] * (model.strain_loss(params) * K)[None, :])[:, idx]  # (B, T, m)
    r = dt / tau
    a = jnp.exp(-r)
    S = s[idx]
    rate = (S - jnp.roll(S, -1, 0)) / dt  # the passage i+1 -> i at a constant rate
    b = Kb * tau[:, None, None] * (1 - a)[:, None, None] * rate[None]
    sig = circulant_transport(a, b)  # (B, T, m)
    inv = np.argsort(idx.reshape(-1))
    flat = sig.reshape(sig.shape[0], -1)[:, inv]
    Kbf = Kb.reshape(Kb.shape[0], -1)[:, inv]
    safe = jnp.where(Kbf > 0, Kbf, 1.0)
    power = jnp.sum(jnp.where(Kbf > 0, flat**2 / (safe * tau[:, None]), 0.0))
    return flat, power


def saturate_shear(z_t, limit, k_t, band=SLIDING_BAND):
    """The tread shear z (V) a trial shear z_t (V) leaves under the friction limit mu F_n (N): z_t
    itself while k_t |z_t| <= (1 - band) limit, the limit along z_t past (1 + band) limit, and between
    them a C2 blend of the ratio f = k_t |z_t| / limit: g' = 1 - smoothstep(t), t = (f - 1 + band) / (2
    band), so g = 1 - band + 2 band (t - t^3 + t^4 / 2) (C2: central differences of the solution keep
    their second order, which a C1 blend's jump in g'' spoils)."""
    tiny = k_t * 1e-12  # N: |z_t| = 0 and limit = 0 (out of contact, unsheared) stay finite and unsheared
    kz = jnp.sqrt(k_t * k_t * dot(z_t, z_t) + tiny * tiny)
    f = kz / (limit + tiny)
    t = (f - 1 + band) / (2 * band)
    blend = (1 - band + 2 * band * (t - t**3 + 0.5 * t**4)) / f
    scale = jnp.where(f <= 1 - band, 1.0, jnp.where(f >= 1 + band, 1.0 / f, blend))
    return z_t * scale


def entry_fraction(gap):
    """(M, C) fraction of each passage m+1 -> m a column spends touching the surface, from the gaps
    (M, C) at its ends (linear along a passage): 1 inside the patch, -gap_m / (gap_m+1 - gap_m) on the
    passage that enters it. A column that touches part-way through a passage has slipped over that
    part only; charging it the whole passage shears every column of the patch by up to one passage
    too much (a first-order error in the sampling). 0 out of contact and leaving it (no limit there)."""
    pen = smooth_ramp(-gap, RAMP_EPS)
    clear = smooth_ramp(jnp.roll(gap, -1, 0), RAMP_EPS)
    return pen / (pen + clear + 1e-3 * RAMP_EPS)


def bristle_transport(model, n_sub, P, n, d, gap, limit, k_t, band=SLIDING_BAND):
    """Tread shear z (V of (N,)) of the steady flow, each column carried from the top of the tire (never
    in contact) down the streamline, z_m = sat(z_{m+1} + phi_m d_m) in the tangent plane (phi: the part
    of the passage spent touching, `entry_fraction`), and the energy (J) each passage dissipates by slip.

    P, n, d, gap, limit, k_t: tread points, surface normals, the slip displacement of each passage (the
    material's displacement minus the surface's, m), the gaps (m), mu F_n and k_t per point, (N,) in the
    tread's (segment, sub-point, column) order."""
    M = model.n_theta * n_sub
    C = len(model.tread_cols_t)
    rs = lambda a: a.reshape(M, C)  # noqa: E731
    phi = entry_fraction(rs(gap))
    n_, d_, L, kt = n.map(rs), d.map(lambda a: rs(a) * phi), rs(limit), rs(k_t)
    start = M // 2  # the top of the tire: out of contact on a road or drum below it
    order = (start - np.arange(M)) % M

    def step(z, m):
        nm = n_[m]
        zp = z - nm * dot(z, nm)
        zn = saturate_shear(zp + d_[m] - nm * dot(d_[m], nm), L[m], kt[m], band)
        # energy lost in the passage: the work of the mean shear force over the slip less the change
        # of the column's elastic energy (zero while it sticks; all of it when it lets go)
        lost = kt[m] * (0.5 * dot(zn + zp, d_[m]) - 0.5 * (dot(zn, zn) - dot(zp, zp)))
        return zn, (zn, lost)

    zero = V(*(jnp.zeros(C, P.x.dtype) for _ in range(3)))
    _, (zs, lost) = jax.lax.scan(step, zero, jnp.asarray(order))
    back = np.argsort(order)
    un = lambda a: a[back].reshape(-1)  # noqa: E731
    return zs.map(un), un(lost)


def _unknowns(model, setup, u):
    """(free nodes x, rim q for the kinematics (spin angle 0), Omega) from the flat unknowns."""
    x, q6, _ = R.unpack(model, u, False)
    target = setup.rim_position.at[SPIN].set(setup.omega)
    qm = jnp.where(setup.rim_free > 0, q6, target)
    return x, qm.at[SPIN].set(0.0), qm[SPIN]


def rolling_forces(model, params, setup, u):
    """(residual (n,), diagnostics dict): minus the net steady force on every mechanical DOF (nodes,
    rim; the spin row: the torque balance), DUMMY_SCALE (u - target) on held DOFs.

    diagnostics: tire_on_rim (6,) (N, N m; the hub dynamometer), contact_force (3,), contact_moment
    (3,) about the wheel centre, omega (rad/s), power_rubber, power_contact_damping, power_friction,
    power_nodal_damping (W), n_contact, and the fields (P, F, F_n, gap, z) at the tread points."""
    x, q, omega = _unknowns(model, setup, u)
    T = model.n_theta
    dtheta = 2 * np.pi / T
    w = jnp.maximum(omega, OMEGA_MIN)
    dt = dtheta / w
    ns = setup.subpoints
    dt_sub = dt / ns

    X, asm_vjp = jax.vjp(model.assemble, x, q)

    def kin(X_):
        return model.strains(X_), model.volume(X_), tread.tread_points(X_, model.tread_cols, model.tread_depth, ns,
                                                                           model.normal_sign)

    (s, _, P), lin = jax.linearize(kin, X)

    K = model.stiffness(params)
    sig_b, p_rubber = maxwell_stresses(model, params, s, omega, dt)
    sigma = K * (s - model.s0) + jnp.sum(sig_b, axis=0)

    k_n, k_t, _ = tread.tread_stiffness(model, params, ns)
    c_n = params.tread_loss * k_n / OMEGA_REF
    gap, n, v_s = setup.surface.query(P, 0.0)
    # tread points along their streamlines (sub-points m = segment * n_sub + sub, upstream m + 1)
    M = T * ns
    Pm = P.map(lambda a: a.reshape(M, -1))
    flat = lambda a: a.reshape(-1)  # noqa: E731
    inside = gap < 0
    pen = smooth_ramp(-gap, RAMP_EPS)
    fn_el = k_n * pen
    # normal damping on the tread's compression rate, the material rate of the penetration field (a
    # gap rate taken across the patch's leading edge would charge the whole approach speed of a
    # point still in the air), with the elastic force's smooth onset and never pulling (C1 clip)
    pen_rate = flat(-omega * ring_diff(pen.reshape(M, -1), dtheta / ns))
    on = smooth_step(-gap / RAMP_EPS)
    F_n = soft_positive(fn_el + c_n * pen_rate * on, FORCE_EPS) * on
    p_damp = jnp.sum((F_n - fn_el * on) * pen_rate)  # what the normal force loses beyond its elastic part
    # the slip of a passage sub-point m+1 -> m: the material's displacement less the surface's
    step = (Pm - Pm.map(lambda a: jnp.roll(a, -1, 0))).map(flat)
    d = step - v_s * dt_sub
    z, lost = bristle_transport(model, ns, P, n, d, gap, params.friction * setup.friction_on * F_n, k_t)
    F = n * F_n - z * k_t
    p_fric = jnp.sum(lost) / dt_sub

    (fX,) = jax.linear_transpose(lin, X)((sigma, -setup.pressure, -F))
    rx, rq = asm_vjp(fX)
    m = model.node_mass
    g = setup.gravity
    lap = (x.roll(-1, 0) - x * 2.0 + x.roll(1, 0)) * (omega**2 / dtheta**2)
    rx = rx + lap * m - V(m * g[0], m * g[1], m * g[2])
    # the study's explicit-FE model form (params.nodal_damping, 0 = off): a force -alpha m v_g on every
    # node, v_g its velocity relative to the road's frame (the flow's -Omega dX/dtheta less the road's)
    v_road = setup.surface.frame_velocity()
    zero = jnp.zeros_like(m)
    v_g = (x.roll(-1, 0) - x.roll(1, 0)) * (-omega / (2 * dtheta)) - V(zero + v_road[0], zero + v_road[1],
                                                                         zero + v_road[2])
    rx = rx + v_g * (params.nodal_damping * m)
    p_nodal = params.nodal_damping * jnp.sum(m * dot(v_g, v_g))
    f_rim = setup.rim_force + jnp.concatenate([g * model.rim_mass, jnp.zeros(3)])
    r = R.pack(rx, rq - f_rim)
    mask = jnp.concatenate([jnp.ones(r.shape[0] - 6), setup.rim_free])
    x6 = R.unpack(model, u, False)[1]
    target = setup.rim_position.at[SPIN].set(setup.omega)
    dummy = jnp.concatenate([jnp.zeros(r.shape[0] - 6), jnp.where(setup.rim_free > 0, 0.0,
                                                                    R.DUMMY_SCALE * (x6 - target))])
    centre = V(q[0], q[1], q[2])
    diag = dict(tire_on_rim=-rq, contact_force=F.sum().array(), contact_moment=cross(P - centre, F).sum().array(),
                omega=omega, power_rubber=p_rubber, power_contact_damping=p_damp, power_friction=p_fric,
                power_nodal_damping=p_nodal,
                n_contact=jnp.sum(inside.astype(jnp.float64)), P=P, F=F, F_n=F_n, gap=gap, z=z)
    return r * mask + dummy, diag


def rolling_residual(model, params, setup, u):
    return rolling_forces(model, params, setup, u)[0]


def rolling_residual_and_rim(model, params, setup, u):
    r, d = rolling_forces(model, params, setup, u)
    return r, d["tire_on_rim"]
