"""The tutorial "Read the .tir into a vehicle model" (docs/tutorials/tir.md) and its scripts
examples/mf61_lateral.py (an MF 6.1 reader and F_y0(alpha) evaluator written without jtire) and
examples/mf61_longitudinal.py (F_x0(kappa) on the same reader, against the simulated E06 curves).

Fast: the .tir comes from the synthetic characterization the rigid-ring tests use (no shell
simulation), exported by `jtire export-tir` as a user runs it. References and tolerances:
- jtire's own Magic Formula (jtire.rigid_ring.magic_formula.fy0 / mz0) on the dict jtire's reader
  returns: the same published equations (Pacejka 2012 §4.3.2) coded twice, in float64, on the same
  coefficients, so they agree to rounding; 1e-9 relative (1e-9 of the curve's peak near F_y = 0).
  Run on jtire's file and on one with every shift/curvature/residual-torque term jtire leaves at 0
  switched on, so each term of the equations is compared.
- The printed cornering stiffness: the closed form K_y = PKY1 FNOMIN sin(PKY4 atan(F_z / (PKY2
  FNOMIN))) computed here (2e-6: the table prints 7 significant digits) and the printed numerical
  slope (1e-4: a central difference, h = 1e-6 rad, is exact to ~1e-10 here).
"""

import ast
import importlib.util
import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

from jtire.cli import main
from jtire.rigid_ring import magic_formula as mf
from jtire.rigid_ring import synthetic
from jtire.rigid_ring import tir as jtir
from jtire.rigid_ring.table import write_characterization

from .conftest import REPO

SCRIPT = REPO / "examples" / "mf61_lateral.py"
PAGE = REPO / "docs" / "tutorials" / "tir.md"
COMMAND = "python examples/mf61_lateral.py runs/characterize/tire.tir --out runs/fy_alpha.png"
ROW = re.compile(r"^\s*(\d+\.\d\d)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$")
# terms jtire's fit leaves at 0 (shifts, dfz^2, residual torque), switched on to compare every term
PERTURBED = {"PHY1": 0.004, "PHY2": -0.002, "PVY1": 0.03, "PVY2": -0.01, "PEY3": 0.2, "PKY4": 1.7,
             "QHZ1": 0.003, "QHZ2": -0.002, "QBZ3": 0.6, "QBZ9": 2.0, "QBZ10": 0.4, "QEZ3": -0.3, "QEZ4": 0.2,
             "QDZ6": 0.003, "QDZ7": -0.001}


def make_tir(folder, tir_path):
    """The synthetic characterization in folder, exported to tir_path by `jtire export-tir`."""
    write_characterization(folder, synthetic.characterization())
    assert main(["export-tir", str(folder), "--out", str(tir_path)]) == 0
    assert tir_path.is_file()


def run_script(*args, cwd=None):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True, check=False,
                          cwd=cwd, timeout=120)


def with_values(text, values):
    """The .tir text with KEY = value lines replaced (every key must be in the file once)."""
    for k, v in values.items():
        text, n = re.subn(rf"^{k}(\s*)=\s*\S+", rf"{k}\g<1>= {v!r}", text, flags=re.MULTILINE)
        assert n == 1, k
    return text


def table(stdout):
    """The printed rows: (F_z, K_y formula, K_y numeric, peak |F_y|, its alpha, D_y)."""
    return [tuple(map(float, m.groups())) for m in map(ROW.match, stdout.splitlines()) if m]


@pytest.fixture(scope="module")
def tir_path(tmp_path_factory):
    d = tmp_path_factory.mktemp("tir")
    make_tir(d / "characterize", d / "tire.tir")
    return d / "tire.tir"


def load_script(path):
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def script():
    return load_script(SCRIPT)


def jtire_reference(path):
    """jtire's reader and evaluator inputs: the coefficient dict and the Nominal."""
    t = jtir.read(path)
    c = t["LATERAL_COEFFICIENTS"] | t["ALIGNING_COEFFICIENTS"]
    return c, mf.Nominal(t["VERTICAL"]["FNOMIN"], t["OPERATING_CONDITIONS"]["NOMPRES"], t["DIMENSION"]["UNLOADED_RADIUS"])


