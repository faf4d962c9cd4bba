"""Static equilibrium solves (jtire.equilibrium) on the coarse ring: identities, the linear algebra,
agreement with settled transients, and implicit derivatives against central differences.

Tolerances, each with its reason:
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jtire.equilibrium as EQ
from jtire import units as U
from jtire.equilibrium import linalg as LA
from jtire.equilibrium import residual as R
from jtire.errors import SimulationError
from jtire.physics.contact import FlatRoad
from jtire.physics.geometry_ops import V, cross
from jtire.state import TireState

P = 120 * U.PSI
LOAD = 45370.0  # N: the rated load (4625 kg)
LATERAL = 5000.0  # N: E09's lateral force

TOL_IDENTITY = 1e-9  # relative to the largest force: the same terms summed in another order (round-off)
TOL_LINALG = 1e-8  # block solve vs dense LU on the coarse Jacobian (condition ~1e8, float64)
# inflation vs a transient settled to KE < 1e-9 J (its residual forces are still ~1 N): measured
# 6e-5 of the largest displacement (4.8 mm)
TOL_INFLATE = 3e-4
# vertical deflection at the rated load vs a transient with every loss zero, KE < 1e-8 J: the
# friction path is the remaining difference (static levels vs continuous loading; measured 0.01-0.05 %
# with 4-15 levels, 0.2 % with one)
TOL_DEFLECTION = 3e-3
# lateral deflection vs the transient: friction in the patch makes it path dependent (the transient's
# bristles slide at the patch edges along the ramp; the static levels take the lateral load in 3
# steps): measured 0.1 %
TOL_LATERAL = 1e-2
# rigid-belt hold vs the transient (no contact, no path dependence): the transient's residual KE
TOL_BELT = 1e-3
# implicit derivative vs central differences (relative step 1e-4, solves to 1e-10 of the load scale):
# the difference quotient's own error is O(h^2) plus solver noise / h
TOL_GRAD = 1e-4


def _rng_state(model, scale, seed):
    """Reference shape moved by a smooth random field of amplitude `scale` (m)."""
    k = jax.random.split(jax.random.PRNGKey(seed), 3)
    d = [scale * jax.random.normal(ki, model.x_ref.x.shape) for ki in k]
    return model.x_ref + V(*d)


def _contact_setup(model, params, x, q, rim_free, seed=1, gravity=(0.0, 0.0, -9.81)):
    """A setup pressing x into a road 10 mm above its lowest tread point, with sheared anchors."""
    Pts = model.tread_points(model.assemble(x, q))
    road = FlatRoad(height=jnp.min(Pts.z) + 0.01, velocity=jnp.zeros(3))
    k = jax.random.split(jax.random.PRNGKey(seed), 3)
    off = V(*(1e-3 * jax.random.normal(ki, Pts.z.shape) for ki in k))
    gap0 = Pts.z - road.height + 2e-3 * jax.random.normal(k[0], Pts.z.shape)
    anchors = R.Anchors(Pts + off, V(off.x * 0.5, off.y * 0.5, off.z * 0), gap0)
    return R.make_setup(P, rim_force=np.array([10.0, 200.0, -3000.0, 5.0, 7.0, -3.0]), rim_free=rim_free,
                        surface=road, anchors=anchors, gravity=np.asarray(gravity))


def test_residual_is_minus_the_dynamic_force_at_rest(coarse_tire):
    """At v = 0, Maxwell stresses 0, no settle damping and bristles at the static tread shear, the
    dynamic vector field's forces (m a) are minus the static residual, on nodes and rim."""
    from jtire.experiments.phases import make_drive
    from jtire.physics.vector_field import evaluate

    m, p = coarse_tire.model, coarse_tire.params
    x = _rng_state(m, 2e-3, 0)
    q = jnp.array([1e-3, -2e-3, -5e-3, 0.01, 0.3, -0.02])
    setup = _contact_setup(m, p, x, q, rim_free=np.ones(6))
    u = R.pack(x, q)
    r, frim = jax.jit(lambda u: R.residual_and_rim(m, p, setup, u))(u)
    _, z, F_n = R.contact(m, p, setup, m.tread_points(m.assemble(x, q)))
    assert int(jnp.sum(F_n > 0)) > 10  # the identity covers contact and friction
    drive = make_drive(P, 1e-5, force0=setup.rim_force, force1=setup.rim_force, rim_free=np.ones(6),
                       surface=setup.surface, damping=0.0, gravity=setup.gravity)
    y = TireState.at_rest(m, len(p.relaxation_times))
    y = eqx.tree_at(lambda s: (s.x, s.q, s.bristle), y, (x, q, z))
    upd, diag = jax.jit(lambda y: evaluate(m, p, drive, jnp.asarray(1.0), y))(y)
    f_x = upd.ax * m.node_mass
    f_q = upd.aq * jnp.concatenate([jnp.full(3, m.rim_mass), m.rim_inertia])
    dyn = R.pack(f_x, f_q)
    scale = float(jnp.max(jnp.abs(dyn)))
    np.testing.assert_allclose(np.asarray(-r), np.asarray(dyn), rtol=0, atol=TOL_IDENTITY * scale)
    np.testing.assert_allclose(np.asarray(frim), np.asarray(diag["tire_on_rim"]), rtol=0, atol=TOL_IDENTITY * scale)


