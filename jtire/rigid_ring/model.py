"""The rigid-ring tire as equations of motion (docs/rigid-ring.md §2-§6), integrated with diffrax.

Axes ISO (x forward, y left, z up); theta > 0 rolling forward; gamma about +x. The axle stays in x
and the road moves under it at the speed V (a flat-track or drum machine; the drum's curvature is
not modelled). Slip angles inside are ISO (alpha > 0: the wheel travels to the LEFT of its heading,
the road pushes it right, F_y < 0); scenarios take SAE angles and convert (alpha_ISO = -alpha_SAE).

State y (N_STATE,): positions q (10,) = [x_a, z_a, theta_a, x_b, z_b, theta_b, y_a, gamma_a, y_b,
gamma_b] (rim a, belt b; m, rad), their velocities (10,), then the contact's tread deflections u
(longitudinal, m) and e (lateral, m; in the reduced model the whole tire's lateral deflection), then
the tread strings' node deflections (N_TREAD longitudinal, N_TREAD lateral; contact = "string"), then
the internal states q_by, q_bgamma of the sidewall's lateral Maxwell branches (ring variant).

Contact = "lag" (MF-Swift's first-order slip lags, below) or "string" (the default): the tread
through the patch as a stretched string (Pacejka, Tyre and Vehicle Dynamics §5.4): its contact points
stick to the road and are carried from the leading edge (xi = 0) to the trailing one (xi = 2a) at
|V|, de/dt + |V| de/dxi = v_c (v_c the belt's slip velocity there), the leading edge's deflection
e_1 relaxes over the free string, sigma_s de_1/dt + |V| e_1 = sigma_s v_c, and the force is
c (sigma_s (e_1 + e(2a)) + int e dxi). Longitudinally sigma_s = 0 (a brush); laterally sigma_s =
sigma_c - a. With c = k_f / (2 (sigma_s + a)^2) it has the lag's steady force and static stiffness
k_f / (sigma_s + a); what differs is its response to slip that varies within a patch transit
(2a / |V|), which the lag over-damps (docs/rigid-ring.md, "Why a string, not the lag"). Nodes:
Chebyshev-Gauss-Lobatto behind the leading edge (spectral; tests/test_rigid_ring_contact.py checks
them against the continuous string). Linear, no sliding, like the lag; |V| is taken as the speed in
either direction.

In-plane (Zegelaar & Pacejka; §4): belt and rim joined by the sidewall springs/dampers
(k_bx, C_bx; k_bz, C_bz; k_btheta, C_btheta); the belt stands on the residual spring
F_z = max(0, k_vr rho + k_vr2 rho^2 + C_vr rho_dot) (past the load the spring of `identify.residual_force`)
where rho = R0 - (z_b - z_road) > 0, else 0 (no adhesion: the max), with the damper faded in over the
first RHO_RAMP = 0.5 mm of deflection (continuous force: see `forces`).
Longitudinal slip (§5): u = a kappa', a du/dt + |V| u = -a V_sx, V_sx = V + x_b' - r_e theta_b'
(minus the road's own motion), F_x = k_cx u + C_vlow du/dt with k_cx = k_k / a, so the
contact relaxation length is a (study eq 5-17) and at V = 0 the patch is a tread spring; C_vlow
= damp_vlow k_cx fades out linearly by V = VXLOW (MF-Swift DAMP_VLOW).
Out-of-plane, "ring" (Chae; §6): belt y_b, gamma_b on the sidewall (k_by, C_by; k_bgamma,
C_bgamma; each spring with a Maxwell branch beside it where the parameters have one: force
k_branch (x - q), dq/dt = (x - q) / tau_branch, x the spring's deflection); the tread e between
the belt's contact point y_b + r_l gamma_b and the patch, sigma_c de/dt + |V| e = sigma_c V_cy
(damping folded in exactly, see `_tread_rate`), F_y = -(k_cy e + C_cy de/dt), sigma_c = k_f / k_cy. Steady: F_y = -k_f sin(alpha).
Out-of-plane, "reduced" (§5 fallback, MF 6.1's own transient): no belt lateral DOFs; the rim
(mass m_tot) on k_l || C_l to a single contact point with sigma = k_f / k_l. Do not mix with the
ring's k_by, k_bgamma (the carcass compliance would count twice).
M_z = M_z,E10(alpha') at alpha' = -F_y_SAE / k_f: the condition's steady E10 curve (odd part,
piecewise linear; k_m alpha', the pneumatic trail k_m/k_f, without one), on the rim (no belt yaw DOF).
Cleat: with a tandem cam (`Drive.ellips`) the contact follows the effective road of
`jtire.enveloping` (height w, slope dw/dx, dw/dt = V dw/ds; MF-Swift's enveloping); without one a
point contact follows the cleat's own profile (frequencies and decay comparable, waveforms not).
Omitted (§4): rotating-sidewall Omega terms, Q_BVX/Q_BVT stiffening, rolling resistance, the effective
rolling radius's variation over the cleat.

Solver: Tsit5 (explicit, adaptive PID). The fastest dynamics are the belt's vertical and fore-aft
modes (~60-70 Hz) and the slip lag k_k / (V m_b) (~1e3 1/s at 50 km/h): not stiff enough for an
implicit solver to pay off; the contact's kink at lift-off is met by step rejection. Everything is
differentiable in the parameters (diffrax's default recursive checkpointing adjoint).
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from .. import enveloping
from .identify import residual_force
from .params import RigidRingParams

N_Q = 10
N_TREAD = 6  # string nodes behind the leading edge (see `_chebyshev`)
N_STATE = 2 * N_Q + 2 + 2 * N_TREAD + 2
IDX = {"x_a": 0, "z_a": 1, "theta_a": 2, "x_b": 3, "z_b": 4, "theta_b": 5, "y_a": 6, "gamma_a": 7, "y_b": 8,
       "gamma_b": 9, "u": 20, "e": 21, "q_by": 22 + 2 * N_TREAD, "q_bgamma": 23 + 2 * N_TREAD}
U_NODES = tuple(range(22, 22 + N_TREAD))
E_NODES = tuple(range(22 + N_TREAD, 22 + 2 * N_TREAD))
CONTACTS = ("string", "lag")
CONTACT = "string"  # the default: the string matches the shell's build-up and drum modes (docs/rigid-ring.md §5)
SIGMA_S_MIN = 0.1  # x a: the free string's shortest length (a shorter one would make e_1 stiff)
RIM = (0, 1, 2, 6, 7)
BELT = (3, 4, 5, 8, 9)
VXLOW = 1.0  # m/s: below it the low-speed tread damping is on (MF VXLOW)
RHO_RAMP = 5e-4  # m: the residual damper fades in over this deflection (~1 ms at 0.5 m/s impact)


def _f64(x):
    return jnp.asarray(x, dtype=jnp.float64)


class Drive(eqx.Module):
    """Inputs of one scenario (SI). free (10,): 1 where a coordinate moves, 0 where it is held at
    its initial velocity (0 for a held rim; the belt is always free). rim_force (10,): generalized
    forces on the rim's coordinates (N, N m), constant. V: road speed (m/s). alpha_iso: slip
    angle after the step (rad, ISO), reached by a half-cosine ramp from t_alpha over t_ramp.
    gravity (m/s^2, >= 0, on every mass). z_road: road height (m). Cleat: a round bump of radius
    r_cleat and height h_cleat (0: none) whose crest passes the contact point at s = V t = s_cleat;
    ellips (4,): the tandem cam (l_s, a_e, b_e, c_e) of `jtire.enveloping`, or None: point contact
    (a different program, so the scenarios without a cam never evaluate one)."""

    free: jnp.ndarray
    rim_force: jnp.ndarray
    V: jnp.ndarray
    alpha_iso: jnp.ndarray
    t_alpha: jnp.ndarray
    t_ramp: jnp.ndarray
    gravity: jnp.ndarray
    z_road: jnp.ndarray
    r_cleat: jnp.ndarray
    h_cleat: jnp.ndarray
    s_cleat: jnp.ndarray
    ellips: jnp.ndarray | None

    @classmethod
    def make(cls, free=(), rim_force=None, V=0.0, alpha_iso=0.0, t_alpha=0.0, t_ramp=0.005, gravity=0.0,
             z_road=0.0, r_cleat=0.1, h_cleat=0.0, s_cleat=0.0, ellips=None):
        """free: names of the rim coordinates that move (e.g. ("z_a",)); the belt always moves."""
        m = jnp.zeros(N_Q).at[jnp.asarray(BELT)].set(1.0)
        for n in free:
            m = m.at[IDX[n]].set(1.0)
        rf = jnp.zeros(N_Q) if rim_force is None else _f64(rim_force)
        return cls(free=_f64(m), rim_force=rf, V=_f64(V), alpha_iso=_f64(alpha_iso), t_alpha=_f64(t_alpha),
                   t_ramp=_f64(t_ramp), gravity=_f64(gravity), z_road=_f64(z_road), r_cleat=_f64(r_cleat),
                   h_cleat=_f64(h_cleat), s_cleat=_f64(s_cleat),
                   ellips=None if ellips is None else _f64(ellips))


def road(drive: Drive, t):
    """(height z_road (m), slope dz/ds, dz/dt) under the contact point at time t."""
    s = drive.V * t - drive.s_cleat
    r, h = drive.r_cleat, drive.h_cleat
    if drive.ellips is not None:  # decided when tracing: a scenario without a cam never evaluates one
        w, w_slope, w_rate = enveloping.effective_with_rate(s, *drive.ellips, r, h)
        return drive.z_road + w, w_slope, w_rate * drive.V
    half = jnp.sqrt(jnp.clip(r**2 - (r - h) ** 2, 0.0))  # half chord of the cleat at the road
    inside = (jnp.abs(s) < half) & (h > 0)
    root = jnp.sqrt(jnp.clip(r**2 - s**2, 1e-12))
    z = jnp.where(inside, root - (r - h), 0.0)
    slope = jnp.where(inside, -s / root, 0.0)
    return drive.z_road + z, slope, slope * drive.V


def slip_angle(drive: Drive, t):
    x = jnp.clip((t - drive.t_alpha) / drive.t_ramp, 0.0, 1.0)
    return drive.alpha_iso * 0.5 * (1.0 - jnp.cos(jnp.pi * x))


def _chebyshev(n):
    """Chebyshev-Gauss-Lobatto differentiation matrix (n+1, n+1) and Clenshaw-Curtis weights (n+1,)
    on [0, 1], node 0 at 0 (the leading edge), node n at 1 (the trailing edge)."""
    import numpy as np

    k = np.arange(n + 1)
    x = np.cos(np.pi * k / n)  # 1 .. -1
    c = np.where((k == 0) | (k == n), 2.0, 1.0) * (-1.0) ** k
    dx = x[:, None] - x[None, :]
    D = np.outer(c, 1.0 / c) / (dx + np.eye(n + 1))
    D -= np.diag(D.sum(axis=1))
    th = np.pi * k / n
    w = np.zeros(n + 1)
    for j in range(n + 1):
        acc = 1.0 + sum(2.0 / (1.0 - 4.0 * m * m) * np.cos(2 * m * th[j]) for m in range(1, (n - 1) // 2 + 1))
        if n % 2 == 0:
            acc += np.cos(n * th[j]) / (1.0 - n * n)
        w[j] = acc * 2.0 / n * (0.5 if j in (0, n) else 1.0)
    # xi = (1 - x) / 2 maps x = 1 -> 0: d/dxi = -2 d/dx, weights halve (sum 1)
    return -2.0 * D, w / 2.0


_D_TREAD, _W_TREAD = _chebyshev(N_TREAD)


def string_rates(lead, nodes, v_c, V, a, sigma_s):
    """Rates of a tread string of length 2a: (d lead/dt, d nodes/dt), and the integral I = sigma_s
    (lead + trailing) + int e dxi, so the force is c I. lead: the leading edge's deflection (held at
    0 when sigma_s is None: a brush); nodes (N_TREAD,) behind it."""
    aV = jnp.abs(V)
    L = 2.0 * a
    D, w = jnp.asarray(_D_TREAD), jnp.asarray(_W_TREAD)
    full = jnp.concatenate([jnp.reshape(lead, (1,)), nodes])
    d_nodes = v_c - aV * (D[1:] @ full) / L
    integral = L * (w @ full)
    if sigma_s is None:
        return jnp.zeros_like(lead), d_nodes, integral, L * (w[1:] @ d_nodes)
    d_lead = v_c - aV * lead / sigma_s
    d_int = sigma_s * (d_lead + d_nodes[-1]) + L * (w @ jnp.concatenate([jnp.reshape(d_lead, (1,)), d_nodes]))
    return d_lead, d_nodes, integral + sigma_s * (lead + nodes[-1]), d_int


def _tread_rate(k, c, k_f, e, v_cy, V):
    """de/dt of a tread spring k || damper c whose road end slides with the linear brush law
    F = -k_f V_sy / |V|: de/dt = (V_cy - |V| e k / k_f) / (1 + |V| c / k_f)."""
    aV = jnp.abs(V)
    return (v_cy - aV * e * k / k_f) / (1.0 + aV * c / k_f)


class RigidRing(eqx.Module):
    """The rigid-ring tire; lateral = "ring" (Chae belt DOFs) or "reduced" (k_l || C_l, sigma);
    contact = "string" (the tread strings through the patch) or "lag" (first-order slip lags)."""

    params: RigidRingParams
    lateral: str = eqx.field(static=True, default="ring")
    contact: str = eqx.field(static=True, default=CONTACT)

    def forces(self, t, y, drive: Drive) -> dict:
        """Every force of the model at (t, y): contact F_x, F_y, F_z, M_z (road on tire, ISO), the
        sidewall forces on the belt, the tread rates, and the tire's force on the rim."""
        p = self.params
        q, v = y[:N_Q], y[N_Q:2 * N_Q]
        u, e = y[20], y[21]
        xa, za, tha, xb, zb, thb, ya, ga, yb, gb = q
        vxa, vza, vtha, vxb, vzb, vthb, vya, vga, vyb, vgb = v
        zr, slope, zr_dot = road(drive, t)
        rl = zb - zr
        rho = p.R0 - rl
        contact = (rho > 0).astype(y.dtype)
        # no damper force before the touch (doc §2: rho = max(0, .)); the damper fades in over the
        # first RHO_RAMP of deflection so the force stays continuous: a jump C_vr x impact speed at
        # the touch would make the adjoint miss the touch time's sensitivity (docs/design-notes.md)
        ramp = jnp.clip(rho / RHO_RAMP, 0.0, 1.0)
        f_spring = residual_force(jnp.maximum(rho, 0.0), p.k_vr, p.k_vr2, p.rho_r, p.rho_max, p.k_vr3, jnp)
        fz = contact * jnp.maximum(0.0, f_spring + ramp * p.C_vr * (zr_dot - vzb))
        fsx = -p.k_bx * (xb - xa) - p.C_bx * (vxb - vxa)
        fsz = -p.k_bz * (zb - za) - p.C_bz * (vzb - vza)
        msth = -p.k_btheta * (thb - tha) - p.C_btheta * (vthb - vtha)
        V = drive.V
        alpha = slip_angle(drive, t)
        string = self.contact == "string"
        # longitudinal tread (the road moves backwards at V under the fixed axle)
        k_cx = p.k_k / p.a
        c_vlow = p.damp_vlow * k_cx * jnp.clip(1.0 - jnp.abs(V) / VXLOW, 0.0, 1.0)
        v_sx = V * jnp.cos(alpha) + vxb - p.r_e * vthb
        un, en = y[U_NODES[0]:U_NODES[-1] + 1], y[E_NODES[0]:E_NODES[-1] + 1]  # static slices, no gather
        if string:  # a brush: k_k / (2 a^2) per length, so F = k_k kappa steady and k_cx u at V = 0
            u_dot, un_dot, integ, d_integ = string_rates(u, un, -v_sx, V, p.a, None)
            fx_t = p.k_k / (2.0 * p.a**2) * integ + c_vlow * d_integ / (2.0 * p.a)
        else:
            u_dot = -v_sx - jnp.abs(V) * u / p.a
            un_dot = jnp.zeros_like(un)
            fx_t = k_cx * u + c_vlow * u_dot
        fx = contact * fx_t - fz * slope  # + the normal force's share on a slope
        # lateral
        v_road = V * jnp.sin(alpha)
        if self.lateral == "ring":
            v_cy = v_road + vyb + rl * vgb
            k_t, c_t = p.k_cy, p.C_cy
        else:
            v_cy = v_road + vya
            k_t, c_t = p.k_l, p.C_l
        if string:  # free string sigma_c - a ahead of the patch (sigma_c = k_f / k_t), then the patch
            sig_s = jnp.maximum(p.k_f / k_t - p.a, SIGMA_S_MIN * p.a)
            c_len = p.k_f / (2.0 * (sig_s + p.a) ** 2)
            e_dot, en_dot, integ, d_integ = string_rates(e, en, v_cy, V, p.a, sig_s)
            k_st = 2.0 * c_len * (sig_s + p.a)  # its static stiffness (k_t unless sigma_c < 1.1 a)
            fy = -contact * (c_len * integ + c_t * d_integ * c_len / k_st)
        else:
            e_dot = _tread_rate(k_t, c_t, p.k_f, e, v_cy, V)
            en_dot = jnp.zeros_like(en)
            fy = -contact * (k_t * e + c_t * e_dot)
        if self.lateral == "ring":
            qy, qg = y[IDX["q_by"]], y[IDX["q_bgamma"]]
            dy, dg = yb - ya, gb - ga
            fsy = -p.k_by * dy - p.C_by * (vyb - vya) - p.k_by_branch * (dy - qy)
            msg = -p.k_bgamma * dg - p.C_bgamma * (vgb - vga) - p.k_bgamma_branch * (dg - qg)
            branch_dot = jnp.stack([dy - qy, dg - qg]) / p.tau_branch
            rim_y = -fsy
        else:
            fsy = msg = jnp.zeros_like(fy)
            branch_dot = jnp.zeros(2, y.dtype)
            rim_y = fy
        # M_z from E10's steady curve at the slip the force stands for (alpha'_SAE = F_y_ISO / k_f; linear
        # k_m alpha' without a curve); an output only: the ring has no yaw DOF
        mz = -jnp.interp(fy / p.k_f, p.mz_alpha, p.mz_value)
        return {"F_x": fx, "F_y": fy, "F_z": fz, "M_z": mz, "F_sx": fsx, "F_sz": fsz, "M_stheta": msth,
                "F_sy": fsy, "M_sgamma": msg, "u_dot": u_dot, "e_dot": e_dot, "r_l": rl, "rho": rho,
                "tread_dot": jnp.concatenate([jnp.stack([u_dot, e_dot]), un_dot, en_dot]), "branch_dot": branch_dot,
                "z_road": zr, "alpha_iso": alpha, "contact": contact,
                "tire_on_rim_x": -fsx, "tire_on_rim_z": -fsz, "tire_on_rim_y": rim_y}

    def vector_field(self, t, y, drive: Drive):
        p = self.params
        f = self.forces(t, y, drive)
        g = drive.gravity
        rf = drive.rim_force
        rl = f["r_l"]
        acc_b = jnp.stack([(f["F_sx"] + f["F_x"]) / p.m_b,
                           (f["F_sz"] + f["F_z"]) / p.m_b - g,
                           (f["M_stheta"] - rl * f["F_x"]) / p.I_by])
        acc_a = jnp.stack([(-f["F_sx"] + rf[0]) / p.m_a,
                           (-f["F_sz"] + rf[1]) / p.m_a - g,
                           (-f["M_stheta"] + rf[2]) / p.I_ay])
        if self.lateral == "ring":
            lat_a = jnp.stack([(-f["F_sy"] + rf[6]) / p.m_a, (-f["M_sgamma"] + rf[7]) / p.I_ax])
            lat_b = jnp.stack([(f["F_sy"] + f["F_y"]) / p.m_b, (f["M_sgamma"] + rl * f["F_y"]) / p.I_bx])
        else:
            lat_a = jnp.stack([(f["F_y"] + rf[6]) / p.m_tot, jnp.zeros_like(rl)])
            lat_b = jnp.zeros(2, y.dtype)
        acc = jnp.concatenate([acc_a, acc_b, lat_a, lat_b]) * drive.free  # the order of q
        if self.lateral != "ring":
            acc = acc.at[8:10].set(0.0)
        return jnp.concatenate([y[N_Q:2 * N_Q], acc, f["tread_dot"], f["branch_dot"]])

    def outputs(self, ts, ys, drive: Drive) -> dict:
        """Forces at saved samples: ts (N,), ys (N, N_STATE) -> dict of (N,) arrays."""
        return _outputs(self, _f64(ts), _f64(ys), drive)


