"""The static experiments end to end through the CLI, as a user runs them (coarse mesh)."""

import csv
import json

from jtire.cli import main

from .conftest import REPO


def test_run_vertical_stiffness_writes_result_and_signals(tmp_path, capsys):
    out = tmp_path / "e02"
    rc = main(["run", str(REPO / "configs" / "experiments" / "vertical_stiffness.toml"), "--out", str(out),
               "--set", "tire.mesh.n_theta=32", "--set", "tire.mesh.n_crown=4", "--set", "vertical_stiffness.ramp_s=0.15"])
    assert rc == 0
    printed = capsys.readouterr().out
    assert "k_sv_N_per_m" in printed and "settled" in printed
    d = json.loads((out / "result.json").read_text())
    assert d["experiment"] == "vertical_stiffness"
    assert set(d["condition"]) == {"pressure_Pa", "load_N"}
    q = d["quantities"]
    assert 5e5 < q["k_sv_N_per_m"] < 3e6 and 0.01 < q["deflection_m"] < 0.08
    assert d["checks"]["load_settled"] and d["checks"]["quasi_static_deflection_rel_error"] < 0.02
    rows = list(csv.DictReader((out / "signals.csv").open()))
    assert {"time_s", "load_N", "deflection_m", "contact_force_N"} <= set(rows[0])
    loads = [float(r["load_N"]) for r in rows]
    assert loads == sorted(loads) and loads[-1] > 0.95 * 60e3