def test_rigid_belt_residual_is_the_belts_net_force(coarse_tire):
    """With a rigid belt (translated, not turned) and a belt load, the static residual of the belt
    pose is minus the net force and moment (about its mass centre) that the dynamic rigid-belt
    update accelerates the belt with; the other nodes' residuals are minus m a."""
    from jtire.experiments.phases import make_drive
    from jtire.physics.vector_field import evaluate

    m, p = coarse_tire.model, coarse_tire.params
    b = jnp.array([1e-3, -2e-3, 3e-3, 0.0, 0.0, 0.0])
    x = _rng_state(m, 1e-3, 2)
    xr = R.rigid_belt_positions(m, b)
    belt = m.belt_mask > 0
    x = V(*(jnp.where(belt, a, c) for a, c in ((xr.x, x.x), (xr.y, x.y), (xr.z, x.z))))
    load = np.array([100.0, 2000.0, -300.0, 400.0, 1500.0, -50.0])
    setup = R.make_setup(P, rim_force=np.zeros(6), rim_free=np.zeros(6), belt_load=load, rigid_belt=True)
    r = jax.jit(lambda u: R.residual(m, p, setup, u))(R.pack(x, jnp.zeros(6), b))
    drive = make_drive(P, 1e-5, damping=0.0, rigid_belt=True, belt_load0=load, belt_load1=load)
    y = eqx.tree_at(lambda s: s.x, TireState.at_rest(m, len(p.relaxation_times)), x)
    upd, _ = jax.jit(lambda y: evaluate(m, p, drive, jnp.asarray(1.0), y))(y)
    mb = m.node_mass * m.belt_mask
    f = upd.ax * mb
    c = (x * mb).sum() / jnp.sum(mb)
    net = jnp.concatenate([f.sum().array(), cross(x - c, f).sum().array()])
    n_x = m.n_theta * (m.n_s - 2) * 3
    scale = float(jnp.max(jnp.abs(net)))
    np.testing.assert_allclose(np.asarray(-r[n_x + 6:]), np.asarray(net), rtol=0, atol=TOL_IDENTITY * scale)
    rx, _, _ = R.unpack(m, r, False)
    free = ~belt
    fx = upd.ax * m.node_mass
    for a, bb in ((rx.x, fx.x), (rx.y, fx.y), (rx.z, fx.z)):
        np.testing.assert_allclose(np.asarray(-a)[free], np.asarray(bb)[free], rtol=0, atol=TOL_IDENTITY * scale)


