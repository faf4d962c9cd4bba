"""The chapter 5-6 figure scripts (paper_figures/fig5_*, fig6_*) and their data layer.

One session fixture runs each experiment the figures need once, small (`_data.run_cases` with
--quick's settings: the 32 x 4 ring, short durations, two conditions), into a characterization
folder; every figure test then draws from it with --from (no simulation), checks the PNG and the
number of curves the script reports. One test (slow) runs a script end to end without --from. The E01
runs also give the check that the contact pressure of a simulated footprint integrates to the load.
"""

import importlib.util
import re
import shutil
import sys

import numpy as np
import pytest

from jtire import units as U
from jtire.experiments import REGISTRY

from .conftest import REPO

FIG_DIR = REPO / "paper_figures"
sys.path.insert(0, str(FIG_DIR))
import _data  # noqa: E402

# script stem -> (experiment, condition kind)
FIGURES = {
    "fig5_2_footprints": ("footprint", "grid"),
    "fig5_4_vertical_load_deflection": ("vertical_stiffness", "pressures"),
    "fig5_6_cleat_axle_force": ("drum_cleat", "loads"),
    "fig5_8_drop_test": ("drop_test", "loads"),
    "fig5_10_inplane_rotation_decay": ("inplane_rotation", "per_pressure"),
    "fig5_12_traction_force_slip": ("traction", "loads"),
    "fig6_2_sidewall_translation_decay": ("sidewall_translation", "per_pressure"),
    "fig6_4_sidewall_camber_decay": ("sidewall_camber", "per_pressure"),
    "fig6_6_lateral_release": ("lateral_stiffness", "loads"),
    "fig6_8_lateral_force_slip": ("cornering", "loads"),
    "fig6_9_aligning_moment_slip": ("cornering", "loads"),
}
MIN_PNG_BYTES = 15_000  # an empty 80-dpi axes is ~8 kB; any of these figures with curves is well above
E01_LOAD_TOL = 0.01  # the brief's 1 %: the settled E01 state's contact force vs the rim load