@eqx.filter_jit
def _outputs(model, ts, ys, drive):
    return jax.vmap(lambda t, y: model.forces(t, y, drive))(ts, ys)


def simulate(model: RigidRing, drive: Drive, y0, t1, ts, rtol=1e-7, atol=1e-9, max_steps=200_000, dt0=1e-5,
             dtmax=None):
    """Integrate from t = 0 to t1, saving at ts (N,). Returns ys (N, N_STATE). dtmax: the largest step (s;
    an input that starts later, like a cleat, is not stepped over from a quiet start). Jit-compiled
    per (lateral, shapes); differentiable in model.params and drive."""
    return _simulate(model, drive, _f64(y0), _f64(t1), _f64(ts), rtol, atol, max_steps, dt0, dtmax)


@eqx.filter_jit
def _simulate(model, drive, y0, t1, ts, rtol, atol, max_steps, dt0, dtmax=None):
    term = diffrax.ODETerm(lambda t, y, args: model.vector_field(t, y, args))
    sol = diffrax.diffeqsolve(term, diffrax.Tsit5(), _f64(0.0), t1, dt0, y0, args=drive,
                              saveat=diffrax.SaveAt(ts=ts),
                              stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol, dtmax=dtmax),
                              max_steps=max_steps)
    return sol.ys


