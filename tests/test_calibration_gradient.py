"""The calibration's gradient route through the shell model: the Jacobian of E02's deflection at
50 kN (a calibration target, solved as a static equilibrium) with respect to the study's free
parameters, by forward mode through the static solve (implicit derivatives), against central
differences of two full evaluations; and E12's drag by reverse mode through the transient against
forward mode and central differences.

Slow: three programs are compiled (the Jacobian, and the two-case evaluation): ~6 min here.
The static Jacobian is checked entry by entry for the largest entry of each kind of leaf, and as a
whole along a random unit direction over every nonzero entry (two static solves each, side by side), to
TOL of the row's largest entry: a central difference's errors (its O(h^2) term and the solver's
residual noise / h) are set by the function's scale, not by each entry's, so a small entry is held to
the same absolute accuracy as the largest. Measured on the coarse ring (step 1e-3 in ln theta), over the
16 nonzero entries: 2.0e-5 of the largest entry at the worst (median 9e-6; the largest entry itself
2e-6: the O(h^2) term ~1e-6, the rest the solver's residual noise / h); the stated tolerance 1e-4.
E12's reverse-mode row is checked entry by entry where it is largest, and as a whole along a random
direction (one pair of runs: any wrong entry moves J v).
"""

import numpy as np
import pytest

from .conftest import COARSE_SET, REPO

TOL = 1e-4


@pytest.mark.slow
@pytest.mark.gate
def test_static_deflection_jacobian_matches_central_differences():
    from jtire import batch
    from jtire.calibration.tire.shell import ShellSimulator, traced_jacobian
    from jtire.calibration.tire.spec import load_calibration

    spec = load_calibration(REPO / "configs" / "calibration" / "study.toml", COARSE_SET)
    sim = ShellSimulator(spec, spec.tire, {"settle_damping_per_s": 300.0, "ke_tol_J": 1e-3})
    g = sim.groups[0]
    exp = g["exp"]
    assert exp.name == "vertical_stiffness" and exp.method == "static"
    theta = np.asarray(spec.space.from_params(spec.base_params))
    conds = [t.condition for _, t in g["targets"]]
    v, J = traced_jacobian(exp, sim.tire, sim.params, theta, conds, ["deflection_m"])
    assert 0.02 < v[0] < 0.06
    # the losses (tan delta) do not enter a static solve: their columns are exactly zero
    names = [n for n in spec.space.names]
    for i, n in enumerate(names):
        if "loss" in n or "tan_delta" in n:
            assert J[0, i] == 0.0, n
    nonzero = [i for i in range(len(names)) if J[0, i] != 0.0]
    assert len(nonzero) >= len(names) // 2
    # entry by entry: the largest entry of each kind of leaf (E_meridional, G_shear, tread.G, ...: each kind
    # reaches the solve through its own gather); every nonzero entry at once along a random direction
    kinds = {}
    for i in nonzero:
        kind = names[i].rsplit(".", 1)[-1] if names[i].startswith("parts.") else names[i]
        if kind not in kinds or abs(J[0, i]) > abs(J[0, kinds[kind]]):
            kinds[kind] = i
    cols = sorted(kinds.values())
    v = np.random.default_rng(0).normal(size=len(theta))
    v[[i for i in range(len(names)) if i not in nonzero]] = 0.0
    h = 1e-3
    steps = [*[np.eye(len(theta))[i] for i in cols], v / np.linalg.norm(v)]
    thetas = [theta + s * h * e for e in steps for s in (1.0, -1.0)]
    r = batch.run(exp, sim.tire, conds * len(thetas), params_list=[sim.params(t) for t in thetas])
    d = np.array([r[k].quantities["deflection_m"] for k in range(len(thetas))])
    fd = (d[0::2] - d[1::2]) / (2 * h)
    exact = np.array([*J[0, cols], J[0] @ steps[-1]])
    err = np.abs(exact - fd) / np.max(np.abs(J[0]))
    assert np.max(err) < TOL, (np.max(err), ([names[i] for i in cols] + ["random direction"])[int(np.argmax(err))])


@pytest.mark.slow
def test_reverse_mode_through_rolling_matches_forward_mode_and_central_differences():
    """d(E12 drag)/d(ln leaf) by reverse mode through the transient (every phase checkpointed:
    `experiments.program.reverse_mode`) equals forward mode (jvp) and central differences with the
    step held, on the coarse ring with short stages. Measured (the two largest entries): reverse,
    jvp and central differences with h = 1e-4 agree in all 6 digits printed (h = 1e-3 is off by up to 7 %: the drag of a
    short run is strongly curved in the stiffnesses, the O(h^2) term dominates). Tolerances: 1e-6
    between the two autodiff modes (same arithmetic, summed in another order), 1e-4 against
    differences. Slow: two large programs compile (~10 min here)."""
    import jax
    import jax.flatten_util
    import jax.numpy as jnp

    from jtire import batch
    from jtire.calibration.tire.shell import traced_jacobian
    from jtire.config import load_run_config
    from jtire.experiments import Case
    from jtire.tire import make_tire

    short = ["rolling_resistance.method=transient", "rolling_resistance.settle_s=0.02", "rolling_resistance.ramp_s=0.02",
             "rolling_resistance.release_s=0.01", "rolling_resistance.measure_s=0.03"]
    rc = load_run_config(REPO / "configs" / "experiments" / "rolling_resistance.toml", COARSE_SET + short)
    tire = make_tire(rc.tire)
    exp, model = rc.experiments[0], tire.model
    flat, unravel = jax.flatten_util.ravel_pytree(tire.params)
    th0 = np.log(np.asarray(flat))
    params_of = lambda th: unravel(jnp.exp(th))  # noqa: E731
    v, J = traced_jacobian(exp, tire, params_of, th0, [rc.condition], ["rolling_resistance_N"], mode="reverse")
    J = J[0]
    assert np.all(np.isfinite(J)) and v[0] > 0
    k = int(np.argmax(np.abs(J)))
    cases = exp.cases(rc.condition)
    dts = batch.stable_steps(model, [tire.params] * len(cases), [c["pressure_Pa"] for c in cases],
                             float(exp.proto.settle_damping))
    one = [Case.of(c.get("load_N", 0.0), c["pressure_Pa"], dts[i], exp.aux(c)) for i, c in enumerate(cases)]

    def drag(th):
        p = params_of(th)
        return exp.traced(model, p, cases, [exp.simulate(model, p, c) for c in one])["rolling_resistance_N"]

    e = np.zeros_like(th0)
    e[k] = 1.0
    val, tangent = jax.jvp(drag, (jnp.asarray(th0),), (jnp.asarray(e),))
    assert float(val) == pytest.approx(v[0], rel=1e-9)
    assert J[k] == pytest.approx(float(tangent), rel=1e-6)
    h = 1e-4
    fd = (float(drag(jnp.asarray(th0 + h * e))) - float(drag(jnp.asarray(th0 - h * e)))) / (2 * h)
    assert J[k] == pytest.approx(fd, rel=1e-4)
    # every entry at once: the derivative along a random unit direction (a wrong entry of weight ~1/sqrt(d)
    # in it moves J v by its error / sqrt(d))
    v = np.random.default_rng(0).normal(size=th0.shape)
    v /= np.linalg.norm(v)
    fd_v = (float(drag(jnp.asarray(th0 + h * v))) - float(drag(jnp.asarray(th0 - h * v)))) / (2 * h)
    assert float(J @ v) == pytest.approx(fd_v, rel=1e-4, abs=1e-4 * np.max(np.abs(J)))
