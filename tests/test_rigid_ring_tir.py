"""The .tir export (jtire.rigid_ring.tir), the CLI `jtire export-tir`, and the validation table.

No Python Magic Formula evaluator that reads .tir files is installable from PyPI (checked: `pacejka`
0.1.0 takes macro parameters, not .tir files; TyreDyn and MFeval are not on PyPI), so the layout is
checked key by key against the published MF 6.1 sample property file shipped with MFeval
(MagicFormula61_Parameters.tir, copied in the public repository
girish-radhakrishnan-250894/slip_angle_control): every section and key it has must be in ours, in
the same sections, with the same [UNITS].
"""

import dataclasses
import math

import numpy as np
import pytest

from jtire.cli import main
from jtire.rigid_ring import magic_formula as mf
from jtire.rigid_ring import synthetic, tir, validation
from jtire.rigid_ring.params import derive
from jtire.rigid_ring.table import write_characterization

# section -> keys of the published MF 6.1 sample (names only), in its order
MF61_SAMPLE = {
    "MDI_HEADER": "FILE_TYPE FILE_VERSION FILE_FORMAT",
    "UNITS": "LENGTH FORCE ANGLE MASS TIME",
    "MODEL": "FITTYP TYRESIDE LONGVL VXLOW ROAD_INCREMENT ROAD_DIRECTION PROPERTY_FILE_FORMAT USER_SUB_ID "
             "N_TIRE_STATES USE_MODE HMAX_LOCAL TIME_SWITCH_INTEG",
    "DIMENSION": "UNLOADED_RADIUS WIDTH ASPECT_RATIO RIM_RADIUS RIM_WIDTH",
    "OPERATING_CONDITIONS": "INFLPRES NOMPRES",
    "INERTIA": "MASS IXX IYY BELT_MASS BELT_IXX BELT_IYY GRAVITY",
    "VERTICAL": "FNOMIN VERTICAL_STIFFNESS VERTICAL_DAMPING MC_CONTOUR_A MC_CONTOUR_B BREFF DREFF FREFF Q_RE0 Q_V1 "
                "Q_V2 Q_FZ2 Q_FCX Q_FCY Q_CAM PFZ1 BOTTOM_OFFST BOTTOM_STIFF",
    "STRUCTURAL": "LONGITUDINAL_STIFFNESS LATERAL_STIFFNESS YAW_STIFFNESS FREQ_LONG FREQ_LAT FREQ_YAW FREQ_WINDUP "
                  "DAMP_LONG DAMP_LAT DAMP_YAW DAMP_WINDUP DAMP_RESIDUAL DAMP_VLOW Q_BVX Q_BVT PCFX1 PCFX2 PCFX3 "
                  "PCFY1 PCFY2 PCFY3 PCMZ1",
    "CONTACT_PATCH": "Q_RA1 Q_RA2 Q_RB1 Q_RB2 ELLIPS_SHIFT ELLIPS_LENGTH ELLIPS_HEIGHT ELLIPS_ORDER ELLIPS_MAX_STEP "
                     "ELLIPS_NWIDTH ELLIPS_NLENGTH",
    "INFLATION_PRESSURE_RANGE": "PRESMIN PRESMAX",
    "VERTICAL_FORCE_RANGE": "FZMIN FZMAX",
    "LONG_SLIP_RANGE": "KPUMIN KPUMAX",
    "SLIP_ANGLE_RANGE": "ALPMIN ALPMAX",
    "INCLINATION_ANGLE_RANGE": "CAMMIN CAMMAX",
    "SCALING_COEFFICIENTS": "LFZO LCX LMUX LEX LKX LHX LVX LCY LMUY LEY LKY LHY LVY LTR LRES LXAL LYKA LVYKA LS LKYC "
                            "LKZC LVMX LMX LMY LMP",
    "LONGITUDINAL_COEFFICIENTS": "PCX1 PDX1 PDX2 PDX3 PEX1 PEX2 PEX3 PEX4 PKX1 PKX2 PKX3 PHX1 PHX2 PVX1 PVX2 PPX1 "
                                 "PPX2 PPX3 PPX4 RBX1 RBX2 RBX3 RCX1 REX1 REX2 RHX1",
    "OVERTURNING_COEFFICIENTS": "QSX1 QSX2 QSX3 QSX4 QSX5 QSX6 QSX7 QSX8 QSX9 QSX10 QSX11 QSX12 QSX13 QSX14 PPMX1",
    "LATERAL_COEFFICIENTS": "PCY1 PDY1 PDY2 PDY3 PEY1 PEY2 PEY3 PEY4 PEY5 PKY1 PKY2 PKY3 PKY4 PKY5 PKY6 PKY7 PHY1 PHY2 "
                            "PVY1 PVY2 PVY3 PVY4 PPY1 PPY2 PPY3 PPY4 PPY5 RBY1 RBY2 RBY3 RBY4 RCY1 REY1 REY2 RHY1 "
                            "RHY2 RVY1 RVY2 RVY3 RVY4 RVY5 RVY6",
    "ROLLING_COEFFICIENTS": "QSY1 QSY2 QSY3 QSY4 QSY5 QSY6 QSY7 QSY8",
    "ALIGNING_COEFFICIENTS": "QBZ1 QBZ2 QBZ3 QBZ4 QBZ5 QBZ9 QBZ10 QCZ1 QDZ1 QDZ2 QDZ3 QDZ4 QDZ6 QDZ7 QDZ8 QDZ9 QDZ10 "
                             "QDZ11 QEZ1 QEZ2 QEZ3 QEZ4 QEZ5 QHZ1 QHZ2 QHZ3 QHZ4 PPZ1 PPZ2 SSZ1 SSZ2 SSZ3 SSZ4",
    "TURNSLIP_COEFFICIENTS": "PDXP1 PDXP2 PDXP3 PKYP1 PDYP1 PDYP2 PDYP3 PDYP4 PHYP1 PHYP2 PHYP3 PHYP4 PECP1 PECP2 "
                             "QDTP1 QCRP1 QCRP2 QBRP1 QDRP1",
}
SAMPLE_UNITS = {"LENGTH": "meter", "FORCE": "newton", "ANGLE": "radians", "MASS": "kg", "TIME": "second"}


