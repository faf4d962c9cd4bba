"""MF 6.1 pure longitudinal slip (jtire.rigid_ring.mf_longitudinal): the equations' closed forms, the
fit to E06 force-slip curves, the curves in the characterization file, and the .tir's longitudinal
keys read back.

The synthetic curves are MF 6.1 F_x0 from a known coefficient set plus a free-rolling drag, so an
exact fit exists: tolerances are the optimizer's (1e-8 of peak), not a model error.
"""

import json

import numpy as np
import pytest

from jtire.errors import ConfigError
from jtire.rigid_ring import magic_formula as mf
from jtire.rigid_ring import mf_longitudinal as mfx
from jtire.rigid_ring import synthetic, tir
from jtire.rigid_ring.table import characterization_from_dict, read_characterization, write_characterization


@pytest.fixture(scope="module")
def char():
    return synthetic.characterization()


@pytest.fixture(scope="module")
def nom(char):
    r = char.rated_row()
    return mf.Nominal(r.load_N, r.pressure_Pa, char.tire.unloaded_radius_m)


def test_fx0_slope_and_peak(nom):
    c = synthetic.TRUE_MF_X
    for fz, p in ((nom.fnomin, nom.nompres), (0.5 * nom.fnomin, 0.7 * nom.nompres)):
        # slope at zero slip is K_xk (central difference: O(h^2) = 1e-10 relative)
        h = 1e-5
        slope = (mfx.fx0(c, nom, fz, h, p) - mfx.fx0(c, nom, fz, -h, p)) / (2 * h)
        assert slope == pytest.approx(float(mfx.slip_stiffness(c, nom, fz, p)), rel=1e-7)
        # with E_x < 1 and C_x > 1 the peak is D_x = mu_x F_z (sin reaches 1)
        dfz, dpi = fz / nom.fnomin - 1, p / nom.nompres - 1
        d = (c["PDX1"] + c["PDX2"] * dfz) * (1 + c["PPX3"] * dpi + c["PPX4"] * dpi**2) * fz
        k = np.linspace(0, 1, 200001)
        assert float(np.max(mfx.fx0(c, nom, fz, k, p))) == pytest.approx(d, rel=1e-8)
    # no shifts: odd in kappa
    k = np.linspace(-0.3, 0.3, 61)
    np.testing.assert_allclose(mfx.fx0(c, nom, nom.fnomin, -k), -mfx.fx0(c, nom, nom.fnomin, k), atol=1e-9)


def test_fit_recovers_the_curves_and_their_coefficients(char, nom):
    curves = mfx.curves_from_characterization(char)
    assert len(curves) == 9
    for cv in curves:  # the free-rolling drag is read at kappa = 0
        assert cv.f0 == pytest.approx(-synthetic.FREE_ROLLING_DRAG * cv.fz, rel=1e-12)
    fit = mfx.fit_pure_longitudinal(curves, nom)
    assert fit.success and fit.max_error < 1e-8 and not fit.at_bound and all(fit.peak_reached)
    true = synthetic.TRUE_MF_X
    # PKX1-3 are three numbers for three loads: K_xk(F_z) is pinned at each load, the split between
    # PKX2 and PKX3 is not (two exact solutions exist), so check K_xk, not PKX2/PKX3
    for key in ("PCX1", "PDX1", "PDX2", "PEX1", "PEX2", "PEX3", "PKX1", "PPX1", "PPX2", "PPX3", "PPX4"):
        assert fit.coefficients[key] == pytest.approx(true[key], rel=1e-6, abs=1e-9), key
    for cv in curves:
        assert float(mfx.slip_stiffness(fit.coefficients, nom, cv.fz, cv.p)) == pytest.approx(
            float(mfx.slip_stiffness(true, nom, cv.fz, cv.p)), rel=1e-6)
    # one load, one pressure: only the four shape coefficients are free
    one = mfx.fit_pure_longitudinal([c for c in curves if c.fz == nom.fnomin and c.p == nom.nompres], nom)
    assert one.fitted == ("PCX1", "PDX1", "PEX1", "PKX1") and one.max_error < 1e-8


def test_curves_short_of_the_peak_are_reported(char, nom):
    short = synthetic.characterization(slips=tuple(np.linspace(0, 0.04, 9)))
    fit = mfx.fit_pure_longitudinal(mfx.curves_from_characterization(short), nom)
    assert not any(fit.peak_reached)
    assert fit.max_error < 1e-3  # the rising part is still reproduced
    _, notes = tir.build(short, fit_x=fit)
    assert any("no E06 curve reaches its peak" in n for n in notes)


def test_characterization_file_keeps_the_e06_curves(tmp_path, char):
    write_characterization(tmp_path, char)
    back = read_characterization(tmp_path)
    for a, b in zip(char.rows, back.rows):
        np.testing.assert_array_equal(a.slip_curves.slip, b.slip_curves.slip)
        np.testing.assert_array_equal(a.slip_curves.force_x_N, b.slip_curves.force_x_N)
        assert b.slip_curves.surface == "flat"
    d = json.loads((tmp_path / "characterization.json").read_text())
    d["rows"][0]["E06_curves"]["surface"] = "ice"
    with pytest.raises(ConfigError, match=r"rows\[0\]\.E06_curves\.surface"):
        characterization_from_dict(d)
    d["rows"][0]["E06_curves"] = {"slip": [0.0, 0.1]}
    with pytest.raises(ConfigError, match=r"rows\[0\]\.E06_curves\.force_x_N"):
        characterization_from_dict(d)


def test_tir_longitudinal_keys_reproduce_the_e06_curves(tmp_path, char):
    sections, notes = tir.build(char)
    back = tir.read(tir.write(tmp_path / "t.tir", sections))
    coef = back["LONGITUDINAL_COEFFICIENTS"]
    comments = {k: c for k, _, c in sections["LONGITUDINAL_COEFFICIENTS"]}
    assert "E06" in comments["PKX1"] and "removed" in comments["PVX1"]
    assert back["LONG_SLIP_RANGE"]["KPUMAX"] == pytest.approx(0.2)
    nom = mf.Nominal(back["VERTICAL"]["FNOMIN"], back["OPERATING_CONDITIONS"]["NOMPRES"],
                     back["DIMENSION"]["UNLOADED_RADIUS"])
    fitted = [r for r in char.rows if r.pressure_Pa == nom.nompres]  # the default fit: nominal pressure
    assert len(fitted) == 3 and "3 conditions" in comments["PKX1"] and coef["PPX1"] == 0.0
    for r in fitted:  # the curve less its free-rolling drag, at every load
        sc = r.slip_curves
        want = sc.force_x_N - sc.force_x_N[0]
        got = mfx.fx0(coef, nom, r.load_N, sc.slip, r.pressure_Pa)
        assert float(np.max(np.abs(got - want))) < 1e-6 * float(np.max(np.abs(want))), (r.load_N, r.pressure_Pa)
    # without curves the slip stiffness alone sets PKX1 (the k_k law), the shape keys stay default
    bare = synthetic.characterization(slips=None)
    s2, _ = tir.build(bare)
    v2 = {k: v for k, v, _ in s2["LONGITUDINAL_COEFFICIENTS"]}
    r = bare.rated_row()
    assert v2["PCX1"] == tir.DEFAULTS["PCX1"][0]
    # the least-squares line of k_k/F_z on dfz over three loads, read at dfz = 0 (2.4 % above the
    # rated value for the synthetic k_k ~ F_z^0.8)
    assert v2["PKX1"] == pytest.approx(r.q["k_k_N_per_slip"] / r.load_N, rel=0.05)
