"""E05 / E07 / E08 (rigid belt, rim locked, no road): invariants of the model, on the coarse ring.

There is no closed form for the sidewall stiffnesses, so the tests check what must hold whatever
the material: the belt stays rigid, the load never enters, the release has no artificial damping
(and no damping at all once every loss is zero), the stiffnesses are positive, finite and rise
with the inflation pressure, and the belt behaves as a single-DOF oscillator (its own mass times
omega_n^2 is the static stiffness, up to the sidewalls' share of the motion).
All runs share one compiled program (rigid belt, N_SAVE samples).
"""

import dataclasses

import numpy as np
import pytest

from jtire import units as U
from jtire.experiments import sidewall
from jtire.experiments.registry import REGISTRY
from jtire.cli.run import load_run_config

from .conftest import REPO
from jtire.signals import free_decay

P_HI, P_LO = 120 * U.PSI, 80 * U.PSI
DECAY = 0.1  # s: ~3 periods of the 25-37 Hz belt modes, enough for two peaks and the fit

# Tolerances, each with its reason.
# belt node distances after a slow, damped hold: the explicit rigid-body update drifts O((h w)^2)
# per step (measured 6e-8 m after a 17 mrad rotation); 1e-6 m is 1e-4 of the belt's ~8 mm motion
TOL_RIGID_M = 1e-6
TOL_XI_UNDAMPED_FIT = 1e-3  # symplectic Euler has no numerical dissipation (a damped model gives ~0.015)
TOL_XI_UNDAMPED_2P = 2e-3  # two peaks also see the beating of the sidewall modes (measured ~1e-3)
TOL_SDOF = 0.10  # k_own_mass*omega^2 vs static k: sidewall mass share and viscoelastic stiffening, a few % each
TOL_CROSS = 1e-9  # m or rad: motion off the loaded axis vanishes by the tire's mirror symmetry


class NoLoad(dict):
    """A condition that raises if the load is read: the rigid-belt runs must not use it."""

    def __getitem__(self, key):
        if key == "load_N":
            raise AssertionError("the rigid-belt experiment read the load")
        return super().__getitem__(key)

    def get(self, key, default=None):
        return self[key] if key in self else default


@pytest.fixture(scope="module")
def proto(short_protocol):
    return short_protocol


@pytest.fixture(scope="module")
def runs(coarse_tire, proto):
    """Inflated states at two pressures, the three held states at each, undamped releases."""
    out = {}
    for p in (P_HI, P_LO):
        dt, inf = sidewall.inflate_rigid(coarse_tire, p, proto)
        r = sidewall.belt_radius(coarse_tire.model, inf.y)
        out[p] = dict(dt=dt, inf=inf, r=r, held={})
        for case, (_, build, *_rest) in sidewall.CASES.items():
            f = {"inplane_rotation": 15e3, "sidewall_translation": 2e3, "sidewall_camber": 5e3}[case]
            load6 = build(f, r)
            out[p]["held"][case] = (load6, sidewall.hold(coarse_tire, p, proto, dt, inf, load6))
    hi = out[P_HI]
    undamped = dataclasses.replace(coarse_tire, params=coarse_tire.params.without_damping())
    out["undamped"] = {}
    for case in ("inplane_rotation", "sidewall_translation"):
        load6, held = hi["held"][case]
        out["undamped"][case] = sidewall.release(undamped, P_HI, proto, hi["dt"], held, load6, DECAY, 1e-3,
                                                 params=undamped.params)
    return out


def _stiffness(model, run, case):
    load6, held = run["held"][case]
    x = sidewall.coordinate(case, sidewall.belt_pose(model, held.y)) - \
        sidewall.coordinate(case, sidewall.belt_pose(model, run["inf"].y))
    return float(np.abs(load6).max()) / abs(x)


def test_every_phase_settled(runs):
    for p in (P_HI, P_LO):
        assert bool(runs[p]["inf"].settled)
        for case, (_, held) in runs[p]["held"].items():
            assert bool(held.settled), (p, case)
            assert not bool(held.blew_up)


def test_stiffness_positive_and_rises_with_pressure(coarse_tire, runs):
    for case in sidewall.CASES:
        k_hi = _stiffness(coarse_tire.model, runs[P_HI], case)
        k_lo = _stiffness(coarse_tire.model, runs[P_LO], case)
        assert np.isfinite(k_hi) and k_hi > 0, case
        # inflation pressure pre-tensions the sidewall cords: every sidewall stiffness grows with it
        assert k_hi > k_lo > 0, (case, k_lo, k_hi)


def test_load_moves_only_its_own_axis(coarse_tire, runs):
    m = coarse_tire.model
    run = runs[P_HI]
    d0, r0 = sidewall.belt_pose(m, run["inf"].y)
    own = {"inplane_rotation": 4, "sidewall_translation": 1, "sidewall_camber": 3}
    for case, (_, held) in run["held"].items():
        d, r = sidewall.belt_pose(m, held.y)
        motion = np.concatenate([d - d0, r - r0])
        assert abs(motion[own[case]]) > 1e-4, case
        motion[own[case]] = 0.0
        assert np.abs(motion).max() < TOL_CROSS, (case, motion)