def linearize(model: RigidRing, drive: Drive, y_eq, t=0.0):
    """Jacobian d(dy/dt)/dy (N_STATE, N_STATE) at y_eq (forward-mode AD)."""
    return _linearize(model, drive, _f64(y_eq), _f64(t))


@eqx.filter_jit
def _linearize(model, drive, y_eq, t):
    return jax.jacfwd(lambda y: model.vector_field(t, y, drive))(y_eq)


def modes(jac, coords, slip=(), internal=()):
    """Modes of the linearized system restricted to coordinates `coords` (names of q), their
    velocities and the slip states `slip` ("u", "e": each with its string's nodes; the states the
    model's contact leaves constant add zero eigenvalues, not oscillatory modes) and the internal
    states `internal` (e.g. "q_by", "q_bgamma": the Maxwell branches). Returns (f_n Hz,
    zeta) of the oscillatory modes, sorted by frequency, as numpy arrays."""
    import numpy as np

    iq = [IDX[c] for c in coords]
    nodes = {"u": U_NODES, "e": E_NODES}
    idx = iq + [i + N_Q for i in iq] + [j for s in slip for j in (IDX[s],) + nodes[s]] + [IDX[n] for n in internal]
    lam = np.linalg.eigvals(np.asarray(jac)[np.ix_(idx, idx)])
    osc = lam[lam.imag > 1e-9]
    wn = np.abs(osc)
    order = np.argsort(wn)
    return wn[order] / (2 * np.pi), (-osc.real / np.abs(osc))[order]
