"""`jtire new-tire`: size designations, load indices, the generated files, and the generated tires against an
independent estimate (Rhyne's vertical-stiffness formula at the load index's rated condition)."""

import math
import tomllib

import pytest

from .conftest import COARSE_SET, REPO
from jtire import new_tire, sizes
from jtire.cli import main
from jtire.config import load_run_config, read_toml
from jtire.errors import ConfigError

FOUR = ("445/50R22.5", "295/75R22.5", "315/80R22.5", "205/55R16")


def test_load_index_table():
    """ISO 4000 / ETRTO load indices: one entry per index 60-200, rising; anchors from the published table
    (91 and 110 from passenger charts, 142, 165 and 168 from tractor manuals, 161 = the study's 4625 kg)."""
    lo, hi = sizes.LOAD_INDEX_RANGE
    loads = [sizes.load_index_kg(i) for i in range(lo, hi + 1)]
    assert len(loads) == hi - lo + 1 and all(a < b for a, b in zip(loads, loads[1:]))
    # each step is ~2.5-4 %: a mistyped entry breaks the geometric progression
    assert all(1.01 < b / a < 1.045 for a, b in zip(loads, loads[1:]))
    anchors = {91: 615, 110: 1060, 142: 2650, 161: 4625, 165: 5150, 168: 5600}
    assert {i: sizes.load_index_kg(i) for i in anchors} == anchors
    for bad in (59, 201):
        with pytest.raises(ConfigError, match="--load-index"):
            sizes.load_index_kg(bad)


def test_designation_reproduces_the_study_tire():
    """445/50R22.5 from its designation against the study's own tire file: width and rim exact, the section
    height (a nominal 50 % against the study's 223.75 mm) and so the diameter within 3 mm, the measuring rim
    the study's 14.00 in."""
    size = sizes.parse_size("445/50R22.5")
    t = read_toml(REPO / "configs" / "tires" / "xone_xda.toml")["tire"]
    assert size.kind == "truck"
    assert size.section_width * 1e3 == pytest.approx(t["section_width_mm"])
    assert size.rim_diameter * 1e3 == pytest.approx(t["rim_diameter_mm"])
    assert abs(size.section_height * 1e3 - t["section_height_mm"]) < 3.0
    assert abs(size.outer_diameter * 1e3 - t["outer_diameter_mm"]) < 3.0
    assert sizes.measuring_rim_in(size) * 25.4 == pytest.approx(t["rim_width_mm"])
    p = sizes.parse_size("P205/55 ZR16")
    assert (p.text, p.kind) == ("205/55R16", "passenger")
    assert p.outer_diameter * 1e3 == pytest.approx(406.4 + 2 * 112.75)


def test_measuring_rim_rule():
    """The rule for sizes outside the table, against measuring rims it was not read from (ETRTO): within
    0.5 in."""
    for text, rim_in in (("385/65R22.5", 11.75), ("275/70R22.5", 8.25), ("195/65R15", 6.0), ("225/45R17", 7.5),
                         ("175/70R13", 5.0)):
        assert abs(sizes.measuring_rim_in(sizes.parse_size(text)) - rim_in) <= 0.5, text


def test_generated_tire_scales_the_study_tire():
    """The 445/50R22.5 generated from its designation is the shipped tire again where the rules say so: the
    same materials (the template's block, verbatim), the mass scaled by its 1.25 mm lower section (< 1 %)."""
    _, rated, files = new_tire.files_for("445/50R22.5")
    gen, ship = tomllib.loads(files["tire.toml"]), read_toml(REPO / "configs" / "tires" / "xone_xda.toml")
    assert gen["parts"] == ship["parts"] and gen["tread"] == ship["tread"] and gen["undertread"] == ship["undertread"]
    assert gen["mass"]["tire_kg"] == pytest.approx(ship["mass"]["tire_kg"], rel=0.01)
    assert gen["mass"]["rim_kg"] == pytest.approx(ship["mass"]["rim_kg"], rel=1e-3)
    assert gen["mass"]["rim_Iy_kgm2"] == pytest.approx(ship["mass"]["rim_Iy_kgm2"], rel=1e-3)
    assert gen["tire"]["crown_radius_mm"] == pytest.approx(ship["tire"]["crown_radius_mm"], rel=1e-3)
    assert (rated.load_kg, rated.pressure_kPa) == (4625.0, pytest.approx(120 * 6.894757, rel=1e-3))