def test_belt_stays_rigid(coarse_tire, runs):
    m = coarse_tire.model
    run = runs[P_HI]
    inf = run["inf"]
    for case, (_, held) in run["held"].items():
        assert sidewall.belt_rigidity_error(m, inf.y, held.y) < TOL_RIGID_M, case
    # After a free rotation decay (where a rigid update could drift): the explicit rigid-body
    # update changes distances by at most (h w)^2 * 2r per step, so the bound is
    # n_steps (h w_max)^2 2 r, w_max from the recorded rotation (measured ~4e-6 m vs ~2e-5 m).
    ts, dec = runs["undamped"]["inplane_rotation"]
    rot = np.asarray(dec.saved["belt_rot"])[:, 1]
    w_max = np.abs(np.diff(rot) / np.diff(ts)).max()
    bound = int(dec.n_steps) * (run["dt"] * w_max) ** 2 * 2 * run["r"]
    assert sidewall.belt_rigidity_error(m, inf.y, dec.y) < bound
    assert bound < 5e-3 * np.ptp(rot) * run["r"]  # ... and the bound is far below the belt's own motion
    # the sidewalls did deform (the test would pass trivially if nothing moved)
    side = np.asarray(m.belt_mask) == 0
    moved = np.abs(np.asarray(run["held"]["inplane_rotation"][1].y.x.x) - np.asarray(inf.y.x.x))[side].max()
    assert moved > 1e-3


@pytest.mark.parametrize("case,mass", [("inplane_rotation", 17.4026), ("sidewall_translation", 70.75)])
def test_no_damping_gives_no_decay(coarse_tire, runs, case, mass):
    ts, dec = runs["undamped"][case]
    s = dec.saved
    field, comp = sidewall.CASES[case][2]
    x0 = sidewall.coordinate(case, sidewall.belt_pose(coarse_tire.model, runs[P_HI]["inf"].y))
    x = np.asarray(s[field])[:, comp] - x0
    fd = free_decay(ts, x, mass, t_start=float(ts[0]) + 1e-3, x_final=0.0)
    assert fd.xi_fit < TOL_XI_UNDAMPED_FIT, fd.xi_fit
    assert fd.two_peak_ok and fd.xi_2p < TOL_XI_UNDAMPED_2P, (fd.two_peak_reason, fd.xi_2p)
    # nothing dissipated, no artificial damping: exactly zero
    assert np.ptp(np.asarray(s["dissipated"])) == 0.0
    assert np.ptp(np.asarray(s["settle_work"])) == 0.0


def test_translation_runner(coarse_tire, proto):
    """The registered E07 runner: never reads the load, positive stiffness and damping, a clean
    single-DOF decay, no artificial damping in the release."""
    cond = NoLoad(pressure_Pa=P_HI, load_N=45e3)
    res = REGISTRY["sidewall_translation"].runner(coarse_tire, cond, proto, force_kN=2e3, decay_s=DECAY,
                                                  release_ramp_ms=1e-3, mass_kg=70.75)
    q, c = res.quantities, res.checks
    assert res.condition == {"pressure_Pa": P_HI}
    assert np.isfinite(q["k_by_N_per_m"]) and q["k_by_N_per_m"] > 0
    assert q["load_N"] == pytest.approx(4e3)
    for key in ("C_by_Ns_per_m", "C_by_2p_Ns_per_m", "C_by_fit_Ns_per_m", "xi_2p", "xi_fit"):
        assert np.isfinite(q[key]) and q[key] > 0, key
    # loss tangents are 0.10-0.15, so a modal damping ratio cannot exceed ~tan(delta)/2
    assert q["xi_fit"] < 0.1
    assert abs(c["k_dynamic_vs_static_rel"]) < TOL_SDOF, c["k_dynamic_vs_static_rel"]
    assert c["release_settle_work_J"] == 0.0
    assert c["release_rubber_dissipated_J"] > 0
    assert c["belt_rigidity_error_m"] < TOL_RIGID_M
    assert c["cross_motion_max"] < TOL_CROSS
    assert len(res.signals["time_s"]) == len(res.signals["y_m"])


def test_registry_and_configs_do_not_need_a_load():
    for name in ("inplane_rotation", "sidewall_translation", "sidewall_camber"):
        assert REGISTRY[name].needs_load is False
        _, exps, cond, _ = load_run_config(REPO / "configs" / "experiments" / f"{name}.toml",
                                           ["condition.load_kg=4625"])
        assert exps[0][0].name == name
        assert "load_N" not in cond  # a load given in the file is ignored, never passed on