def test_contact_energy_is_the_normal_force_potential(coarse_tire):
    """Without friction the residual is the gradient of Pi (strain energy - p V + contact penalty
    energy - rim work - gravity work): checks the integral of the contact's smooth ramp."""
    m, p = coarse_tire.model, coarse_tire.params
    x = _rng_state(m, 2e-3, 3)
    q = jnp.array([0.0, 0.0, -4e-3, 0.0, 0.1, 0.0])
    s = eqx.tree_at(lambda a: a.anchors, _contact_setup(m, p, x, q, np.ones(6)), None,
                    is_leaf=lambda a: a is None)
    u = R.pack(x, q)
    r = jax.jit(lambda u: R.residual(m, p, s, u))(u)
    g = jax.jit(jax.grad(lambda u: R.potential(m, p, s, u)))(u)
    np.testing.assert_allclose(np.asarray(g), np.asarray(r), rtol=0, atol=TOL_IDENTITY * float(jnp.max(jnp.abs(r))))


# Gate (without the rigid belt, ~28 s cold here) and slow (with it, ~70 s): each compiles dense Jacobians
# of its own. In the fast suite the block factorization is the Newton solves' preconditioner, where a
# wrong block would slow or stop a solve, not change its answer; the implicit derivatives, which use it
# as the Jacobian, are checked against central differences in the gate too.
@pytest.mark.parametrize("rigid_belt", [pytest.param(False, marks=[pytest.mark.slow, pytest.mark.gate]),
                                        pytest.param(True, marks=pytest.mark.slow)])
def test_block_jacobian_and_solve_match_dense(coarse_tire, rigid_belt):
    """The coloured block assembly equals jax.jacfwd, and the block-cyclic banded solve equals a
    dense LU solve, with contact and friction (and with a rigid belt, whose border rows are then
    assembled from the transposed linearization)."""
    m, p = coarse_tire.model, coarse_tire.params
    x = _rng_state(m, 1e-3, 4)
    q = jnp.array([0.0, 0.0, -5e-3, 0.0, 0.0, 0.0])
    s = _contact_setup(m, p, x, q, np.array([0.0, 1, 1, 0, 0, 0]))
    if rigid_belt:
        s = R.make_setup(P, rim_force=s.rim_force, rim_free=s.rim_free, surface=s.surface, anchors=s.anchors,
                         belt_load=np.array([0.0, 100, 0, 0, 0, 0]), rigid_belt=True)
    u = R.pack(x, q, jnp.array([0.0, 1e-3, -4e-3, 0, 0, 0]) if rigid_belt else None)
    st = LA.structure(m, s.n_border)
    fun = lambda v: R.residual(m, p, s, v)  # noqa: E731
    r, A = jax.jit(lambda v: LA.jacobian(fun, v, st, not rigid_belt))(u)
    J = np.asarray(jax.jit(jax.jacfwd(fun))(u))
    Jb = np.asarray(LA.to_dense(st, A))
    np.testing.assert_allclose(Jb, J, rtol=0, atol=TOL_IDENTITY * np.abs(J).max())
    d = np.asarray(jax.jit(lambda A, v: LA.solve_flat(st, LA.factor(A), v))(A, r))
    ref = np.linalg.solve(J, np.asarray(r))
    np.testing.assert_allclose(d, ref, rtol=0, atol=TOL_LINALG * np.abs(ref).max())


def test_check_static_names_the_level():
    info = EQ.StaticInfo(np.array([3, 40]), np.array([1, 9]), np.array([20, 300]), np.array([1e-3, 5.0]),
                         np.array([0.07, 0.07]), np.array([7e4, 7e4]), np.array([True, False]))
    with pytest.raises(SimulationError, match=r"E02 level 1 \(60 kN\).*40 Newton iterations.*5 N above"):
        EQ.check_static(info, lambda k: f"E02 level {k} ({[30, 60][k]} kN)")
    EQ.check_static(jax.tree_util.tree_map(lambda a: a[:1], info), "E02")  # converged: no error


# ---- agreement with settled transients (slow: each transient is ~10^4 explicit steps) -----------
LEVELS = (10e3, 20e3, 30e3, LOAD)
LATERALS = (1e3, 3e3, LATERAL)


@pytest.fixture(scope="module")
def statics(coarse_tire):
    """Inflation, the vertical path to LOAD and the lateral path to LATERAL, one static program."""
    m, p = coarse_tire.model, coarse_tire.params
    run = jax.jit(lambda prm: EQ.static_path(m, prm, P, EQ.vertical_levels(P, jnp.asarray(LEVELS)),
                                             EQ.lateral_levels(P, LOAD, jnp.asarray(LATERALS))))
    path = run(p)
    EQ.check_static(path.infos, lambda k: f"static path level {k}")
    return path


