"""Derived rigid-ring quantities (docs/rigid-ring.md §3, §5, §7): closed-form identities.

Tolerances are float64 round-off (1e-12 relative) unless stated: each identity is algebraic.
"""

import dataclasses
import math

import jax.numpy as jnp
import pytest

from jtire.errors import ConfigError
from jtire.rigid_ring import synthetic
from jtire.rigid_ring.params import RigidRingParams, derive


@pytest.fixture(scope="module")
def char():
    return synthetic.characterization()


def test_vertical_split_variant_a_identities(char):
    for r in char.rows:
        d = derive(r, char.tire)
        assert d.variant_used == "A" and d.variant_A_valid
        # statically in series, dynamically (rim locked, belt on the drum) in parallel
        assert 1 / d.k_bz + 1 / d.k_vr == pytest.approx(1 / d.k_sv, rel=1e-12)
        assert d.k_bz + d.k_vr == pytest.approx(d.k_dv, rel=1e-12)
        assert d.k_bz >= d.k_vr  # the larger root goes to the sidewall
        # variant B: k_bz = k_dv and the same series law
        assert d.k_bz_B == d.k_dv and 1 / d.k_bz_B + 1 / d.k_vr_B == pytest.approx(1 / d.k_sv, rel=1e-12)
        # one time constant: the series pair is exactly k_sv || tau k_sv
        assert d.C_bz / d.k_bz == pytest.approx(d.C_tot / d.k_sv) and d.C_vr / d.k_vr == pytest.approx(d.tau)
        assert (d.k_bx, d.C_bx) == (d.k_bz, d.C_bz) and d.k_bx_source.startswith("isotropy")


def test_k_bx_and_C_bx_from_e13_when_measured(char):
    r = char.rows[0]
    e13 = {"k_bx_N_per_m": 3.1 * r.q["k_sv_N_per_m"], "C_bx_Ns_per_m": 456.0}
    d = derive(dataclasses.replace(r, q=r.q | e13), char.tire)
    assert (d.k_bx, d.C_bx, d.k_bx_source) == (e13["k_bx_N_per_m"], 456.0, "E13")
    assert d.k_bx_measured and not derive(r, char.tire).k_bx_measured
    assert 1 / d.C_x == pytest.approx(1 / d.k_cx + 1 / d.k_bx + d.r_b**2 / d.k_btheta)
    assert d.k_bz != d.k_bx  # the vertical split is untouched
    # a spring without its decay: the damper from the time constant, and the source says so
    d = derive(dataclasses.replace(r, q=r.q | {"k_bx_N_per_m": e13["k_bx_N_per_m"]}), char.tire)
    assert d.C_bx == pytest.approx(d.tau * d.k_bx) and "no decay" in d.k_bx_source


def test_variant_b_used_when_a_invalid(char):
    r = char.rows[0]
    d = derive(dataclasses.replace(r, q=r.q | {"k_dv_N_per_m": 2.0 * r.q["k_sv_N_per_m"]}), char.tire)
    assert not d.variant_A_valid and d.variant_used == "B" and d.k_bz_A is None
    assert d.k_bz == d.k_dv and d.k_vr == pytest.approx(2.0 * d.k_sv)  # 1/k_vr = 1/k_sv - 1/(2 k_sv)
    d = derive(dataclasses.replace(r, q=r.q | {"k_dv_N_per_m": 0.5 * r.q["k_sv_N_per_m"]}), char.tire)
    assert d.variant_used is None and "k_bz" in " ".join(d.missing("vertical"))


def test_k_cy_series_compliance_reproduces_k_l(char):
    for r in char.rows:
        d = derive(r, char.tire)
        assert d.k_cy_source.startswith("series")
        assert d.k_l_ring == pytest.approx(d.k_l, rel=1e-12)
        assert d.sigma_c == pytest.approx(d.k_f / d.k_cy) and d.C_cy == pytest.approx(d.k_cy * d.C_l / d.k_l)
        assert d.sigma == pytest.approx(d.k_f / d.k_l)


