"""The revised vertical identification (docs/rigid-ring.md §3): tangent springs with the static rest at
the secant, and C_bz, C_vr from the belt mode (E03) and the in-contact bounce (E04).

Ring -> tables -> ring: a ring with known springs and dampers is "measured" the way the shell model is
(its static law for the secant and tangent, its own drum-cleat record for the belt mode, its own drop
record after the last lift-off for the bounce), the measurements go into a table row, and derive()
must give the springs and dampers back. Tolerances: the static quantities are algebra (1e-9); the
record-based ones carry the signal reductions' error (a damped-sine fit over a finite record), stated
at each assert.
"""

import dataclasses
import math

import numpy as np
import pytest

from jtire.rigid_ring import scenarios as sc
from jtire.rigid_ring import synthetic, tir
from jtire.rigid_ring.modes import belt_vertical_mode, vertical_modes
from jtire.rigid_ring.params import RigidRingParams, derive

TANGENT_OVER_SECANT = 1.15  # the shell's load-deflection curves stiffen by 1.10-1.21x at the load
ZETA_BELT, ZETA_BOUNCE = 0.06, 0.09


@pytest.fixture(scope="module")
def char():
    return synthetic.characterization()


def _row(char, **extra):
    r = char.rated_row()
    return dataclasses.replace(r, q=r.q | extra)


@pytest.fixture(scope="module")
def truth(char):
    """A ring identified from a row that has every input of the revised identification."""
    r = char.rated_row()
    return derive(_row(char, k_sv_tangent_N_per_m=TANGENT_OVER_SECANT * r.q["k_sv_N_per_m"],
                       first_mode_xi=ZETA_BELT, xi_in_contact_fit=ZETA_BOUNCE), char.tire)


def test_tangent_springs_rest_at_the_secant(truth):
    d = truth
    assert d.stiffness_source.startswith("tangent") and d.k_vr2 > 0
    # small motions: sidewall and residual tangent in series give E02's tangent, in parallel the drum's k_dv
    assert 1 / d.k_bz + 1 / d.k_vr == pytest.approx(1 / d.k_vt, rel=1e-12)
    assert d.k_bz + d.k_vr == pytest.approx(d.k_dv, rel=1e-12)
    # the residual law's tangent at its static deflection is k_vr, its secant (1/k_sv - 1/k_bz)^-1
    rho = d.residual_deflection(d.load_N)
    assert d.k_vr1 + 2 * d.k_vr2 * rho == pytest.approx(d.k_vr, rel=1e-12)
    assert d.load_N / rho == pytest.approx(d.k_vr_secant, rel=1e-12)
    assert rho + d.load_N / d.k_bz == pytest.approx(d.load_N / d.k_sv, rel=1e-12)  # rest at F_z/k_sv
    # the linearized drop's bounce is stiffer than the secant's (what the shell's bounce needs)
    f_secant = math.sqrt(d.k_sv / d.tire.m_tot_kg) / (2 * math.pi)
    assert vertical_modes(d)[0][0] > 1.03 * f_secant


def test_dampers_meet_both_damping_ratios(truth):
    d = truth
    assert d.damping_source.startswith("belt mode zeta") and d.C_bz > 0 and d.C_vr > 0
    assert belt_vertical_mode(d)[1] == pytest.approx(ZETA_BELT, rel=1e-12)  # C_bz + C_vr, closed form
    assert vertical_modes(d)[0][1] == pytest.approx(ZETA_BOUNCE, rel=1e-9)  # the bisected share
    # not the one time constant: stiffness-proportional damping would give other ratios
    assert not math.isclose(d.C_bz / d.k_bz, d.C_vr / d.k_vr, rel_tol=0.05)


