"""Configs: parsed once, converted to SI, and every kind of bad input refused in one line."""

import pytest

from jtire import units as U
from jtire.cli import main
from jtire.config import load_run_config, load_tire
from jtire.errors import ConfigError

from .conftest import REPO, TIRE_TOML

FOOTPRINT = REPO / "configs" / "experiments" / "footprint.toml"


def test_units_converted_once(spec):
    assert spec.geometry.rim_radius == pytest.approx(0.28575)
    assert spec.parts["crown"]["E_circumferential"] == pytest.approx(1e10)
    assert spec.relaxation_times == pytest.approx((1e-3, 6e-3, 4e-2))
    rc = load_run_config(FOOTPRINT)
    assert rc.condition["pressure_Pa"] == pytest.approx(120 * 6894.757293168)
    assert rc.condition["load_N"] == pytest.approx(4625 * 9.81)
    assert rc.solver["load_ramp"] == pytest.approx(0.1) and rc.solver["ke_tol"] == pytest.approx(1e-3)
    assert rc.experiments[0].proto.as_dict() == pytest.approx(rc.solver)


def test_overrides(tmp_path):
    rc = load_run_config(FOOTPRINT, ["condition.pressure_psi=70"])
    assert rc.condition["pressure_Pa"] == pytest.approx(70 * U.PSI)
    assert load_run_config(FOOTPRINT, ["tire.mesh.n_theta=48"]).tire.n_theta == 48
    assert load_run_config(FOOTPRINT, ["solver.load_ramp_s=0.05"]).solver["load_ramp"] == pytest.approx(0.05)
    # experiment tables: SI leaves of the experiment instance
    rc = load_run_config(REPO / "configs" / "experiments" / "lateral_stiffness.toml", ["lateral_stiffness.force_kN=3"])
    assert float(rc.experiments[0].force) == pytest.approx(3e3)


def test_several_experiments_and_unused_tables_are_validated():
    rc = load_run_config(REPO / "configs" / "default.toml")
    assert [e.name for e in rc.experiments] == ["footprint", "vertical_stiffness", "lateral_stiffness"]
    # a table of an experiment the config does not run is still checked
    with pytest.raises(ConfigError, match="drop_test.drop_height_mm = 900"):
        load_run_config(REPO / "configs" / "default.toml", ["drop_test.drop_height_mm=900"])


def _write(tmp_path, body, tire_body=None):
    tire = tmp_path / "tire.toml"
    tire.write_text(tire_body if tire_body is not None else TIRE_TOML.read_text())
    cfg = tmp_path / "exp.toml"
    cfg.write_text(f'tire_file = "tire.toml"\n{body}')
    return cfg


BAD_EXPERIMENTS = [
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = -3.0\n', "condition.pressure_psi = -3: must be in [10, 250] psi"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = 9000.0\n', "condition.pressure_psi = 9000: must be in"),
    ('experiment = "footprint"\n[condition]\nload_kg = "heavy"\npressure_psi = 120.0\n', "condition.load_kg = 'heavy': must be a number in [50, 50000] kg"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\npresure_psi = 120.0\n', "condition.presure_psi: unknown field"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\n', "give exactly one of pressure_psi"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\nload_kN = 45.0\npressure_psi = 120.0\n', "give exactly one of load_kg"),
    ('experiment = "flying"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n', "experiment = 'flying': unknown"),
    ('experiment = "footprint"\ncolour = "red"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n', "colour: unknown field"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n[solver]\nke_tol_J = 0.0\n', "solver.ke_tol_J = 0: must be in"),
    ('experiment = "vertical_stiffness"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n[vertical_stiffness]\nmax_load_kN = -60.0\n', "vertical_stiffness.max_load_kN = -60: must be in"),
    ('experiments = ["footprint", "footprint"]\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n', "each experiment at most once"),
    ('experiment = "footprint"\nexperiments = ["footprint"]\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n', "not both"),
    ('[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n', "needs experiment = NAME"),
    ('experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n[footprint]\nsize = 3\n', "footprint.size: unknown field"),
]


@pytest.mark.parametrize("body,message", BAD_EXPERIMENTS)
def test_bad_experiment_configs_rejected(tmp_path, body, message):
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]").replace("(", r"\(")):
        load_run_config(_write(tmp_path, body))


BAD_TIRES = [
    ("E_meridional_MPa = 1000.0", "E_meridional_MPa = -5.0", "parts.lower_sidewall.E_meridional_MPa = -5: must be in"),
    ("n_theta = 64", "n_theta = 8", "mesh.n_theta = 8: must be in [16, 1024]"),
    ("n_side = 5 ", "n_side = 7 ", "mesh.n_side = 7: must be a multiple of 5"),
    ("belt_kg = 70.75", "belt_kg = 90.0", "mass.belt_kg = 90: must be below mass.tire_kg"),
    ("friction = 0.8", "friction = true", "tread.friction = True: must be a number in [0, 3]"),
    ('rim_diameter_mm = 571.5', '', "tire.rim_diameter_mm: missing field"),
]


@pytest.mark.parametrize("old,new,message", BAD_TIRES)
def test_bad_tire_configs_rejected(tmp_path, old, new, message):
    text = TIRE_TOML.read_text()
    assert old in text
    body = 'experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n'
    with pytest.raises(ConfigError, match=message.replace("[", r"\[").replace("]", r"\]")):
        load_run_config(_write(tmp_path, body, text.replace(old, new, 1)))


def test_cli_reports_one_line_and_exit_code(tmp_path, capsys):
    cfg = _write(tmp_path, 'experiment = "footprint"\n[condition]\nload_kg = 4625.0\npressure_psi = -3.0\n')
    assert main(["run", str(cfg)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["jtire run: error: condition.pressure_psi = -3: must be in [10, 250] psi"]
    assert main(["run", str(FOOTPRINT), "--set", "condition.pressure_psi=abc"]) == 2
    assert "condition.pressure_psi = 'abc': must be a number in [10, 250] psi" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "missing.toml")]) == 2
    assert "no such config file" in capsys.readouterr().err


def test_tire_file_loads(spec):
    assert load_tire(TIRE_TOML) == spec
