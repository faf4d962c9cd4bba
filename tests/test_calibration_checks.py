"""The calibration's [checks]: measured responses (the footprint) simulated once at the calibrated
point and reported beside the targets, not fitted (calibration.tire.run.evaluate_checks)."""

import json

import pytest

from jtire.calibration.tire.spec import load_calibration
from jtire.cli import main
from jtire.errors import ConfigError

from .conftest import COARSE_SET, REPO

CAL = REPO / "configs" / "calibration"
TIRE = REPO / "configs" / "tires" / "xone_xda.toml"
# one static target and the two footprint checks of study.toml: a check costs one static solve
SMALL = f'''tire_file = "{TIRE}"
[targets.DZ]
experiment = "vertical_stiffness"
quantity = "deflection_m"
condition = {{ load_kg = 4625.0, pressure_psi = 120.0 }}
table = {{ stated_load_kN = 50.0, max_load_kN = 60.0 }}
measured_mm = 39.0625
[checks.FL]
experiment = "footprint"
quantity = "contact_length_m"
condition = {{ load_kg = 4625.0, pressure_psi = 120.0 }}
measured_mm = 200.12
[checks.FW]
experiment = "footprint"
quantity = "contact_width_m"
condition = {{ load_kg = 4625.0, pressure_psi = 120.0 }}
measured_mm = 379.32
[[free]]
name = "parts.mid_sidewall.E_bending"
factor = [0.33, 3.0]
'''


def test_shipped_configs_check_the_footprint():
    for name in ("study", "track", "study_moduli_only"):
        spec = load_calibration(CAL / f"{name}.toml")
        assert [(c.name, c.experiment, round(c.measured * 1e3, 2)) for c in spec.checks] == [
            ("FL", "footprint", 200.12), ("FW", "footprint", 379.32)], name
        # not part of what fixes the calibration's numbers: adding checks keeps a folder resumable
        assert "checks" not in json.dumps(spec.fingerprint())


@pytest.mark.parametrize("edit, words", [
    (("[checks.FL]", "[checks.DZ]"), "checks.DZ: also a target"),
    (("measured_mm = 200.12", "measured_mm = -200.12"), "checks.FL.measured_mm = -200.12"),
    (('quantity = "contact_length_m"', 'quantity = "contact_len"'), "checks.FL.quantity = 'contact_len'"),
])
def test_bad_checks_are_one_line(tmp_path, edit, words):
    cfg = tmp_path / "c.toml"
    cfg.write_text(SMALL.replace(*edit, 1))
    with pytest.raises(ConfigError, match=words):
        load_calibration(cfg)


@pytest.mark.slow  # 51 s with a cold compile cache (E02 and E01 through the CLI's own tire)
def test_check_tire_reports_the_footprint_on_the_shell_model(tmp_path, capsys):
    # coarse ring, one E02 solve and one E01 solve at rated. The footprint of the default tire is
    # ~0.2 m long and ~0.35 m wide (E01 on the default mesh: 207 x 357 mm); the coarse ring's
    # 32 segments of 0.1 m make the length coarse, so only a physical range is asserted here:
    # longer than one segment pitch, shorter than the 0.4 m of a 2-segment chord, and a width
    # inside the tread's 0.2-0.45 m.
    cfg = tmp_path / "c.toml"
    cfg.write_text(SMALL)
    sets = [a for s in COARSE_SET for a in ("--set", "tire." + s.split("tire.", 1)[1])]
    assert main(["calibrate", str(cfg), "--check-tire", str(TIRE), "--out", str(tmp_path / "o"), *sets]) == 0
    out = capsys.readouterr().out
    assert "| FL (check) | footprint | 200.12 mm |" in out and "not fitted" in out
    rows = {r["target"]: r for r in json.loads((tmp_path / "o" / "check_tire.json").read_text())["rows"]}
    assert 100.0 < rows["FL (check)"]["simulated"] < 400.0
    assert 200.0 < rows["FW (check)"]["simulated"] < 450.0
    assert rows["FL (check)"]["error_pct"] == pytest.approx(
        abs(rows["FL (check)"]["simulated"] / 200.12 - 1) * 100)
