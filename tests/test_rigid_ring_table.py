"""Characterization layout, reader, tables and trend verdicts (jtire.rigid_ring.table/report/trends).

The data are the synthetic characterization (jtire.rigid_ring.synthetic: made-up smooth laws with
the study's magnitudes), so every expected number below is recomputed from the rows, not typed in.
"""

import dataclasses
import json

import numpy as np
import pytest

from jtire.errors import ConfigError
from jtire.rigid_ring import report, synthetic, trends
from jtire.rigid_ring.table import (Characterization, read_characterization, row_from_results,
                                    write_characterization)


@pytest.fixture(scope="module")
def char():
    return synthetic.characterization()


def test_json_round_trip(tmp_path, char):
    p = write_characterization(tmp_path, char)
    assert p.name == "characterization.json"
    d = json.loads(p.read_text())
    assert d["format"] == "jtire.characterization" and d["quantities"]["k_sv_N_per_m"]["unit"] == "N/m"
    back = read_characterization(tmp_path)
    assert back.tire == char.tire and len(back.rows) == len(char.rows)
    for a, b in zip(char.rows, back.rows):
        assert a.q == b.q and a.load_N == b.load_N and a.pressure_Pa == b.pressure_Pa
        np.testing.assert_array_equal(a.curves.lateral_force_N, b.curves.lateral_force_N)


def _as_json(char):
    from jtire.io import _jsonable

    return _jsonable(char.to_dict())


def test_reader_errors(tmp_path, char):
    d = _as_json(char)
    d["rows"][0]["k_sv_N_per_m"] = "stiff"
    (tmp_path / "c.json").write_text(json.dumps(d))
    with pytest.raises(ConfigError, match=r"rows\[0\].k_sv_N_per_m"):
        read_characterization(tmp_path / "c.json")
    d = _as_json(char)
    del d["rows"][1]["E10_curves"]["lateral_force_N"]
    (tmp_path / "c.json").write_text(json.dumps(d))
    with pytest.raises(ConfigError, match="lateral_force_N"):
        read_characterization(tmp_path / "c.json")
    with pytest.raises(ConfigError, match="no file"):
        read_characterization(tmp_path / "nothing.json")


def test_row_from_results_merges_known_quantities():
    r = row_from_results(45371.25, 827371.0, [{"quantities": {"k_sv_N_per_m": 1.2e6, "unrelated": 3.0}},
                                               {"quantities": {"C_l_2p_Ns_per_m": 400.0, "k_sv_N_per_m": 1.3e6}}],
                         e10_signals={"slip_angle_deg": [0, 1, 2], "lateral_force_N": [0, -3e3, -6e3],
                                      "aligning_moment_Nm": [0, 90, 180], "F_z_N": [1, 1, 1]})
    assert r.q == {"k_sv_N_per_m": 1.3e6, "C_l_2p_Ns_per_m": 400.0}
    np.testing.assert_array_equal(r.curves.M_z_SAE_Nm, [0, 90, 180])


def test_row_takes_each_quantity_from_its_own_experiment():
    """k_sv is E02's (the static secant); the drop test (E04) also reports a k_sv (its rest at the end
    of the drop), which must not replace E02's in the row, whichever order the results come in. A
    result without a study_id still overrides as before; E04's own C_tot is taken from E04."""
    e02 = {"study_id": "E02", "quantities": {"k_sv_N_per_m": 1.2e6}}
    e04 = {"study_id": "E04", "quantities": {"k_sv_N_per_m": 1.45e6, "C_tot_Ns_per_m": 900.0}}
    for order in ([e02, e04], [e04, e02]):
        assert row_from_results(45371.25, 827371.0, order).q == {"k_sv_N_per_m": 1.2e6, "C_tot_Ns_per_m": 900.0}
    assert row_from_results(1.0, 1.0, [e04, {"quantities": {"k_sv_N_per_m": 1.3e6}}]).q["k_sv_N_per_m"] == 1.3e6