def test_tread_damper_from_the_lateral_release(char):
    """With E09's fitted release zeta in the row (xi_l_fit), C_cy is the tread damper that gives the
    ring's linear lateral release that zeta beside E07's C_by and E08's C_bgamma: a C_cy put into a ring
    comes back from the zeta it produces (bisection to 1e-9), and the release then has that zeta. A zeta
    the sidewall's dampers alone exceed has no C_cy >= 0: the fallback k_cy C_l / k_l, named with the
    range the ring spans. Without xi_l_fit, the fallback says so."""
    from jtire.rigid_ring import modes

    row = char.rated_row()
    d0 = derive(row, char.tire)
    assert "no E09 xi_l_fit" in d0.C_cy_source
    for scale in (0.3, 1.0, 2.5):
        c_true = scale * d0.C_cy
        zeta = modes.lateral_modes(dataclasses.replace(d0, C_cy=c_true), "ring")[0][1]
        d = derive(dataclasses.replace(row, q=row.q | {"xi_l_fit": zeta}), char.tire)
        assert d.C_cy == pytest.approx(c_true, rel=1e-9) and d.C_cy_source.startswith("E09's release zeta")
        assert modes.lateral_modes(d, "ring")[0][1] == pytest.approx(zeta, rel=1e-9)
        assert (d.C_by, d.C_bgamma, d.k_cy) == (d0.C_by, d0.C_bgamma, d0.k_cy)  # only the tread damper moves
    z_sidewalls = modes.lateral_modes(dataclasses.replace(d0, C_cy=0.0), "ring")[0][1]
    d = derive(dataclasses.replace(row, q=row.q | {"xi_l_fit": 0.5 * z_sidewalls}), char.tire)
    assert d.C_cy == pytest.approx(d0.C_cy) and "fallback: the ring's release spans zeta" in d.C_cy_source


def test_maxwell_branches_give_the_storage_push_at_its_frequency(char):
    """Default lateral springs: the static pushes, each sidewall spring with a Maxwell branch (relaxation
    time the tire's) sized so the ring's k_l on the springs' storage at E09's release frequency is E09's
    push on the storage moduli there, k_l' (1e-12: algebraic), and the static k_l at rest. The springs,
    k_cy and the .tir are the static ones. Without a relaxation time (a folder written before it was
    recorded), or without the storage push, no branch, and the source says why."""
    row = char.rated_row()
    tire = dataclasses.replace(char.tire, relaxation_time_s=0.04)
    k_l = row.q["k_l_N_per_m"]
    st = dataclasses.replace(row, q=row.q | {"k_l_storage_N_per_m": 1.1 * k_l, "f_l_storage_Hz": 15.0})
    d, d0 = derive(st, tire), derive(st, tire, lateral_springs="static")
    beta, tau = d.lateral_branch
    assert tau == 0.04 and beta > 0 and "Maxwell branch" in d.lateral_spring_source
    assert d.k_l_at(15.0) == pytest.approx(1.1 * k_l, rel=1e-12)
    assert d.k_l_at(0.0) == pytest.approx(k_l, rel=1e-12) and d.k_l_at(0.0) == pytest.approx(d.k_l_ring, rel=1e-12)
    assert (d.k_by, d.k_bgamma, d.k_cy, d.k_l) == (d0.k_by, d0.k_bgamma, d0.k_cy, d0.k_l)
    x2 = (2 * math.pi * 15.0 * tau) ** 2  # the sidewall's storage stiffening at 15 Hz, 1 + beta x^2/(1 + x^2)
    side = 1 / d.k_by + d.r_b**2 / d.k_bgamma
    assert 1 / (1.1 * k_l) == pytest.approx(1 / d.k_cy + side / (1 + beta * x2 / (1 + x2)), rel=1e-12)
    p = RigidRingParams.from_derived(d)
    assert float(p.k_by_branch) == pytest.approx(beta * d.k_by) and float(p.tau_branch) == tau
    assert float(RigidRingParams.from_derived(d0).k_by_branch) == 0.0
    for r, t, why in ((st, char.tire, "no relaxation time"), (row, tire, "no push on the storage moduli")):
        x = derive(r, t)
        assert x.lateral_branch is None and why in x.lateral_spring_source and x.branch_beta is None


def test_k_cy_fallback_when_ill_conditioned(char):
    r = char.rated_row()
    # a lateral sidewall as soft as the whole tire: 1/k_cy <= 0
    d = derive(dataclasses.replace(r, q=r.q | {"k_by_N_per_m": 0.9 * r.q["k_l_N_per_m"]}), char.tire)
    assert d.k_cy_source.startswith("fallback") and "1/k_cy <= 0" in d.k_cy_source
    assert d.sigma_c == d.a and d.k_cy == pytest.approx(d.k_f / d.a)
    # the ring then misses k_l, and says by how much
    k_ring = 1 / (1 / d.k_cy + 1 / d.k_by + d.r_b**2 / d.k_bgamma)
    assert d.k_l_ring_rel_error == pytest.approx(k_ring / d.k_l - 1) and d.k_l_ring_rel_error < 0