@pytest.fixture(scope="module")
def char():
    return synthetic.characterization()


@pytest.fixture(scope="module")
def exported(char):
    return tir.build(char)


def test_layout_matches_the_published_mf61_sample(exported):
    sections, _ = exported
    text = tir.dumps(sections)
    back = tir.loads(text)
    assert list(back) == list(MF61_SAMPLE)
    for sec, keys in MF61_SAMPLE.items():
        assert list(back[sec]) == keys.split(), sec
    assert back["UNITS"] == SAMPLE_UNITS and back["MODEL"]["FITTYP"] == 61
    # [INERTIA] MASS is a number (the key shares its name with [UNITS] MASS = 'kg', once quoted too)
    assert isinstance(back["INERTIA"]["MASS"], float) and back["INERTIA"]["MASS"] > 0
    assert "MASS                     = 'kg'" in text


def test_round_trip_and_comments(exported):
    sections, _ = exported
    back = tir.loads(tir.dumps(sections, ["a comment"]))
    for sec, rows in sections.items():
        for k, v, c in rows:
            got = back[sec][k]
            assert got == v if isinstance(v, str) else float(got) == pytest.approx(float(v), rel=1e-15), (sec, k)
            assert c, f"{k} has no comment"


def test_derived_values(char, exported):
    sections, notes = exported
    v = {k: val for rows in sections.values() for k, val, _ in rows}
    c = {k: com for rows in sections.values() for k, _, com in rows}
    d = derive(char.rated_row(), char.tire)
    assert v["VERTICAL_STIFFNESS"] == d.k_sv and "E02" in c["VERTICAL_STIFFNESS"]
    assert v["LATERAL_STIFFNESS"] == d.k_l and v["FNOMIN"] == d.load_N and v["NOMPRES"] == d.pressure_Pa
    assert v["FREQ_LAT"] == pytest.approx(math.sqrt(d.k_by / char.tire.m_b_kg) / (2 * math.pi))
    assert v["BELT_MASS"] == char.tire.m_b_kg and v["GRAVITY"] == -9.81
    # synthetic k_sv ~ p^0.55: PFZ1 is the least-squares slope of k_sv/k_sv0 - 1 on dpi
    assert 0.3 < v["PFZ1"] < 0.6
    # synthetic k_l = k_l0 (1 + 0.05 dfz'), dfz' = F_z/F_z0 - 1 = dfz: PCFY1 = 0.05, PCFY2 = 0
    assert v["PCFY1"] == pytest.approx(0.05, rel=1e-9) and abs(v["PCFY2"]) < 1e-9
    # contact half length against rho = F_z/k_sv reproduces the rated footprint
    rho = d.rho / v["UNLOADED_RADIUS"]
    a = v["UNLOADED_RADIUS"] * (v["Q_RA2"] * rho + v["Q_RA1"] * math.sqrt(rho))
    assert a == pytest.approx(d.a, rel=0.02)
    assert v["PKY1"] < 0 and v["PKY1"] == pytest.approx(synthetic.TRUE_MF["PKY1"], rel=1e-6)
    assert any("DAMP_LONG" in n for n in notes)  # the tau split gives ~0.2, not the usual ~0.04