def _script(stem):
    spec = importlib.util.spec_from_file_location(stem, FIG_DIR / f"{stem}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _skip_missing(experiment):
    if experiment not in REGISTRY:
        pytest.skip(f"experiment {experiment!r} is not in jtire.experiments.REGISTRY yet (E06 is being rebuilt)")


@pytest.fixture(scope="session")
def char_dir(tmp_path_factory):
    """Every experiment the figures use, run once small into DIR/<experiment>/cases/... ."""
    from jtire import cache

    cache.enable()
    root = tmp_path_factory.mktemp("char")
    done = set()
    for experiment, kind in FIGURES.values():
        if experiment in done or experiment not in REGISTRY:
            continue
        _data.run_cases(experiment, _data.conditions(kind, quick=True), quick=True, out_root=root)
        done.add(experiment)
    return root


def _run(stem, argv, capsys):
    assert _script(stem).main(argv) == 0
    out = capsys.readouterr().out
    m = re.search(r"curves=(\d+)", out)
    assert m, out
    return int(m.group(1))


# Drawing every figure from results needs every experiment the figures use run first (the char_dir
# fixture: drum, free drum, rigid belt, cornering programs; ~5-8 min here): slow checks.
@pytest.mark.slow
@pytest.mark.parametrize("stem", sorted(FIGURES))
def test_figure_from_results(stem, char_dir, tmp_path, capsys):
    experiment, kind = FIGURES[stem]
    _skip_missing(experiment)
    out = tmp_path / f"{stem}.png"
    n = _run(stem, ["--from", str(char_dir), "--quick", "--out", str(out)], capsys)
    assert n == len(_data.conditions(kind, quick=True))  # one curve (panel) per condition run
    assert out.stat().st_size > MIN_PNG_BYTES
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.slow
def test_plain_sweep_layout_is_read(char_dir, tmp_path):
    """`jtire sweep` writes DIR/cases/... without the experiment level: the same cases come back."""
    shutil.copytree(char_dir / "drop_test", tmp_path / "sweep")
    a = _data.load_cases(char_dir, "drop_test")
    b = _data.load_cases(tmp_path / "sweep", "drop_test")
    assert [c.name for c in a] == [c.name for c in b] and len(a) == 2
    assert np.array_equal(a[0].signals["rim_z_m"], b[0].signals["rim_z_m"])
    with pytest.raises(Exception, match="no results of footprint"):
        _data.load_cases(tmp_path / "sweep", "footprint")


def test_selection_from_a_grid():
    """From a full 3 x 3 grid: "loads" takes the 120 psi row, "pressures" the 4625 kg column."""
    grid = [_data.Case(f"{i:03d}", "x", c, {}) for i, c in enumerate(_data.conditions("grid", quick=False))]
    loads = _data.select(grid, "loads")
    assert [round(c.load_kg, 1) for c in loads] == list(_data.LOADS_KG)
    assert {round(c.pressure_psi, 6) for c in loads} == {120.0}
    pressures = _data.select(grid, "pressures")
    assert [round(c.pressure_psi, 6) for c in pressures] == list(_data.PRESSURES_PSI)
    assert {round(c.load_kg, 1) for c in pressures} == {4625.0}
    assert len(_data.select(grid, "grid")) == 9


@pytest.mark.slow
def test_footprint_pressure_integrates_to_the_load(char_dir):
    """The contact pressure of a simulated, settled footprint times each point's area, summed over
    the patch, is the rim load (the road carries the wheel)."""
    for c in _data.load_cases(char_dir, "footprint"):
        t = c.tables["contact_pressure"]
        total = float(np.sum(t["contact_pressure_Pa"] * t["point_area_m2"]))
        assert total == pytest.approx(c.condition["load_N"], rel=E01_LOAD_TOL)
        # and the patch it covers is E01's measured extent (within one contact point's size)
        span = np.ptp(t["point_x_m"]) + np.max(t["point_dx_m"])
        assert abs(span - c.quantities["contact_length_m"]) < 2 * np.max(t["point_dx_m"])


# ~45 s here (its quick protocol compiles programs of its own): a slow check; the fast suite draws
# Figure 5-2 from a real characterization instead (below), the README's way of making the figures
@pytest.mark.slow
def test_one_script_end_to_end(tmp_path, capsys):
    """fig6_2 simulates its own runs (E07 at two pressures, quick) through the public API."""
    out = tmp_path / "fig6_2.png"
    n = _run("fig6_2_sidewall_translation_decay", ["--quick", "--out", str(out)], capsys)
    assert n == 2 and out.stat().st_size > MIN_PNG_BYTES


def test_missing_folder_is_one_line(tmp_path, capsys, monkeypatch):
    mod = _script("fig5_8_drop_test")
    monkeypatch.setattr(sys, "argv", ["fig5_8_drop_test.py", "--from", str(tmp_path / "none")])
    assert _style_guard()(mod.main) == 2
    assert "no such folder" in capsys.readouterr().err


def _style_guard():
    import _style

    return _style.guard


def test_quick_conditions_are_SI():
    c = _data.conditions("loads", quick=True)
    assert c[0]["pressure_Pa"] == pytest.approx(120 * U.PSI) and c[0]["load_N"] == pytest.approx(2312.5 * U.G0)


# gate: a characterize subprocess of its own (~30 s cold here)
@pytest.mark.slow
@pytest.mark.gate
def test_footprint_figure_from_a_characterization(tmp_path, capsys):
    """`jtire characterize` writes each footprint case's contact-pressure table, so Figure 5-2 draws
    from a characterization folder (--from) as every other figure does; the table integrates to the
    case's load (E01_LOAD_TOL). Coarse ring, footprint only, 2 conditions (~1 min here)."""
    from jtire.cli import main

    from .conftest import COARSE_SET, SOLVER_SET

    out = tmp_path / "char"
    argv = ["characterize", str(REPO / "configs" / "characterize.toml"), "--set", 'experiments=["footprint"]',
            "--set", "grid.loads_kg=[2312.5, 4625.0]", "--set", "grid.pressures_psi=[120.0]",
            *[a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)], "--no-validate", "--out", str(out)]
    assert main(argv) == 0
    cases = sorted((out / "footprint" / "cases").glob("*"))
    assert len(cases) == 2
    for c in cases:
        t = np.genfromtxt(c / "contact_pressure.csv", delimiter=",", names=True)
        load = __import__("json").loads((c / "result.json").read_text())["condition"]["load_N"]
        assert float(np.sum(t["contact_pressure_Pa"] * t["point_area_m2"])) == pytest.approx(load, rel=E01_LOAD_TOL)
    capsys.readouterr()
    assert _run("fig5_2_footprints", ["--from", str(out), "--out", str(tmp_path / "f.png")], capsys) == 2
    assert (tmp_path / "f.png").stat().st_size > MIN_PNG_BYTES