def test_ring_records_give_the_ring_back(char, truth):
    """Measure the known ring as the shell is measured, identify, compare."""
    d = truth
    dF = 0.001 * d.load_N
    defl = [d.residual_deflection(f) + f / d.k_bz for f in (d.load_N - dF, d.load_N, d.load_N + dF)]
    k_sv = d.load_N / defl[1]
    k_t = 2 * dF / (defl[2] - defl[0])  # central difference: O(dF^2) error, ~1e-7 here
    drum = sc.drum_cleat(d)
    f_belt, zeta_belt = drum.quantities["F_z_f_n_fit_Hz"], drum.quantities["F_z_zeta_fit"]
    drop = sc.drop_test(d, drop_height=0.002, duration=0.6)  # a low drop: little or no lift-off
    zeta_bounce = drop.quantities["bounce_zeta_in_contact"] or drop.quantities["bounce_zeta_fit"]
    row = _row(char, k_sv_N_per_m=k_sv, k_sv_tangent_N_per_m=k_t, first_mode_Hz=f_belt,
               k_dv_N_per_m=(2 * math.pi * f_belt) ** 2 * char.tire.m_b_kg, first_mode_xi=zeta_belt,
               xi_in_contact_fit=zeta_bounce)
    got = derive(row, char.tire)
    assert got.k_sv == pytest.approx(d.k_sv, rel=1e-9) and got.k_vt == pytest.approx(d.k_vt, rel=1e-5)
    # the belt mode from a damped-mode fit of a clean linear record (measured: f to 1e-7, the springs
    # to 3e-7): 1e-4 leaves room for the fit's round-off, not for a wrong split
    for name in ("k_bz", "k_vr", "k_vr2"):
        assert getattr(got, name) == pytest.approx(getattr(d, name), rel=1e-4), name
    assert got.C_bz + got.C_vr == pytest.approx(d.C_bz + d.C_vr, rel=1e-4)  # zeta_belt fitted to 1e-6
    # the bounce's zeta from a fit of the whole 2 mm drop (the quadratic contact makes it slightly
    # nonlinear; measured 0.0894 for 0.09): the share of the total moves by ~1 %, 3 % allowed
    for name in ("C_bz", "C_vr"):
        assert getattr(got, name) == pytest.approx(getattr(d, name), rel=0.03), name
    assert got.damping_source.startswith("belt mode zeta")


def test_no_solution_is_reported_and_the_time_constant_named(char):
    r = char.rated_row()
    base = {"k_sv_tangent_N_per_m": TANGENT_OVER_SECANT * r.q["k_sv_N_per_m"], "first_mode_xi": ZETA_BELT}
    d = derive(_row(char, **base, xi_in_contact_fit=0.9), char.tire)  # a bounce far more damped than any split gives
    assert "fallback" in d.damping_source and "no C_bz, C_vr >= 0" in d.damping_source and "0.9" in d.damping_source
    assert d.C_bz == pytest.approx(d.tau * d.k_bz) and d.C_vr == pytest.approx(d.tau * d.k_vr)
    d = derive(_row(char, **base), char.tire)  # no in-contact bounce measured
    assert "fallback" in d.damping_source and "xi_in_contact_fit" in d.damping_source


def test_secant_fallbacks_are_named(char):
    r = char.rated_row()
    d = derive(r, char.tire)  # no tangent in the row: the first spec's linear springs
    assert d.stiffness_source == "secant k_sv (no tangent in the row)" and d.k_vr2 == 0.0
    assert 1 / d.k_bz + 1 / d.k_vr == pytest.approx(1 / d.k_sv, rel=1e-12)
    d = derive(_row(char, k_sv_tangent_N_per_m=0.8 * r.q["k_sv_N_per_m"]), char.tire)  # a softening curve
    assert d.stiffness_source.startswith("secant k_sv (its residual spring softens") and d.k_vr2 == 0.0
    d = derive(_row(char, k_sv_tangent_N_per_m=3.0 * r.q["k_sv_N_per_m"]), char.tire)
    assert d.stiffness_source.startswith("secant") and d.k_vr2 == 0.0


def test_drop_rests_at_the_secant_and_rings_at_the_tangent(truth):
    res = sc.drop_test(truth)
    assert res.quantities["static_deflection_m"] == pytest.approx(truth.load_N / truth.k_sv, rel=1e-9)
    # the model's own linearization (jax) at rest agrees with the numpy modes of the tangent springs
    assert res.implied["bounce_f_n_Hz"] == pytest.approx(vertical_modes(truth)[0][0], rel=1e-9)
    assert res.implied["bounce_zeta"] == pytest.approx(ZETA_BOUNCE, rel=1e-6)
    assert np.isfinite(res.quantities["peak_F_z_N"])


