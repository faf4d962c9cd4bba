"""Bad inputs of the simulation commands (run, sweep, characterize, export-tir, export-vtk, run --frames)
and of the command line itself: one line, exit code 2, before any simulation (test_bad_inputs.py)."""

from pathlib import Path

import numpy as np
import pytest

from .bad_input_harness import (
    Case, check_one_line, CHAR, COND, FOOTPRINT, NON_UTF8, VERTICAL, _blocked,
    _characterize_claimed, _exp, _exp_bytes_tire, _npz, _out, _sweep_claimed, _w)

CASES = [
    # ---- run -------------------------------------------------------------------------------------
    Case("run-non-utf8-config", lambda t: ["run", _w(t, "bad.toml", b"\xff\xfe")], "bad.toml", "not UTF-8", "line 1"),
    Case("run-non-utf8-tire", lambda t: ["run", _exp_bytes_tire(t)], "tire.toml", "not UTF-8"),
    Case("run-folder-as-config", lambda t: ["run", str(t)], "is a folder, not a config file"),
    Case("run-missing-config", lambda t: ["run", str(Path(t) / "nope.toml")], "nope.toml", "no such config file"),
    Case("run-malformed-toml", lambda t: ["run", _w(t, "m.toml", "experiment = [\n")], "m.toml", "not valid TOML"),
    Case("run-set-empty-key", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "=5"], "--set '=5'", "dotted field name"),
    Case("run-set-no-equals", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.load_kg"], "KEY=VALUE"),
    Case("run-load-1e-6-kg", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.load_kg=1e-6"],
         "condition.load_kg = 1e-06: must be in [50, 50000]"),
    Case("run-pressure-boolean", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.pressure_psi=true"],
         "condition.pressure_psi = True: must be a number"),
    Case("run-unknown-top-key", lambda t: ["run", _exp(t, 'colour = "red"\n' + FOOTPRINT)], "colour: unknown field"),
    Case("run-experiment-and-experiments", lambda t: ["run", _exp(t, 'experiments = ["footprint"]\n' + FOOTPRINT)],
         "not both"),
    Case("run-unknown-experiment", lambda t: ["run", _exp(t, FOOTPRINT.replace('"footprint"', '"flying"'))],
         "experiment = 'flying': unknown"),
    Case("run-table-of-experiment-not-run", lambda t: ["run", _exp(
        t, FOOTPRINT + "[vertical_stiffness]\nmax_load_kN = -60.0\n")], "vertical_stiffness.max_load_kN = -60"),
    Case("run-slip-angles-booleans", lambda t: ["run", _exp(t, FOOTPRINT.replace(
        '"footprint"', '"cornering"') + "[cornering]\nslip_angles_deg = [true, false]\n")],
         "cornering.slip_angles_deg = [True, False]: must be a list"),
    Case("run-second-experiment-table-bad", lambda t: ["run", _exp(t, FOOTPRINT.replace(
        'experiment = "footprint"', 'experiments = ["footprint", "vertical_stiffness"]')
        + "[vertical_stiffness]\nmax_load_kN = 60.0\nstated_load_kN = 70.0\n")], "vertical_stiffness."),
    Case("run-two-loads", lambda t: ["run", _exp(t, FOOTPRINT + "load_kN = 45.0\n")], "give exactly one of load_kg"),
    Case("run-no-tire-file", lambda t: ["run", _w(t, "e.toml", f'experiment = "footprint"\n{COND}')],
         "tire_file: missing"),
    Case("run-tire-file-missing", lambda t: ["run", _w(t, "e.toml", FOOTPRINT.replace("tire.toml", "no_tire.toml"))],
         "no_tire.toml", "no such tire file"),
    Case("run-tread-wider-than-section", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.tread_width_mm=1000"],
         "tire file tire.toml: tire.tire.tread_width_mm = 1000: must be in [tire.belt_width_mm = 360"),
    Case("run-crown-radius-50", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.crown_radius_mm=50"],
         "tire file tire.toml: tire.tire.crown_radius_mm = 50: must be above"),
    Case("run-tread-depth-60", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.tread_depth_mm=60"],
         "tire.tire.tread_depth_mm = 60: must be below"),
    Case("run-mesh-n-theta-8", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.mesh.n_theta=8"],
         "tire file tire.toml: tire.mesh.n_theta = 8: must be in [16, 1024]"),
    Case("run-belt-heavier-than-tire", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.mass.belt_kg=90"],
         "tire.mass.belt_kg = 90: must be below mass.tire_kg"),
    Case("run-settle-damping-below-range", lambda t: ["run", _exp(t, FOOTPRINT), "--set",
                                                      "solver.settle_damping_per_s=0.5"],
         "solver.settle_damping_per_s = 0.5: must be in"),
    Case("run-out-unwritable", lambda t: ["run", _exp(t, FOOTPRINT), "--out", _blocked(t)],
         "cannot read or write", "a_file"),
    # ---- sweep -----------------------------------------------------------------------------------
    Case("sweep-non-utf8-config", lambda t: ["sweep", _w(t, "bad.toml", NON_UTF8)], "bad.toml", "not UTF-8",
         "line 3"),
    Case("sweep-negative-batch", lambda t: ["sweep", _exp(t, VERTICAL), "--batch", "-1", *_out(t)],
         "--batch -1: must be >= 0"),
    Case("sweep-boolean-loads", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloads_kg = [true]\n"), *_out(t)],
         "sweep.loads_kg = [True]: must be a list"),
    Case("sweep-unknown-key", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloadz_kg = [4625.0]\n"), *_out(t)],
         "sweep.loadz_kg: unknown field"),
    Case("sweep-load-twice", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloads_kg = [4625.0, 4625.0]\n"),
                                        *_out(t)], "sweep.loads_kg: lists a value twice"),
    Case("sweep-two-experiments", lambda t: ["sweep", _exp(t, VERTICAL.replace(
        'experiment = "vertical_stiffness"', 'experiments = ["vertical_stiffness", "footprint"]')), *_out(t)],
         "exactly one experiment"),
    Case("sweep-out-unwritable", lambda t: ["sweep", _exp(t, VERTICAL), "--out", _blocked(t)], "cannot read or write"),
    Case("sweep-resume-other-settings", lambda t: _sweep_claimed(t) + ["--set", "vertical_stiffness.max_load_kN=70"],
         "holds results made with other settings"),
    Case("sweep-no-config", lambda t: ["sweep"], "the following arguments are required: config"),
    # ---- characterize ----------------------------------------------------------------------------
    Case("characterize-non-utf8-tire", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--tire",
                                                  _w(t, "t2.toml", b"[tire]\n\xff"), *_out(t)],
         "t2.toml", "not UTF-8", "line 2"),
    Case("characterize-negative-batch", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--batch", "-2",
                                                   *_out(t)], "--batch -2: must be >= 0"),
    Case("characterize-boolean-grid", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                 "grid.loads_kg=[true]", *_out(t)], "grid.loads_kg = [True]"),
    Case("characterize-rated-off-grid", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                   "grid.rated_load_kg=1000", *_out(t)], "grid.rated_load_kg"),
    Case("characterize-unknown-key", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set", "colour=1",
                                                *_out(t)], "colour: unknown field"),
    Case("characterize-relaxation-listed", lambda t: ["characterize", _exp(t, CHAR.replace(
        '"footprint", ', '"relaxation_length", '), name="char.toml"), *_out(t)], "relaxation_length is derived"),
    Case("characterize-folder-as-config", lambda t: ["characterize", str(t), *_out(t)], "is a folder"),
    Case("characterize-out-unwritable", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--out",
                                                   _blocked(t)], "cannot read or write"),
    Case("characterize-resume-other-settings", lambda t: _characterize_claimed(t) + [
        "--set", "vertical_stiffness.max_load_kN=70"], "holds results made with other settings"),
    Case("characterize-tire-error-names-file", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                          "tire.tire.tread_width_mm=1000", *_out(t)],
         "tire file tire.toml: tire.tire.tread_width_mm = 1000"),
    # ---- export-tir ------------------------------------------------------------------------------
    Case("export-tir-missing", lambda t: ["export-tir", str(Path(t) / "none.json")], "no file"),
    Case("export-tir-non-utf8", lambda t: ["export-tir", _w(t, "c.json", b"\xff")], "c.json: not UTF-8"),
    Case("export-tir-not-json", lambda t: ["export-tir", _w(t, "c.json", "{not json")], "not valid JSON"),
    Case("export-tir-wrong-format", lambda t: ["export-tir", _w(t, "c.json", "{}")], "format"),
    Case("export-tir-longvl-nan", lambda t: ["export-tir", _w(t, "c.json", "{}"), "--longvl", "nan"],
         "--longvl nan: must be a speed"),
    Case("export-tir-fittyp-choice", lambda t: ["export-tir", _w(t, "c.json", "{}"), "--fittyp", "52"],
         "argument --fittyp: invalid choice"),
    # ---- reproduce (more in tests/test_reproduce.py) -------------------------------------------------------
    Case("reproduce-foreign-folder", lambda t: ["reproduce", "--quick", "--out", str(Path(_w(t, "x/notes.txt", "a")).parent)],
         "is not a reproduce folder"),
    Case("reproduce-out-is-a-file", lambda t: ["reproduce", "--quick", "--out", _w(t, "out.txt", "a")], "out.txt"),
    # ---- new-tire (more in tests/test_new_tire.py) -------------------------------------------------------
    Case("new-tire-not-a-size", lambda t: ["new-tire", "12.00R20", "--out", str(Path(t) / "x")], "size '12.00R20'"),
    Case("new-tire-measured-missing", lambda t: ["new-tire", "205/55R16", "--measured", str(Path(t) / "m.csv"),
                                                  "--out", str(Path(t) / "x")], "m.csv: no such measurements CSV"),
    Case("new-tire-measured-columns", lambda t: ["new-tire", "205/55R16", "--measured", _w(t, "m.csv", "a,b\n1,2\n"),
                                                  "--out", str(Path(t) / "x")], "m.csv: needs the columns"),
    # ---- export-vtk and run --frames ------------------------------------------------------------------
    Case("export-vtk-missing", lambda t: ["export-vtk", str(Path(t) / "nofolder")], "nofolder", "no such frames file"),
    Case("export-vtk-not-npz", lambda t: ["export-vtk", _w(t, "f.npz", b"not a zip file")], "f.npz",
         "not a readable .npz file"),
    Case("export-vtk-missing-arrays", lambda t: ["export-vtk", _npz(t, t=np.zeros(2))], "missing arrays"),
    Case("export-vtk-wrong-shape", lambda t: ["export-vtk", _npz(t, t=np.zeros(2), nodes=np.zeros((2, 4, 5, 3)),
                                                                  nodes_ref=np.zeros((4, 6, 3)))],
         "nodes has shape (2, 4, 5, 3), expected (2, 4, 6, 3)"),
    Case("run-frames-out-of-range", lambda t: ["run", _exp(t, FOOTPRINT), "--frames", "1", *_out(t)],
         "--frames: 1 is out of range", "2 to 200"),
    Case("run-frames-without-out", lambda t: ["run", _exp(t, FOOTPRINT), "--frames", "5"], "--frames: needs --out"),
    Case("run-method-unknown", lambda t: ["run", _exp(t, FOOTPRINT), "--set", 'footprint.method="implicit"'],
         "footprint.method = 'implicit': must be one of static, transient"),
    Case("run-drop-gravity-static", lambda t: ["run", _exp(t, FOOTPRINT.replace('"footprint"', '"drop_test"')),
                                               "--set", "drop_test.gravity=true"],
         'drop_test.gravity = true: the static levels carry no gravity', 'method = "transient"'),
    # ---- the command line itself -----------------------------------------------------------------
    Case("unknown-subcommand", lambda t: ["simulate"], "invalid choice: 'simulate'"),
    Case("no-subcommand", lambda t: [], "the following arguments are required: command"),
]


@pytest.mark.parametrize("case", [c.param() for c in CASES])
def test_bad_input_is_one_line_exit_2_before_any_simulation(case, tmp_path, monkeypatch, capsys):
    check_one_line(case, tmp_path, monkeypatch, capsys)