def test_mf_from_the_tir_reproduces_the_e10_curves(tmp_path, char, exported):
    sections, _ = exported
    p = tir.write(tmp_path / "t.tir", sections)
    back = tir.read(p)
    coef = back["LATERAL_COEFFICIENTS"] | back["ALIGNING_COEFFICIENTS"]
    nom = mf.Nominal(back["VERTICAL"]["FNOMIN"], back["OPERATING_CONDITIONS"]["NOMPRES"],
                     back["DIMENSION"]["UNLOADED_RADIUS"])
    for r in char.rows:
        if not math.isclose(r.pressure_Pa, nom.nompres):
            continue
        a = -np.radians(r.curves.slip_angle_deg)
        np.testing.assert_allclose(-mf.fy0(coef, nom, r.load_N, a), r.curves.lateral_force_N, rtol=1e-8, atol=1e-6)


def test_cli_export_tir(tmp_path, char, capsys):
    write_characterization(tmp_path, char)
    assert main(["export-tir", str(tmp_path), "--out", str(tmp_path / "x.tir")]) == 0
    out = capsys.readouterr().out
    assert "MF fit (nominal pressure)" in out and "| k_sv rises with pressure | pass |" in out
    assert (tmp_path / "x.tir").is_file() and (tmp_path / "in_plane.md").is_file()
    assert main(["export-tir", str(tmp_path / "missing")]) == 2


def test_compare_verdicts_and_figure(tmp_path):
    ring = {"drop.static_deflection_m": 0.0354, "drop.bounce_zeta": 0.05, "lateral.f_Hz": 10.0,
            "drum.F_z_peak_to_peak_N": 2.3e4}
    shell = {"drop.static_deflection_m": 0.0354 / 1.02, "drop.bounce_zeta": 0.05 / 1.25, "lateral.f_Hz": None,
             "drum.F_z_peak_to_peak_N": 2e4, "drum.F_x_peak_to_peak_N": 1e4}
    rows = {c.metric: c for c in validation.compare(shell, ring)}
    assert rows["drop.static_deflection_m"].verdict == "pass"  # +2 % within 3 %
    assert rows["drop.bounce_zeta"].verdict == "FAIL"  # +25 % beyond 20 %
    assert rows["lateral.f_Hz"].verdict == "not compared"  # no shell value
    assert rows["drum.F_z_peak_to_peak_N"].verdict == "pass"  # +15 % within 20 %
    assert rows["drum.F_x_peak_to_peak_N"].verdict == "not compared"  # no ring value (a point contact gives none)
    assert "| drop.bounce_zeta |" in validation.markdown(rows.values())
    t = np.linspace(0, 1, 50)
    step = -1e4 * (1 - np.exp(-5 * t)) + 300 * np.sin(200 * t)  # a build-up with a ripple on it
    p = validation.validation_figure({"drop": (t, np.sin(t)), "step_5": (t, step)},
                                     {"drop": (t, np.cos(t)), "step_5": (t, t)}, tmp_path / "v.png")
    assert p.stat().st_size > 1000


