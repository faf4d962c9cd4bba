"""The calibration's gradient route through the shell model: the Jacobian of E02's deflection at
50 kN (a calibration target, solved as a static equilibrium) with respect to the study's free
parameters, by forward mode through the static solve (implicit derivatives), against central
differences of two full evaluations.

Slow: three programs are compiled (the Jacobian, and the two-case evaluation): ~6 min here.
Measured on the coarse ring: relative difference 2e-6 on the largest entry (step 1e-3 in ln theta:
the quotient's O(h^2) error ~1e-6 plus solver noise / h ~1e-7); the stated tolerance 1e-4.
"""

import numpy as np
import pytest

from .conftest import COARSE_SET, REPO

TOL = 1e-4


@pytest.mark.slow
def test_static_deflection_jacobian_matches_central_differences():
    from jtire import batch
    from jtire.calibration.shell import ShellSimulator, traced_jacobian
    from jtire.calibration.spec import load_calibration

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
    k = int(np.argmax(np.abs(J[0])))
    h = 1e-3
    tp, tm = theta.copy(), theta.copy()
    tp[k] += h
    tm[k] -= h
    r = batch.run(exp, sim.tire, conds * 2, params_list=[sim.params(tp), sim.params(tm)])
    fd = (r[0].quantities["deflection_m"] - r[1].quantities["deflection_m"]) / (2 * h)
    assert J[0, k] == pytest.approx(fd, rel=TOL)