@pytest.mark.parametrize("text", FOUR)
def test_generated_configs_validate(tmp_path, text):
    """Each size's three files load as `jtire run` and `jtire characterize` load them; the run config is at the
    rated condition, E02's ramp above it, E09's force 11 % of it (as the shipped 5 kN at 45.4 kN)."""
    from jtire.characterize import load_plan

    size, rated, files = new_tire.files_for(text)
    for name, body in files.items():
        (tmp_path / name).write_text(body)
    rc = load_run_config(tmp_path / "run.toml")
    assert rc.condition["load_N"] == pytest.approx(rated.load_kg * 9.81)
    assert rc.condition["pressure_Pa"] == pytest.approx(rated.pressure_kPa * 1e3)
    assert rc.tables["vertical_stiffness"]["max_load_kN"] > 1.3 * rated.load_N
    assert rc.tables["lateral_stiffness"]["force_kN"] == pytest.approx(0.11 * rated.load_N, rel=1e-2)
    assert rc.tire.size == size.text and rc.tire.geometry.outer_radius == pytest.approx(size.outer_diameter / 2)
    plan = load_plan(tmp_path / "characterize.toml")
    loads = sorted({c["load_N"] for c in plan.conditions})
    assert loads == pytest.approx([0.5 * rated.load_N, rated.load_N, 1.5 * rated.load_N], rel=1e-3)
    assert plan.rated["load_N"] == pytest.approx(rated.load_N, rel=1e-3)


