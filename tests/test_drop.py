"""E04 drop test and the E09 release decay, on the coarse ring.

Invariants: the release has no artificial damping; with every loss and friction off the drop
conserves energy through the impacts (so the damping measured with losses on is the rubber's);
the wheel comes to rest on the road carrying exactly the load; damping ratios are positive and
below what the rubber's loss tangents allow; after the lateral release the rim returns to where it
was before the lateral force (the patch sticks: 5 kN << mu F_z).
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jtire import solve
from jtire import units as U
from jtire.errors import ConfigError
from jtire.experiments import drop
from jtire.experiments.registry import REGISTRY
from jtire.physics.contact import RAMP_EPS

P = 120 * U.PSI
LOAD = 4625 * U.G0
H = 0.02  # m, drop height (the study's)

# Tolerances, each with its reason.
TOL_EQUILIBRIUM = 0.02  # settled contact force vs load: settling stops at KE < 1e-3 J, and the stiff
#                         tread contact still rings a little then (measured 0.9 % on the full ring)
TOL_ENERGY = 0.005  # of the load's work F (h + d_max): symplectic Euler's bounded energy error
#                     (measured 4e-4); the same drop with the rubber's losses on loses 13 %
XI_MAX = 0.1  # the loss tangents are 0.10-0.15: a structural damping ratio stays below ~tan(delta)/2
TOL_RETURN = 0.05  # of y_ss: the rim returns to its pre-load position when the patch sticks


@pytest.fixture(scope="module")
def proto(short_protocol):
    return short_protocol


@pytest.fixture(scope="module")
def dropped(coarse_tire, proto):
    return REGISTRY["drop_test"].runner(coarse_tire, {"pressure_Pa": P, "load_N": LOAD}, proto, drop_height_mm=H,
                                        duration_s=0.25, gravity=False, k_sv_from="settle", m_tot_kg=111.25)


def test_bad_k_sv_source_is_refused_before_any_simulation(coarse_tire, proto):
    with pytest.raises(ConfigError, match="k_sv_from"):
        drop.run_drop(coarse_tire, {"pressure_Pa": P, "load_N": LOAD}, proto, H, 0.25, False, "guess", 111.25)


def test_drop_result(dropped):
    q, c = dropped.quantities, dropped.checks
    for key in ("C_tot_Ns_per_m", "C_tot_2p_Ns_per_m", "C_tot_fit_Ns_per_m", "k_sv_N_per_m", "xi_2p", "xi_fit"):
        assert np.isfinite(q[key]) and q[key] > 0, key
    assert q["xi_2p"] < XI_MAX and q["xi_fit"] < XI_MAX
    # C_tot = 2 xi sqrt(m_tot k_sv) with the two-peak xi (the study's method)
    assert q["C_tot_Ns_per_m"] == pytest.approx(2 * q["xi_2p"] * np.sqrt(111.25 * q["k_sv_N_per_m"]), rel=1e-12)
    assert c["drop_settle_work_J"] == 0.0  # the settle damping is off during the drop
    assert c["drop_rubber_dissipated_J"] > 0
    assert c["settle_settled"]
    assert c["static_contact_vs_load_rel_error"] < TOL_EQUILIBRIUM
    # the wheel went deeper than its static deflection on the first impact, and the k_sv
    # deflection is measured from first contact
    assert c["max_deflection_m"] > q["static_deflection_m"] > 0
    assert q["k_sv_N_per_m"] == pytest.approx(LOAD / q["static_deflection_m"])
    sig = dropped.signals
    assert len({len(v) for v in sig.values()}) == 1


def _energy(model, params, y, pressure, load, z_road):
    """Total mechanical energy (J) of state y: kinetic (absolute velocities), elastic, gas
    (-p V at constant p), the rim load's potential (F z) and the tread's penalty energy."""
    X = model.assemble(y.x, y.q)
    m = np.asarray(model.node_mass)
    v2 = np.asarray(y.v.x) ** 2 + np.asarray(y.v.y) ** 2 + np.asarray(y.v.z) ** 2
    M = np.concatenate([np.full(3, float(model.rim_mass)), np.asarray(model.rim_inertia)])
    ke = 0.5 * np.sum(m * v2) + 0.5 * np.sum(M * np.asarray(y.qd) ** 2)
    pen = np.maximum(z_road - np.asarray(model.tread_points(X).z), 0.0)
    e = RAMP_EPS  # integral of the smooth contact ramp (geometry_ops.smooth_ramp) from 0 to pen
    ramp_int = np.where(pen <= e, pen**3 / (6 * e), e**2 / 6 + 0.5 * (pen**2 - e**2) - 0.5 * e * (pen - e))
    k_n = np.asarray(model.contact_stiffness(params)[0])
    return (ke + float(model.strain_energy(params, X)) - pressure * float(model.volume(X))
            + load * float(y.q[2]) + float(np.sum(k_n * ramp_int)))


def test_undamped_frictionless_drop_conserves_energy(coarse_tire, proto):
    # zeros_like keeps the weak type of the leaf: no recompilation
    base = coarse_tire.params
    params = eqx.tree_at(lambda p: p.friction, base.without_damping(), jnp.zeros_like(base.friction))
    tire = dataclasses.replace(coarse_tire, params=params)
    dt, inf, z_road, ts, fall = drop.drop(tire, P, LOAD, proto, H, 0.1, gravity=False)
    solve.check_phase("drop", fall, tire.model, require_settled=False)
    s = fall.saved
    assert np.asarray(s["n_contact"]).max() > 0  # it did hit the road
    assert np.ptp(np.asarray(s["dissipated"])) == 0.0 and np.ptp(np.asarray(s["settle_work"])) == 0.0
    e0 = _energy(tire.model, params, inf.y, P, LOAD, z_road)
    e1 = _energy(tire.model, params, fall.y, P, LOAD, z_road)
    d_max = -np.asarray(s["q"])[:, 2].min()
    assert abs(e1 - e0) < TOL_ENERGY * LOAD * d_max, (e1 - e0, LOAD * d_max)


def test_lateral_release_decay(coarse_tire, proto):
    res = REGISTRY["lateral_stiffness"].runner(coarse_tire, {"pressure_Pa": P, "load_N": LOAD}, proto,
                                               force_kN=5e3, decay_s=0.15, release_ramp_ms=1e-3, mass_kg=111.25)
    q, c = res.quantities, res.checks
    assert np.isfinite(q["k_l_N_per_m"]) and q["k_l_N_per_m"] > 0
    for key in ("C_l_Ns_per_m", "C_l_2p_Ns_per_m", "C_l_fit_Ns_per_m", "xi_fit"):
        assert np.isfinite(q[key]) and q[key] > 0, key
    assert q["xi_fit"] < XI_MAX
    assert c["release_settle_work_J"] == 0.0
    assert abs(c["release_final_level_minus_preload_m"]) < TOL_RETURN * q["lateral_deflection_m"]