def _plan(model, params, branches, ke_tol):
    """Run phase branches eagerly (jtire.experiments.program); check every phase settled."""
    from jtire.experiments.program import check_phase, phase, run_plan

    y0 = TireState.at_rest(model, len(params.relaxation_times))
    outs, y, mem = run_plan(model, params, branches, y0, {"z_road": jnp.nan}, ke_tol, 3)
    outs = jax.device_get(outs)
    for i in range(len(branches)):
        check_phase(f"phase {i}", phase(outs, i), model)
    return y, mem


@pytest.fixture(scope="module")
def transients(coarse_tire):
    """The same loads as explicit transients with every loss zero (statics have no viscoelastic
    lag) and a tight settle (KE < 1e-9 J): inflate, load ramp to LOAD, lateral ramp to LATERAL.
    Returns the end states (inflated, loaded, lateral)."""
    from jtire import solve
    from jtire.experiments import phases
    from jtire.experiments.loads import DOWN, LEFT, RIM_YZ, RIM_Z

    m, p = coarse_tire.model, coarse_tire.params.without_damping()
    proto = phases.Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-9, inflate_ramp=0.04, inflate_max=1.0,
                                           load_ramp=0.2, settle_max=1.5))
    case = phases.Case.of(LOAD, P, solve.stable_step(m, p, P, 300.0))
    road = lambda mem: phases.flat_road(mem["z_road"])  # noqa: E731
    inflate = phases.inflate_branch(case, proto, phases.flat_road(-phases.FAR))
    load = phases.load_branch(m, case, proto, road, LOAD * DOWN, RIM_Z, ramp=0.2, hold=1.7)
    lateral = phases.load_branch(m, case, proto, road, LOAD * DOWN + LATERAL * LEFT, RIM_YZ, force0=LOAD * DOWN,
                                 ramp=0.2, hold=1.7)
    ends = []
    for k in (1, 2, 3):  # the end state of each phase: the plan's first k phases
        y, _ = _plan(m, p, [inflate, load, lateral][:k], proto.ke_tol)
        ends.append(y)
    return ends


@pytest.mark.slow
def test_inflation_matches_the_settled_transient(statics, transients, coarse_tire):
    m = coarse_tire.model
    inf = transients[0]
    y0 = jax.tree_util.tree_map(lambda a: a[0], statics.ys)
    us, ut, uref = (np.asarray(R.pack(y.x, y.q)) for y in (y0, inf, TireState.at_rest(m, 3)))
    assert np.abs(us - ut).max() <= TOL_INFLATE * np.abs(ut - uref).max()


@pytest.mark.slow
@pytest.mark.gate
def test_loaded_deflection_matches_the_settled_transient(statics, transients):
    k = 1 + len(LEVELS)  # level 0 inflation, 1 the touch
    assert float(statics.rim_force[k, 2]) == pytest.approx(-LOAD)
    d_static, d_trans = -float(statics.q[k, 2]), -float(transients[1].q[2])
    assert d_static == pytest.approx(d_trans, rel=TOL_DEFLECTION)
    assert float(statics.contact[k, 2]) == pytest.approx(LOAD, rel=1e-6)  # the road carries the load


@pytest.mark.slow
@pytest.mark.gate
def test_lateral_deflection_matches_the_settled_transient(statics, transients):
    k = 1 + len(LEVELS)
    y_static = float(statics.q[-1, 1] - statics.q[k, 1])
    y_trans = float(transients[2].q[1] - transients[1].q[1])
    assert y_static == pytest.approx(y_trans, rel=TOL_LATERAL)
    assert float(statics.contact[-1, 1]) == pytest.approx(-LATERAL, rel=1e-5)


