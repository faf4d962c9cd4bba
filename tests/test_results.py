"""The results folder has one owner (jtire.results): a case is saved (tables, signals, then result.json),
read back, found by its condition, and a failure leaves error.txt that a later success removes. No
simulation: an ExperimentResult made by hand."""

import json

import numpy as np
import pytest

from jtire import results
from jtire import units as U
from jtire.errors import ConfigError
from jtire.experiments.result import ExperimentResult


def _result(load_kg, psi):
    cond = {"load_N": load_kg * U.G0, "pressure_Pa": psi * U.PSI}
    return ExperimentResult("footprint", cond, {"contact_length_m": 0.2, "note": "text"},
                            signals={"t": np.array([0.0, 1.0]), "z": np.array([np.nan, 2.0])})


def test_a_case_round_trips_and_is_found_by_its_condition(tmp_path):
    cases = results.cases_dir(tmp_path, "footprint")
    assert cases == tmp_path / "footprint" / "cases"
    conds = [{"load_N": kg * U.G0, "pressure_Pa": 120 * U.PSI} for kg in (2312.5, 4625.0)]
    names = [results.case_name(i, c) for i, c in enumerate(conds)]
    assert names == ["000_p120psi_l2312.5kg", "001_p120psi_l4625kg"]
    results.save_failure(cases / names[0], "diverged at t = 0.1 s")
    assert not results.is_done(cases / names[0]) and results.read_error(cases / names[0]) == "diverged at t = 0.1 s"
    results.save(cases / names[0], _result(2312.5, 120), tables={"extra": {"a": [1.0, 2.0]}})
    results.save(cases / names[1], _result(4625.0, 120))
    assert results.is_done(cases / names[0]) and results.read_error(cases / names[0]) is None
    assert (cases / names[0] / "extra.csv").is_file()
    r = results.read_result(cases / names[1])
    assert r["quantities"]["contact_length_m"] == 0.2
    s = results.read_signals(cases / names[1])
    assert np.isnan(s["z"][0]) and s["z"][1] == 2.0
    assert results.find_case(cases, 4625.0 * U.G0, 120 * U.PSI) == cases / names[1]
    assert results.find_case(cases, 4625.0 * U.G0, 70 * U.PSI) is None
    results.write_summary(tmp_path / "footprint", names, conds, [results.read_result(cases / n) for n in names], False)
    lines = (tmp_path / "footprint" / results.SUMMARY).read_text().splitlines()
    assert lines[0].split(",")[:4] == ["case", "pressure_Pa", "load_N", "contact_length_m"] and len(lines) == 3
    assert json.loads((cases / names[1] / results.RESULT).read_text())["experiment"] == "footprint"


def test_the_grid_refuses_a_repeated_value():
    g = {"loads_kg": [4625.0 * U.G0, 4625.0 * U.G0], "pressures_psi": [120 * U.PSI]}
    with pytest.raises(ConfigError, match="grid.loads_kg: lists a value twice"):
        results.grid_conditions(g, "grid")
    g["loads_kg"] = [2312.5 * U.G0, 4625.0 * U.G0]
    assert len(results.grid_conditions(g, "grid")) == 2
    assert results.grid_conditions(g, "grid", per_pressure=True) == [{"pressure_Pa": 120 * U.PSI}]