@pytest.mark.parametrize("argv, field", [
    (["11R22.5"], "size '11R22.5'"),
    (["225/45R17"], "--load-index: needed for 225/45R17"),
    (["225/45R17", "--load-index", "250"], "--load-index 250"),
    (["295/75R22.5", "--pressure-kPa", "5000"], "--pressure-kPa 5000"),
    (["295/75R22.5", "--rim-width-in", "14"], "--rim-width-in 14"),
])
def test_bad_input_is_one_line(tmp_path, monkeypatch, capsys, argv, field):
    monkeypatch.chdir(tmp_path)
    assert main(["new-tire", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err
    assert not (tmp_path / "tires").exists()


def test_refuses_to_overwrite(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["new-tire", "205/55R16"]) == 0
    before = (tmp_path / "tires" / "205_55R16" / "tire.toml").read_text()
    assert main(["new-tire", "205/55R16", "--pressure-kPa", "290"]) == 2
    assert "--force" in capsys.readouterr().err
    assert (tmp_path / "tires" / "205_55R16" / "tire.toml").read_text() == before
    assert main(["new-tire", "205/55R16", "--pressure-kPa", "290", "--force"]) == 0
    assert "pressure_kPa = 290" in (tmp_path / "tires" / "205_55R16" / "tire.toml").read_text()


def _quantity(out: str, name: str) -> float:
    return float(next(ln.split()[1] for ln in out.splitlines() if ln.split()[:1] == [name]))


def test_passenger_tire_runs_e01_e02_e09_e12(tmp_path, monkeypatch, capsys):
    """The smallest size, furthest from the shipped truck tire: `jtire new-tire 205/55R16`, then its run config
    on the coarse ring: E01, E02, E09 and E12 converge, the footprint lies inside the tread, the rolling
    resistance from the hub force agrees with the dissipated power within 10 % (the coarse ring's contact
    ripple), and the RRC is a passenger tire's (0.005-0.02)."""
    monkeypatch.chdir(tmp_path)
    assert main(["new-tire", "205/55R16"]) == 0
    capsys.readouterr()
    assert main(["run", "tires/205_55R16/run.toml", *[a for s in COARSE_SET for a in ("--set", s)]]) == 0
    out = capsys.readouterr().out
    assert [ln.split()[:2] for ln in out.splitlines() if ln.split()[:1] == ["converged"]] == [["converged", "True"]] * 4
    assert 0.05 < _quantity(out, "contact_length_m") < 0.25
    assert 0.1 < _quantity(out, "contact_width_m") <= 0.19  # the tread is 172 mm wide
    assert _quantity(out, "k_l_N_per_m") > 0
    rrc, rrc_power = _quantity(out, "rrc"), _quantity(out, "rrc_from_power")
    assert 0.005 < rrc < 0.02 and rrc_power == pytest.approx(rrc, rel=0.1)


@pytest.mark.slow
@pytest.mark.gate
@pytest.mark.parametrize("text", FOUR)
def test_vertical_stiffness_against_rhyne(tmp_path, text):
    """The issue's goal: each generated tire's E02 secant stiffness at its rated load and pressure (default
    mesh, static) within 20 % of Rhyne's formula. 20 %: the formula's own spread (the study's measured
    445/50R22.5 reads 1280 kN/m at 50 kN against Rhyne's 1562 kN/m, 18 % below) and materials that are
    defaults, not calibrated. Measured: -12 %, -8 %, -10 %, +3 % (docs/new-tire.md)."""
    from jtire import batch

    size, rated, files = new_tire.files_for(text)
    for name, body in files.items():
        (tmp_path / name).write_text(body)
    rc = load_run_config(tmp_path / "run.toml", ["experiments=[\"vertical_stiffness\"]"])
    from jtire.tire import make_tire

    (res,) = batch.run(rc.experiments[0], make_tire(rc.tire), [rc.condition])
    assert res.checks["static_converged"]
    k = res.quantities["k_sv_N_per_m"]
    k_rhyne = sizes.rhyne_stiffness(size, rated.pressure_kPa * 1e3)
    assert math.isfinite(k) and abs(k / k_rhyne - 1) < 0.20, (text, k, k_rhyne)


EXAMPLE_CSV = REPO / "configs" / "data" / "measurements_example.csv"


def test_measured_csv_to_calibration(tmp_path):
    """--measured: one target per row at the row's own condition; a stiffness becomes the deflection at its
    load (the study's DZ / DY form), F / k; rolling resistance gets the non-tire drag bias (bounds 0 to twice
    the largest measured drag); the study's free parameters, the crown radius relative to this tire's."""
    from jtire.calibration.tire.spec import load_calibration

    _, _, files = new_tire.files_for("295/75R22.5", measured=EXAMPLE_CSV)
    for name, body in files.items():
        (tmp_path / name).write_text(body)
    spec = load_calibration(tmp_path / "calibrate.toml", [])
    t = {x.name: x for x in spec.targets}
    assert list(t) == ["DZ1", "DY1", "FL1", "FW1", "FX1"]
    f = 2800 * 9.81
    assert t["DZ1"].measured == pytest.approx(f / 1100e3, rel=1e-4) and t["DZ1"].table["stated_load_kN"] == pytest.approx(f, rel=1e-4)
    assert t["DY1"].measured == pytest.approx(t["DY1"].table["force_kN"] / 420e3, rel=1e-4)
    assert t["FX1"].measured == 165.0 and t["FX1"].table["speed_mph"] == pytest.approx(80 / 3.6, rel=1e-3)  # SI inside: m/s
    assert t["FL1"].condition["pressure_Pa"] == pytest.approx(758e3)
    study = load_calibration(REPO / "configs" / "calibration" / "study.toml", [])
    assert spec.space.names == study.space.names
    cal = tomllib.loads(files["calibrate.toml"])
    crown = next(x for x in cal["free"] if x["name"] == "geometry.crown_radius")
    assert crown["factor"] == [0.5, 4.0]  # the study's 1-8 m around its 2 m
    bias = next(x for x in cal["free"] if x["name"] == "bias.non_tire_drag")
    assert bias["bounds"] == [0.0, 330.0] and bias["targets"] == ["FX1"]


@pytest.mark.parametrize("row, field", [
    ("k_sv,1100,lb/in,2800,758,", "line 7: unit 'lb/in' for k_sv"),
    ("stiffness,1100,kN/m,2800,758,", "line 7: quantity 'stiffness'"),
    ("k_sv,-5,kN/m,2800,758,", "line 7: value = -5"),
    ("k_sv,1100,kN/m,2800,9999,", "line 7: pressure_kPa = 9999"),
    ("k_sv,1100,kN/m,heavy,758,", "line 7: load_kg = 'heavy'"),
])
def test_bad_measurements_are_one_line(tmp_path, monkeypatch, capsys, row, field):
    monkeypatch.chdir(tmp_path)
    lines = EXAMPLE_CSV.read_text().splitlines()
    header = next(i for i, ln in enumerate(lines) if ln.startswith("quantity,"))
    (tmp_path / "m.csv").write_text("\n".join(lines[:header + 1] + [row]) + "\n")
    assert header + 2 == 7  # the row's line number in the messages above
    assert main(["new-tire", "295/75R22.5", "--measured", "m.csv"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "m.csv" in err and field in err, err
    assert not (tmp_path / "tires").exists()



def test_standin_refuses_a_target_it_has_no_formula_for(tmp_path, monkeypatch, capsys):
    """A calibration whose target the closed-form stand-in cannot give (E02's secant k_sv instead of the
    deflection) stops with one line before anything runs, not with a traceback mid-run."""
    monkeypatch.chdir(tmp_path)
    assert main(["new-tire", "295/75R22.5", "--measured", str(EXAMPLE_CSV)]) == 0
    cal = tmp_path / "tires" / "295_75R22.5" / "calibrate.toml"
    text = cal.read_text().replace('quantity = "deflection_m"', 'quantity = "k_sv_N_per_m"', 1)
    cal.write_text(text.replace("measured_mm = 24.971", "measured_kN_per_m = 1100", 1))
    capsys.readouterr()
    assert main(["calibrate", str(cal), "--out", "runs/cal", "--standin", "--budget", "28"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "targets.DZ1: the stand-in has no vertical_stiffness.k_sv_N_per_m" in err
