"""E14, the standstill longitudinal stiffness C_x (coarse ring, rated condition).

- Fore-aft symmetry: the standing tire has no preferred direction of travel (its mesh and layup are
  unchanged by a half turn about the vertical axis), so a forward and a backward push of the same size
  give the same C_x, to the static solver's residual (1e-4 relative: each level is converged to a force
  residual of ~1e-6 of the load scale, and x is a 2 mm deflection under a 45 kN load).
- Linearity: a 2 kN push on a 45 kN load is far from sliding (friction ~0.9 F_z), so the secant at F/2
  equals the one at F within 1 %.
- Scheduling: E14 is static levels only, so it takes no explicit step and runs case by case, unbatched
  (a vmapped Newton loop runs both branches of its conditionals: several times an unbatched case's
  wall, docs/speed.md).
- Series bound (gate): the rim's fore-aft push goes through the sidewall (E13's k_bx), the belt's
  rotation about its centre (E05's k_btheta, the patch r below it) and the tread in series, so
  1/C_x > 1/k_bx + r^2/k_btheta with r the loaded radius (below the belt centre's height: a weaker
  bound), and the contact adds a compliance of at least 10 % of 1/C_x.
"""

import pytest

from .conftest import P_RATED, make_experiment, ok


def _q(run):
    return ok(run.results[0]).quantities


def test_forward_and_backward_pushes_agree(e14):
    fwd, back = _q(e14["forward"]), _q(e14["backward"])
    assert fwd["C_x_N_per_m"] == pytest.approx(back["C_x_N_per_m"], rel=1e-4)
    assert ok(e14["backward"].results[0]).info["direction"] == "backward"
    for q in (fwd, back):
        assert q["C_x_half_over_full"] == pytest.approx(1.0, abs=0.01)
        assert q["longitudinal_force_N"] == pytest.approx(2000.0)
        # a truck tire's fore-aft stiffness at rest is of order 1 MN/m (deflection ~2 mm under 2 kN)
        assert 2e5 < q["C_x_N_per_m"] < 5e6


def test_e14_is_static_and_runs_unbatched(protocol, spec, e14):
    exp = make_experiment("longitudinal_stiffness", protocol, spec)
    assert not exp.time_stepped and not exp.shardable
    assert "dt_s" not in ok(e14["forward"].results[0]).info  # no explicit step was computed for it


@pytest.mark.slow
@pytest.mark.gate
def test_the_contact_adds_compliance_to_the_sidewall_springs(e14, e13_runs, sidewall_runs, e01_static, coarse_tire):
    c_x = _q(e14["forward"])["C_x_N_per_m"]
    k_bx = _q(e13_runs["x"])["k_bx_N_per_m"]
    k_bt = _q(sidewall_runs["inplane_rotation"][P_RATED])["k_btheta_Nm_per_rad"]
    r_l = coarse_tire.spec.geometry.outer_radius - _q(e01_static)["deflection_m"]
    sidewall = 1.0 / k_bx + r_l**2 / k_bt
    assert 1.0 / c_x > sidewall
    assert (1.0 / c_x - sidewall) * c_x > 0.10


def test_every_experiment_declares_its_method(protocol, spec):
    """Whether a run is vmapped and given an explicit step follows from `method`; an experiment without
    one (E14 before) was taken for a transient. Each is built from its default table; a composite (E11)
    runs its components and has none of its own."""
    from jtire.experiments import REGISTRY
    from jtire.experiments.base import METHODS

    for name, cls in REGISTRY.items():
        exp = make_experiment(name, protocol, spec)
        if hasattr(exp, "components"):
            continue
        assert exp.method in METHODS, name
        assert exp.shardable <= exp.time_stepped, name  # a shardable run is time-stepped


def test_an_experiment_without_a_method_is_refused():
    from jtire.experiments.base import _method

    class NoMethod:
        pass
    with pytest.raises(TypeError, match="NoMethod: method None"):
        _method(NoMethod())