@pytest.mark.parametrize("fs", [500.0, 4000.0])
def test_shell_drop_metrics_search_the_belt_band_below_nyquist(tmp_path, fs):
    """The shell's drop, read from a characterization case folder: a default-mesh drop is saved at
    500 Hz, so the belt-mode band (40-300 Hz) is cut at fs/2 = 250 Hz (a characterize on the default
    mesh once failed here after 43 min of grid). A synthetic contact force with a 120 Hz ring-down
    on a 2 Hz bounce: the peak found within 1 % (the padded spectrum's resolution is 0.01 Hz; the
    Hann window and the short record bias an interpolated peak by well under that)."""
    import json

    from jtire import units as U
    from jtire import validate

    load, p = 4625.0 * U.G0, 120.0 * U.PSI
    t = np.arange(0.0, 1.0, 1.0 / fs)
    touch = t >= 0.05
    tau = t - 0.05
    fz = np.where(touch, load * (1 + 0.3 * np.exp(-3 * tau) * np.cos(2 * np.pi * 2 * tau))
                  + 2e3 * np.exp(-4 * tau) * np.sin(2 * np.pi * 120.0 * tau), 0.0)
    case = tmp_path / "drop_test" / "cases" / "000"
    case.mkdir(parents=True)
    (case / "result.json").write_text(json.dumps({
        "condition": {"load_N": load, "pressure_Pa": p},
        "quantities": {"static_deflection_m": 0.035, "f_d_fit_Hz": 2.0, "xi_fit": 0.1},
        "checks": {"drop_height_m": 0.02, "first_contact_t_s": 0.05}}))
    bounce = np.where(touch, load * (1 + 0.3 * np.exp(-3 * tau) * np.cos(2 * np.pi * 2 * tau)), 0.0)

    def metrics(f):
        # rim z: first contact at -drop height, then sinking in proportion to the force (rest: F_z = load)
        rows = ["time_s,contact_force_z_N,rim_z_m"] + [f"{a:.17g},{b:.17g},{-0.02 - 0.035 * b / load:.17g}"
                                                       for a, b in zip(t, f)]
        (case / "signals.csv").write_text("\n".join(rows) + "\n")
        return validate.shell_metrics(tmp_path, load, p)

    m, sig = metrics(fz)
    # the drop panel: time from first contact, rim z from where the wheel rests under the load
    tx, zx = sig["drop"]
    assert tx == pytest.approx(t - 0.05, abs=1e-12)
    assert zx == pytest.approx(0.035 * (1 - fz / load), abs=1e-12)
    assert sig["drop_band_Hz"] == pytest.approx((40.0, min(300.0, fs / 2)), rel=1e-9)
    assert m["drop.belt_mode_Hz"] == pytest.approx(120.0, rel=0.01)
    # the bounce alone: its spectrum falls through the band, the maximum sits on the band's lower
    # edge -- that is no belt mode, and is reported as none (the table then says "not compared")
    m, _ = metrics(bounce)
    assert m["drop.belt_mode_Hz"] is None
    assert validate.belt_band(np.arange(0, 1, 1 / 50.0)) is None  # 25 Hz Nyquist: no band left


def test_ellips_keys_come_from_the_nominal_rows_tandem_cam(char):
    """With E03's tandem cam in the rows the CONTACT_PATCH ELLIPS keys carry it in jtire's scaling
    (l_s/2a, a_e/R0, b_e/R0, c_e), each saying so; without it they keep their defaults."""
    import dataclasses

    from jtire.rigid_ring.table import Characterization

    cam = {"ellips_shift_m": 0.1, "ellips_length_m": 0.4, "ellips_height_m": 0.15, "ellips_order": 1.5,
           "enveloping_fit_rms_height_m": 2e-4, "enveloping_max_height_m": 0.016}
    with_cam = Characterization(char.tire, tuple(dataclasses.replace(r, q=r.q | cam) for r in char.rows))
    d = derive(with_cam.rated_row(), with_cam.tire)
    assert d.ellips == (0.1, 0.4, 0.15, 1.5)
    sections, _ = tir.build(with_cam)
    v = {k: (val, com) for k, val, com in sections["CONTACT_PATCH"]}
    R0 = char.tire.unloaded_radius_m
    assert v["ELLIPS_SHIFT"][0] == pytest.approx(0.1 / (2 * d.a)) and "E03" in v["ELLIPS_SHIFT"][1]
    assert v["ELLIPS_LENGTH"][0] == pytest.approx(0.4 / R0) and v["ELLIPS_HEIGHT"][0] == pytest.approx(0.15 / R0)
    assert v["ELLIPS_ORDER"][0] == 1.5 and "scaling" in v["ELLIPS_LENGTH"][1]
    plain = {k: (val, com) for k, val, com in tir.build(char)[0]["CONTACT_PATCH"]}
    assert plain["ELLIPS_SHIFT"] == (0.8, "default: no enveloping identified") and derive(char.rated_row(), char.tire).ellips is None