def test_tir_vertical_law_rests_at_the_secant_with_the_tangent(char):
    """MF 6.1's F_z = FNOMIN (Q_FZ1 x + Q_FZ2 x^2), x = rho/R0, Q_FZ1 = sqrt((C_z R0/FNOMIN)^2 - 4 Q_FZ2):
    with the written VERTICAL_STIFFNESS and Q_FZ2 it must pass through (FNOMIN/k_sv, FNOMIN) with the
    slope k_vt there (algebra: 1e-9)."""
    rows = tuple(dataclasses.replace(r, q=r.q | {"k_sv_tangent_N_per_m": TANGENT_OVER_SECANT * r.q["k_sv_N_per_m"]})
                 for r in char.rows)
    ch = dataclasses.replace(char, rows=rows)
    sections, _ = tir.build(ch)
    v = {k: val for k, val, _ in sections["VERTICAL"]}
    r0, R0 = ch.rated_row(), ch.tire.unloaded_radius_m
    k_sv, k_vt = r0.q["k_sv_N_per_m"], r0.q["k_sv_tangent_N_per_m"]
    assert v["VERTICAL_STIFFNESS"] == pytest.approx(k_vt, rel=1e-12) and v["Q_FZ2"] > 0
    fz0 = v["FNOMIN"]
    q1 = math.sqrt((v["VERTICAL_STIFFNESS"] * R0 / fz0) ** 2 - 4 * v["Q_FZ2"])
    x0 = fz0 / k_sv / R0
    assert fz0 * (q1 * x0 + v["Q_FZ2"] * x0**2) == pytest.approx(fz0, rel=1e-9)
    assert fz0 / R0 * (q1 + 2 * v["Q_FZ2"] * x0) == pytest.approx(k_vt, rel=1e-9)
    # without a tangent: the linear law of before
    v = {k: val for k, val, _ in tir.build(char)[0]["VERTICAL"]}
    assert v["VERTICAL_STIFFNESS"] == char.rated_row().q["k_sv_N_per_m"] and v["Q_FZ2"] == 0.0


def test_mz_table_is_the_odd_part_of_the_e10_curve(char):
    r = char.rated_row()
    cv = r.curves
    deg = np.concatenate([-np.asarray(cv.slip_angle_deg[1:4]), cv.slip_angle_deg])  # -1..-3 deg beside 0..20
    mz = np.concatenate([-np.asarray(cv.M_z_SAE_Nm[1:4]) + 5.0, cv.M_z_SAE_Nm + 5.0])  # an offset: not odd
    row = dataclasses.replace(r, curves=dataclasses.replace(cv, slip_angle_deg=deg, M_z_SAE_Nm=mz,
                                                            lateral_force_N=np.interp(deg, cv.slip_angle_deg, cv.lateral_force_N),
                                                            F_z_N=None, F_y_SAE_N=None))
    a, m = derive(row, char.tire).mz_curve
    a, m = np.asarray(a), np.asarray(m)
    assert np.all(np.diff(a) > 0) and np.allclose(m, -m[::-1], atol=1e-12)  # ascending, odd
    i = int(np.argmin(abs(a - np.radians(2.0))))
    assert m[i] == pytest.approx(float(cv.M_z_SAE_Nm[2]), rel=1e-12)  # (M(2) - M(-2)) / 2 removes the offset
    assert m[-1] == pytest.approx(float(cv.M_z_SAE_Nm[-1]) + 5.0)  # one-sided angles keep their value
    # no curve: the table is the line k_m alpha' (the first spec's pneumatic trail)
    p = RigidRingParams.from_derived(derive(dataclasses.replace(r, curves=None), char.tire))
    assert np.interp(0.01, p.mz_alpha, p.mz_value) == pytest.approx(0.01 * r.q["k_m_Nm_per_rad"], rel=1e-12)


def test_lateral_release_record_gives_the_tread_damper_back(char):
    """Ring -> record -> ring, laterally: a ring with the sidewall's Maxwell branches and a tread damper
    set for a modal zeta 0.04 is released as E09 releases the shell; its record's damped-sine zeta goes
    into the row (xi_l_fit) and derive() identifies C_cy from it. The identified ring's linear release
    has exactly that zeta (bisection, 1e-9). A single damped sine fitted to this three-mode release
    reads 2.7 % above the modal zeta (measured, on either ring), and zeta moves by 0.22 % per 1 % of C_cy
    here (the sidewall's dampers carry most), so C_cy comes back 12.6 % high: 15 % allowed; the
    identified ring's own record then reads the same 2.7 % above the first record (3.5 % allowed)."""
    from jtire.rigid_ring.modes import lateral_modes

    r = char.rated_row()
    tire = dataclasses.replace(char.tire, relaxation_time_s=0.04)
    k_l = r.q["k_l_N_per_m"]
    row = dataclasses.replace(r, q=r.q | {"k_l_storage_N_per_m": 1.1 * k_l, "f_l_storage_Hz": 15.0, "xi_l_fit": 0.04})
    d = derive(row, tire)
    assert d.lateral_branch is not None and d.C_cy_source.startswith("E09")
    z_rec = sc.lateral_release(d, lateral="ring").quantities["zeta_fit"]
    got = derive(dataclasses.replace(row, q=row.q | {"xi_l_fit": z_rec}), tire)
    assert lateral_modes(got, "ring")[0][1] == pytest.approx(z_rec, rel=1e-9)
    assert got.C_cy == pytest.approx(d.C_cy, rel=0.15) and got.lateral_branch == d.lateral_branch
    assert sc.lateral_release(got, lateral="ring").quantities["zeta_fit"] == pytest.approx(z_rec, rel=0.035)