def test_lateral_springs_on_the_storage_moduli(char):
    """A row with E09's push on the rubber's storage moduli (k_l_storage, `characterize.lateral_springs`):
    the ratio r = k_l_storage / k_l is reported, the default springs stay the static pushes. With
    lateral_springs="storage", k_by, k_bgamma and k_l are the static ones x r, so the series k_cy is x r
    too and sigma_c / r; with every spring x r and the masses the same, the undamped lateral frequencies
    are x sqrt(r). E09's static k_l stays in k_l_static and the .tir (static springs) is unchanged.
    Another value is one ConfigError line."""
    from jtire.rigid_ring import modes, tir
    from jtire.rigid_ring.table import Characterization

    row = char.rated_row()
    d0 = derive(row, char.tire)
    assert d0.lateral_storage_ratio is None and d0.k_l_static == d0.k_l and not d0.uses_storage
    r = 1.08**2
    st = dataclasses.replace(row, q=row.q | {"k_l_storage_N_per_m": r * d0.k_l, "f_l_storage_Hz": 15.1})
    ds = derive(st, char.tire)
    assert ds.lateral_storage_ratio == pytest.approx(r, rel=1e-12) and not ds.uses_storage
    assert (ds.k_by, ds.k_l, ds.k_cy) == (d0.k_by, d0.k_l, d0.k_cy)
    d = derive(st, char.tire, lateral_springs="storage")
    assert d.uses_storage and "15.1 Hz" in d.lateral_spring_source
    for k in ("k_by", "k_bgamma", "k_l", "k_cy"):
        assert getattr(d, k) == pytest.approx(r * getattr(d0, k), rel=1e-12), k
    assert d.k_l_static == d0.k_l and d.sigma_c == pytest.approx(d0.sigma_c / r, rel=1e-12)
    assert (d.C_by, d.C_bgamma, d.C_l) == (d0.C_by, d0.C_bgamma, d0.C_l)  # dampers as identified

    def undamped(x):
        return [f for f, _ in modes.lateral_modes(dataclasses.replace(x, C_by=0.0, C_cy=0.0, C_bgamma=0.0), "ring")]
    assert undamped(d) == pytest.approx([math.sqrt(r) * f for f in undamped(d0)], rel=1e-9)
    swap = Characterization(char.tire, tuple(st if x is row else x for x in char.rows))
    tirs = [{k: v for sec in tir.build(c)[0].values() for k, v, _ in sec} for c in (char, swap)]
    assert tirs[1] == tirs[0]
    with pytest.raises(ConfigError, match="lateral_springs = 'dynamic': must be one of maxwell, static, storage"):
        derive(st, char.tire, lateral_springs="dynamic")


def test_structural_keys(char):
    d = derive(char.rated_row(), char.tire)
    s = d.structural()
    t = char.tire
    assert s["FREQ_LAT"] == pytest.approx(math.sqrt(d.k_by / t.m_b_kg) / (2 * math.pi))
    assert s["FREQ_WINDUP"] == pytest.approx(math.sqrt(d.k_btheta / t.I_by_kgm2) / (2 * math.pi))
    # synthetic C_by was built from zeta 0.04 x 1.04 (two-peak value)
    assert s["DAMP_LAT"] == pytest.approx(0.04 * 1.04)
    assert s["DAMP_RESIDUAL"] == pytest.approx(d.C_vr / d.k_vr)
    assert 1 / d.C_x == pytest.approx(1 / d.k_cx + 1 / d.k_bx + d.r_b**2 / d.k_btheta)


def test_missing_inputs_are_named(char):
    c = synthetic.drop(char, {"k_by_N_per_m", "contact_length_m"})
    d = derive(c.rated_row(), c.tire)
    assert d.k_cy is None and d.a is None and d.structural()["FREQ_LAT"] is None
    with pytest.raises(ConfigError, match="k_by"):
        d.require("lateral_ring", "test")
    d.require("lateral_reduced", "test")  # the reduced model does not need the sidewall


def test_params_are_float64_leaves(char):
    p = RigidRingParams.from_row(char.rated_row(), char.tire)
    for name, leaf in vars(p).items():
        assert isinstance(leaf, jnp.ndarray) and leaf.dtype == jnp.float64 and not leaf.weak_type, name