def test_longitudinal_stiffness_is_e14s_when_measured(char):
    """With E14's C_x in the rows LONGITUDINAL_STIFFNESS is the rated row's and PCFX1, PCFX2 fit E14's
    values over load (here C_x = 1.1 x the ring's series value x (1 + 0.2 dfz)); the notes give the
    ring's series value beside it. Without E14, the series value, said so."""
    from jtire.rigid_ring.table import Characterization

    fz0 = char.rated_row().load_N

    def c_x(r):
        return 1.1 * derive(r, char.tire).C_x * (1.0 + 0.2 * (r.load_N / fz0 - 1.0))

    rows = tuple(dataclasses.replace(r, q=r.q | {"C_x_N_per_m": c_x(r)}) for r in char.rows)
    sections, notes = tir.build(Characterization(char.tire, rows))
    v = {k: (val, com) for rows in sections.values() for k, val, com in rows}
    d = derive(char.rated_row(), char.tire)
    assert v["LONGITUDINAL_STIFFNESS"][0] == pytest.approx(1.1 * d.C_x, rel=1e-12)
    assert "E14" in v["LONGITUDINAL_STIFFNESS"][1]
    assert any(n.startswith("LONGITUDINAL_STIFFNESS") and "-9.1 %" in n for n in notes)  # 1/1.1 - 1
    # PCFX1, PCFX2: the least-squares fit of C_x / C_x0 - 1 on dfz, dfz^2 over the rated pressure's rows,
    # taken on E14's values (not the ring's: those would give another fit)
    same_p = [r for r in rows if math.isclose(r.pressure_Pa, d.pressure_Pa, rel_tol=1e-6)]
    x = np.array([r.load_N / fz0 - 1.0 for r in same_p])
    y = np.array([r.q["C_x_N_per_m"] / (1.1 * d.C_x) - 1.0 for r in same_p])
    c = np.linalg.lstsq(np.column_stack([x, x * x]), y, rcond=None)[0]
    assert v["PCFX1"][0] == pytest.approx(c[0], rel=1e-9) and v["PCFX2"][0] == pytest.approx(c[1], rel=1e-9, abs=1e-12)
    plain = {k: (val, com) for rows in tir.build(char)[0].values() for k, val, com in rows}
    assert plain["LONGITUDINAL_STIFFNESS"][0] == pytest.approx(d.C_x) and "no E14" in plain["LONGITUDINAL_STIFFNESS"][1]


def test_inertia_keys_are_the_whole_tire_when_recorded():
    """IXX, IYY: the whole tire without rim (belt + the mesh's sidewalls and beads), which a thin-ring
    check bounds: the belt's I_by alone is below it and m_tire R0^2 above it (no node lies outside
    the unloaded radius); a characterization without them keeps the belt's values, marked [A]."""
    from jtire.characterize import load_plan, tire_info
    from jtire.resources import config_path

    t = tire_info(load_plan(config_path("characterize.toml")))
    assert t.I_by_kgm2 < t.tire_Iy_kgm2 < t.tire_mass_kg * t.unloaded_radius_m**2
    assert t.I_bx_kgm2 < t.tire_Ix_kgm2 < t.tire_Iy_kgm2  # a ring: I about a diameter ~ half of I about its axis
    base = synthetic.characterization()
    ring = dataclasses.replace(base, tire=dataclasses.replace(base.tire, tire_Iy_kgm2=t.tire_Iy_kgm2,
                                                              tire_Ix_kgm2=t.tire_Ix_kgm2))
    for c, iy, ix, mark in ((ring, t.tire_Iy_kgm2, t.tire_Ix_kgm2, False),
                            (base, base.tire.I_by_kgm2, base.tire.I_bx_kgm2, True)):
        rows = {k: (v, com) for r in tir.build(c)[0].values() for k, v, com in r}
        assert rows["IYY"][0] == iy and rows["IXX"][0] == ix and rows["IYY"][1].startswith("[A]") == mark
    back = type(base.tire).from_dict(dataclasses.asdict(ring.tire))  # and the json round trip keeps them
    assert back.tire_Iy_kgm2 == t.tire_Iy_kgm2