def test_case_notes_name_the_case_and_what_happened():
    """`characterize.case_notes`: one line per case that batch.run reran on a finer ring, or whose
    slip-angle sweep stopped beyond its fit ranges, with the condition in the config's units; a plain
    case, or a failed one (None), gives none."""
    from jtire import units as U
    from jtire.characterize import case_notes

    r = {"condition": {"load_N": 2312.5 * U.G0, "pressure_Pa": 150 * U.PSI},
         "info": {"n_theta": 128, "refined_from_n_theta": 64, "refined_because": "the hub drag ..."}}
    e10 = {"condition": {"load_N": 6937.5 * U.G0, "pressure_Pa": 70 * U.PSI},
           "info": {"unsolved_slip_angles_deg": [6.0, 8.0, 20.0], "sweep_stopped": "slip angle 6 deg: ..."}}
    plain = {"condition": {"pressure_Pa": 120 * U.PSI}, "info": {}}
    assert case_notes({"rolling_resistance": [r, None, plain], "cornering": [e10]}) == [
        "rolling_resistance at 2312.5 kg, 150 psi: rerun on 128 segments (the hub drag ...)",
        "cornering at 6937.5 kg, 70 psi: slip angles 6, 8, 20 deg not solved (slip angle 6 deg: ...)"]


def test_missing_quantities_give_dashes_and_none(char):
    c = synthetic.drop(char, {"k_by_N_per_m", "C_by_2p_Ns_per_m"})
    rows = report.table_rows(c, "out")
    assert all(r["k_by_N_per_m"] is None and r["k_cy_N_per_m"] is None for r in rows)
    assert all(r["C_by_rel_diff_2p_vs_fit"] is None for r in rows)
    md = report.markdown(c, "out")
    assert "| k_by (kN/m) [E07] | 2312.5 | — | — | — |" in md


def test_markdown_layout_rows_load_columns_pressure(char):
    md = report.markdown(char, "in")
    assert "| quantity | load (kg) | 70 psi | 120 psi | 150 psi |" in md
    r = char.row(4625.0 * 9.81, 120 * 6894.757293168)
    c2, cf = r.q["C_tot_2p_Ns_per_m"], r.q["C_tot_fit_Ns_per_m"]
    # damping cells carry two-peak / fit and their relative difference
    assert f"{c2:.4g} / {cf:.4g} ({100 * (c2 / cf - 1):+.1f} %)" in md
    rows = report.table_rows(char, "in")
    assert [r["vertical_split"] for r in rows] == ["A"] * 9


def test_variant_flag_when_k_dv_below_4_k_sv(char):
    r = char.rows[0]
    low = dataclasses.replace(r, q=r.q | {"k_dv_N_per_m": 3.0 * r.q["k_sv_N_per_m"]})
    c = Characterization(char.tire, (low,))
    row = report.table_rows(c, "in")[0]
    assert row["vertical_split"] == "B" and row["variant_A_valid"] is False
    assert "B (A invalid: k_dv < 4 k_sv)" in report.markdown(c, "in")


def test_write_tables(tmp_path, char):
    paths = report.write_tables(char, tmp_path)
    assert {p.name for p in paths} == {"in_plane.csv", "in_plane.json", "in_plane.md", "out_of_plane.csv",
                                       "out_of_plane.json", "out_of_plane.md"}
    d = json.loads((tmp_path / "out_of_plane.json").read_text())
    assert d["units"]["k_f_N_per_rad"]["unit"] == "N/rad" and len(d["rows"]) == 9


def test_trend_verdicts_pass_fail_not_tested(char):
    vs = {v.check: v for v in trends.verdicts(char)}
    assert all(v.verdict == "pass" for k, v in vs.items() if not k.startswith("F_y"))
    assert vs["F_y(-alpha) = -F_y(alpha) (E10)"].verdict == "not tested"
    # one value out of line must FAIL and be named with its numbers
    r = char.row(4625.0 * 9.81, 150 * 6894.757293168)
    bad = tuple(dataclasses.replace(x, q=x.q | {"k_sv_N_per_m": 1.0e6}) if x is r else x for x in char.rows)
    v = trends.monotone(Characterization(char.tire, bad), "k_sv_N_per_m", "k_sv", +1, "pressure")
    assert v.verdict == "FAIL" and "150 psi 1e+06" in v.failures[0]
    gone = synthetic.drop(char, {"k_by_N_per_m"})
    assert trends.monotone(gone, "k_by_N_per_m", "k_by", +1, "pressure").verdict == "not tested"


def test_symmetry_verdict_with_negative_angles(char):
    angles = (-8, -4, -2, 0, 2, 4, 8)
    sym = synthetic.characterization(loads_kg=(4625.0,), pressures_psi=(120.0,), angles_deg=angles)
    assert trends.symmetry(sym).verdict == "pass"
    asym = synthetic.characterization(loads_kg=(4625.0,), pressures_psi=(120.0,), angles_deg=angles,
                                      mf=synthetic.TRUE_MF | {"PHY1": 0.01})  # a 0.57 deg shift
    v = trends.symmetry(asym)
    assert v.verdict == "FAIL", v.numbers