def test_script_is_independent_of_jtire():
    """It stands for the engineer's own tool: it imports only numpy, matplotlib and the standard library."""
    tree = ast.parse(SCRIPT.read_text())
    mods = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    mods |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert mods <= {"argparse", "json", "math", "sys", "pathlib", "numpy", "matplotlib"}, mods
    assert len(SCRIPT.read_text().splitlines()) <= 300


def test_script_runs_and_plots(tir_path, tmp_path):
    """(a) rc 0, one row per load asked, a PNG with curves in it (an empty pair of axes is ~12 kB)."""
    png = tmp_path / "out" / "fy.png"
    r = run_script(tir_path, "--out", png, "--loads-kN", "20,45.4,68")
    assert r.returncode == 0, r.stderr
    assert [row[0] for row in table(r.stdout)] == [20000.0, 45400.0, 68000.0]
    data = png.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 40_000, len(data)


@pytest.mark.parametrize("values", [{}, PERTURBED], ids=["jtire_file", "every_term_on"])
def test_agrees_with_jtire_magic_formula(script, tir_path, tmp_path, values):
    """(b) F_y0, M_z0 and K_y of the script = jtire's magic_formula on jtire's reader, 1e-9."""
    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), values))
    c_ref, nom = jtire_reference(path)
    c, lacking = script.coefficients(path, script.parse_tir(path))
    assert lacking == []
    fz, alpha = np.meshgrid(np.array([0.4, 0.5, 1.0, 1.5, 1.8]) * nom.fnomin,
                            np.radians([-15, -8, -3, -1, -0.2, 0, 0.2, 1, 3, 8, 15]))
    for mine, ref in [(script.lateral(c, fz, alpha)["fy"], mf.fy0(c_ref, nom, fz, alpha)),
                      (script.aligning(c, fz, alpha), mf.mz0(c_ref, nom, fz, alpha)),
                      (script.lateral(c, fz[0], 0.0)["ky"], mf.cornering_stiffness(c_ref, nom, fz[0]))]:
        np.testing.assert_allclose(mine, ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
    assert np.ptp(mf.mz0(c_ref, nom, fz, alpha)) > 0  # the comparison is of curves, not zeros


def test_scaling_factors_in_the_file_apply(script, tir_path, tmp_path):
    """LKY scales K_y (4.E25), LMUY the peak D_y (4.E23), LFZO the nominal load F'_z0 (4.E1)."""
    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), {"LKY": 1.3, "LMUY": 0.8}))
    c0, _ = script.coefficients(tir_path, script.parse_tir(tir_path))
    c, _ = script.coefficients(path, script.parse_tir(path))
    p0, p = script.lateral(c0, 40e3, 0.0), script.lateral(c, 40e3, 0.0)
    assert p["ky"] == pytest.approx(1.3 * p0["ky"], rel=1e-12) and p["dy"] == pytest.approx(0.8 * p0["dy"], rel=1e-12)
    half = with_values(tir_path.read_text(), {"LFZO": 0.5, "FNOMIN": 2 * c0["FNOMIN"]})
    path.write_text(half)
    c, _ = script.coefficients(path, script.parse_tir(path))
    a = np.radians([-7.0, 1.0, 12.0])
    np.testing.assert_allclose(script.lateral(c, 40e3, a)["fy"], script.lateral(c0, 40e3, a)["fy"], rtol=1e-12)


def test_printed_cornering_stiffness(tir_path, tmp_path):
    """(c) printed K_y = the closed form (2e-6) = the printed numerical slope (1e-4); peak and D_y as jtire's."""
    r = run_script(tir_path, "--out", tmp_path / "fy.png")
    assert r.returncode == 0, r.stderr
    rows = table(r.stdout)
    t = jtir.read(tir_path)
    lat, fnom = t["LATERAL_COEFFICIENTS"], t["VERTICAL"]["FNOMIN"]
    loads = [0.5 * fnom, fnom, 1.5 * fnom]  # the default loads
    assert [row[0] for row in rows] == pytest.approx(loads, abs=0.006)
    c_ref, nom = jtire_reference(tir_path)
    grid = np.radians(np.linspace(-15, 15, 3001))
    for fz, (_, k_formula, k_numeric, peak, _, dy) in zip(loads, rows):
        closed = lat["PKY1"] * fnom * np.sin(lat["PKY4"] * np.arctan(fz / (lat["PKY2"] * fnom)))
        assert k_formula == pytest.approx(closed, rel=2e-6)
        assert k_numeric == pytest.approx(k_formula, rel=1e-4)
        assert peak == pytest.approx(np.max(np.abs(mf.fy0(c_ref, nom, fz, grid))), rel=2e-6)
        assert dy == pytest.approx((lat["PDY1"] + lat["PDY2"] * (fz - fnom) / fnom) * fz, rel=2e-6)