@pytest.mark.slow
def test_rigid_belt_hold_matches_the_settled_transient(coarse_tire):
    """E07 / E05-like belt load (a lateral force and an in-plane moment at once) on the rigid belt,
    rim held: the belt's displacement and rotation from the inflated pose."""
    from jtire import solve
    from jtire.experiments import phases
    from jtire.experiments.loads import RIM_LOCKED
    from jtire.physics.rigid_belt import belt_motion

    m = coarse_tire.model
    load6 = np.array([0.0, 4000.0, 0.0, 0.0, 7000.0, 0.0])
    tire = coarse_tire
    proto = phases.Protocol.from_dict(dict(settle_damping=300.0, ke_tol=1e-9, inflate_ramp=0.04, inflate_max=1.0,
                                           load_ramp=0.1, settle_max=1.5))
    dt = solve.stable_step(m, tire.params, P, 300.0)
    kw = dict(surface=phases.flat_road(-phases.FAR), rigid_belt=True, damping=proto.settle_damping,
              belt_load0=np.zeros(6))

    def inflate(y, t, mem):
        d = phases.make_drive(P, dt, pressure0=0.0, t0=t, t1=t + proto.inflate_ramp, belt_load1=np.zeros(6), **kw)
        return phases.Phase(d, y, proto.inflate_max, proto.inflate_ramp), mem

    def hold(y, t, mem):
        d = phases.make_drive(P, dt, t0=t, t1=t + proto.load_ramp, rim_free=RIM_LOCKED, belt_load1=load6, **kw)
        return phases.Phase(d, y, proto.load_ramp + proto.settle_max, proto.load_ramp), mem

    pose = lambda y: belt_motion(y.x, m.x_ref, m.node_mass, m.belt_mask)  # noqa: E731
    inf, _ = _plan(m, tire.params, [inflate], proto.ke_tol)
    held, _ = _plan(m, tire.params, [inflate, hold], proto.ke_tol)
    trans = [b - a for a, b in zip(pose(inf), pose(held))]
    path = jax.jit(lambda prm: EQ.static_path(m, prm, P, EQ.belt_levels(P, load6[None]), rigid_belt=True))(tire.params)
    EQ.check_static(path.infos, lambda k: f"belt level {k}")
    ys = [jax.tree_util.tree_map(lambda a, k=k: a[k], path.ys) for k in (0, 1)]
    stat = [b - a for a, b in zip(pose(ys[0]), pose(ys[1]))]
    np.testing.assert_allclose(stat[0][1], trans[0][1], rtol=TOL_BELT)  # lateral displacement
    np.testing.assert_allclose(stat[1][1], trans[1][1], rtol=TOL_BELT)  # in-plane rotation


# ---- implicit derivatives -------------------------------------------------------------------------
@pytest.mark.slow
def test_implicit_derivative_matches_central_differences(coarse_tire):
    """d(deflection at 20 kN)/d(theta) along a direction in three MaterialParams leaves and the
    pressure, by forward mode through the load path (friction anchors carried), against central
    differences of solves to 1e-10 of the load scale."""
    m, p = coarse_tire.model, coarse_tire.params
    tight = EQ.NewtonOptions(rtol=jnp.asarray(1e-10))

    def defl(prm, pres):
        path = EQ.static_path(m, prm, pres, EQ.vertical_levels(pres, jnp.array([10e3, 20e3])), opts=tight)
        return -path.q[-1, 2]

    tp = jax.tree_util.tree_map(jnp.zeros_like, p)
    tp = eqx.tree_at(lambda a: (a.E_meridional, a.tread_E, a.friction), tp,
                     (jnp.zeros(6).at[2].set(1e9), jnp.asarray(1e7), jnp.asarray(0.5)))
    tpres = jnp.asarray(1e4)
    _, d = jax.jit(lambda prm, pr: jax.jvp(defl, (prm, pr), (tp, tpres)))(p, jnp.asarray(P))
    f = jax.jit(defl)
    h = 1e-4
    shift = lambda s: jax.tree_util.tree_map(lambda a, b: a + s * h * b, p, tp)  # noqa: E731
    fd = (f(shift(1), P + h * tpres) - f(shift(-1), P - h * tpres)) / (2 * h)
    assert float(d) == pytest.approx(float(fd), rel=TOL_GRAD)