def test_numerical_slope_is_numerical(script, tir_path, tmp_path):
    """With shifts S_Hy, S_Vy the slope at alpha = 0 differs from K_y (the slope at alpha_y = 0): the
    numeric column follows a central difference of jtire's F_y0 (1e-6), not the formula."""
    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), PERTURBED | {"PHY1": 0.02}))
    c_ref, nom = jtire_reference(path)
    c, _ = script.coefficients(path, script.parse_tir(path))
    fz, h = 30e3, 1e-5
    ref = (mf.fy0(c_ref, nom, fz, h) - mf.fy0(c_ref, nom, fz, -h)) / (2 * h)
    assert script.numerical_slope(c, fz) == pytest.approx(ref, rel=1e-6)
    assert abs(ref - script.lateral(c, fz, 0.0)["ky"]) > 1e-3 * abs(ref)


@pytest.mark.parametrize("case", ["missing_file", "no_PKY1", "quoted_number", "not_a_tir"])
def test_bad_input_exits_2(tir_path, tmp_path, case):
    """(d) exit 2, one line on stderr naming the file (and the key), no PNG."""
    path, key = tmp_path / f"{case}.tir", None
    text = tir_path.read_text()
    if case == "no_PKY1":
        path.write_text(re.sub(r"^PKY1\s*=.*\n", "", text, flags=re.MULTILINE))
        key = "PKY1"
    elif case == "quoted_number":
        path.write_text(re.sub(r"^(PDY1\s*=\s*)(\S+)", r"\1'\2'", text, flags=re.MULTILINE))
        key = "PDY1"
    elif case == "not_a_tir":
        path.write_text("FNOMIN = 4000\n")
    png = tmp_path / "fy.png"
    r = run_script(path, "--out", png)
    assert r.returncode == 2 and r.stdout == "" and not png.exists()
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and str(path) in lines[0], r.stderr
    assert key is None or key in lines[0]


def test_tutorial_tir_commands(tmp_path):
    """The page's command, run as written from a folder holding runs/characterize/tire.tir (made by
    `jtire export-tir` from the synthetic characterization) and a link to examples/; the output block
    the page shows is what it prints on that file."""
    page = PAGE.read_text()
    blocks = re.split(r"^```.*$", page, flags=re.MULTILINE)[1::2]
    assert any(COMMAND in b.splitlines() for b in blocks), "the page's code block with the command changed"
    (tmp_path / "examples").symlink_to(REPO / "examples")
    make_tir(tmp_path / "runs" / "characterize", tmp_path / "runs" / "characterize" / "tire.tir")
    argv = shlex.split(COMMAND)
    r = subprocess.run([sys.executable, *argv[1:]], cwd=tmp_path, capture_output=True, text=True,
                       check=False, timeout=120)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "runs" / "fy_alpha.png").stat().st_size > 40_000
    shown = next(b for b in blocks if b.strip().startswith("runs/characterize/tire.tir: FITTYP"))
    assert r.stdout.strip() == shown.strip()


# ---- examples/mf61_longitudinal.py ------------------------------------------------------------------------
SCRIPT_X = REPO / "examples" / "mf61_longitudinal.py"
COMMAND_X = ("python examples/mf61_longitudinal.py runs/characterize/tire.tir --curves "
             "runs/characterize/characterization.json --out runs/fx_kappa.png")
PERTURBED_X = {"PHX1": 0.004, "PHX2": -0.002, "PVX1": 0.01, "PVX2": -0.005, "PEX4": 0.2, "LKX": 1.1, "LMUX": 0.9}


@pytest.fixture(scope="module")
def script_x():
    return load_script(SCRIPT_X)


def test_longitudinal_script_is_independent_of_jtire():
    tree = ast.parse(SCRIPT_X.read_text())
    mods = {a.name.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    mods |= {n.module.split(".")[0] for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert mods <= {"argparse", "json", "math", "sys", "pathlib", "numpy", "matplotlib", "mf61_lateral"}, mods


@pytest.mark.parametrize("values", [{}, {k: v for k, v in PERTURBED_X.items() if not k.startswith("L")}],
                         ids=["jtire_file", "every_term_on"])
def test_longitudinal_agrees_with_jtire_magic_formula(script_x, tir_path, tmp_path, values):
    """F_x0 and K_xk of the script = jtire's mf_longitudinal on jtire's reader, 1e-9 (nominal pressure)."""
    from jtire.rigid_ring import mf_longitudinal as mfx

    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), values))
    t = jtir.read(path)
    c_ref = t["LONGITUDINAL_COEFFICIENTS"]
    nom = mf.Nominal(t["VERTICAL"]["FNOMIN"], t["OPERATING_CONDITIONS"]["NOMPRES"], t["DIMENSION"]["UNLOADED_RADIUS"])
    c = script_x.coefficients(path, script_x.parse_tir(path))
    fz, kappa = np.meshgrid(np.array([0.4, 0.5, 1.0, 1.5, 1.8]) * nom.fnomin, [-0.3, -0.05, 0.0, 0.01, 0.08, 0.15, 0.3])
    ref = mfx.fx0(c_ref, nom, fz, kappa)
    np.testing.assert_allclose(script_x.longitudinal(c, fz, kappa)["fx"], ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
    np.testing.assert_allclose(script_x.longitudinal(c, fz[0], 0.0)["kxk"], mfx.slip_stiffness(c_ref, nom, fz[0]),
                               rtol=1e-12)


def test_longitudinal_scaling_factors_apply(script_x, tir_path, tmp_path):
    """LKX scales K_xk (4.E15), LMUX the peak D_x (4.E13)."""
    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), {"LKX": 1.3, "LMUX": 0.8}))
    c0 = script_x.coefficients(tir_path, script_x.parse_tir(tir_path))
    c = script_x.coefficients(path, script_x.parse_tir(path))
    p0, p = script_x.longitudinal(c0, 40e3, 0.0), script_x.longitudinal(c, 40e3, 0.0)
    assert p["kxk"] == pytest.approx(1.3 * p0["kxk"], rel=1e-12) and p["dx"] == pytest.approx(0.8 * p0["dx"], rel=1e-12)


@pytest.mark.parametrize("case", ["missing_file", "no_PKX1", "missing_curves"])
def test_longitudinal_bad_input_exits_2(tir_path, tmp_path, case):
    path, extra, named = tmp_path / f"{case}.tir", [], None
    text = tir_path.read_text()
    if case == "no_PKX1":
        path.write_text(re.sub(r"^PKX1\s*=.*\n", "", text, flags=re.MULTILINE))
        named = "PKX1"
    elif case == "missing_curves":
        path.write_text(text)
        extra, named = ["--curves", tmp_path / "none.json"], str(tmp_path / "none.json")
    png = tmp_path / "fx.png"
    r = subprocess.run([sys.executable, str(SCRIPT_X), str(path), "--out", str(png), *map(str, extra)],
                       capture_output=True, text=True, check=False, timeout=120)
    assert r.returncode == 2 and r.stdout == "" and not png.exists()
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and (named or str(path)) in lines[0], r.stderr


def test_tutorial_longitudinal_command(tmp_path):
    """The page's command, as written, on the synthetic characterization and its exported .tir: one
    comparison line per load at NOMPRES, each at round-off (the synthetic curves are MF 6.1 curves
    plus a free-rolling drag, which the fit and the script both remove), and the PNG."""
    page = PAGE.read_text()
    blocks = re.split(r"^```.*$", page, flags=re.MULTILINE)[1::2]
    assert any(COMMAND_X in b.splitlines() for b in blocks), "the page's code block with the command changed"
    (tmp_path / "examples").symlink_to(REPO / "examples")
    make_tir(tmp_path / "runs" / "characterize", tmp_path / "runs" / "characterize" / "tire.tir")
    r = subprocess.run([sys.executable, *shlex.split(COMMAND_X)[1:]], cwd=tmp_path, capture_output=True, text=True,
                       check=False, timeout=120)
    assert r.returncode == 0, r.stderr
    errs = [float(m.group(1)) for m in re.finditer(r"over 0-10 % slip = ([0-9.]+) % of the curve's peak", r.stdout)]
    assert len(errs) == len(synthetic.LOADS_KG) and max(errs) < 0.01, r.stdout
    assert (tmp_path / "runs" / "fx_kappa.png").stat().st_size > 30_000
