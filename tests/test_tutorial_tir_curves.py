"""The example Magic Formula scripts (examples/mf61_lateral.py, examples/mf61_longitudinal.py, written
without jtire) against a characterization's own curves (`--curves`) and at other pressures than
NOMPRES (the pressure terms, `--all-pressures`); the read-back the gate and the one-condition
characterize test apply to a real characterization (`read_back_errors`). The file evaluators
themselves, at NOMPRES, and the tutorial's other commands: tests/test_tutorial_tir.py.

Fast: the .tir and curves come from the synthetic characterization, whose E10 and E06 curves are MF
6.1 curves with pressure terms (jtire.rigid_ring.synthetic), so a file fitted at every pressure
reproduces them to round-off.
"""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from jtire.cli import main
from jtire.rigid_ring import magic_formula as mf
from jtire.rigid_ring import synthetic
from jtire.rigid_ring import tir as jtir
from jtire.rigid_ring.table import write_characterization

from .conftest import REPO
from .test_tutorial_tir import (PAGE, SCRIPT, SCRIPT_X, jtire_reference, load_script, make_tir,
                                with_values)


@pytest.fixture(scope="module")
def tir_path(tmp_path_factory):
    d = tmp_path_factory.mktemp("tir")
    make_tir(d / "characterize", d / "tire.tir")
    return d / "tire.tir"


@pytest.fixture(scope="module")
def script():
    return load_script(SCRIPT)


@pytest.fixture(scope="module")
def script_x():
    return load_script(SCRIPT_X)


PRESSURE_ON = {"PPY1": 0.3, "PPY2": -0.4, "PPY3": -0.2, "PPY4": 0.1, "PPZ1": 0.5}
PRESSURE_ON_X = {"PPX1": 0.25, "PPX2": -0.3, "PPX3": -0.15, "PPX4": 0.2}


def test_pressure_terms_agree_with_jtire_magic_formula(script, script_x, tir_path, tmp_path):
    """With every pressure term switched on, F_y0, M_z0, K_y and F_x0, K_xk of the scripts at 0.6, 1
    and 1.25 NOMPRES = jtire's magic_formula and mf_longitudinal at the same pressures, 1e-9; and
    the terms act (the curves move by more than 1 % off NOMPRES)."""
    from jtire.rigid_ring import mf_longitudinal as mfx

    path = tmp_path / "t.tir"
    path.write_text(with_values(tir_path.read_text(), PRESSURE_ON | PRESSURE_ON_X))
    c_ref, nom = jtire_reference(path)
    c_ref_x = jtir.read(path)["LONGITUDINAL_COEFFICIENTS"]
    c, _ = script.coefficients(path, script.parse_tir(path))
    cx = script_x.coefficients(path, script_x.parse_tir(path))
    fz, alpha = np.meshgrid(np.array([0.5, 1.0, 1.5]) * nom.fnomin, np.radians([-8, -1, 0.5, 3, 12]))
    kappa = np.array([[-0.05], [0.01], [0.08], [0.2]]) + 0 * fz[:1]
    for f in (0.6, 1.0, 1.25):
        p, dpi = f * nom.nompres, f - 1.0
        for mine, ref in [(script.lateral(c, fz, alpha, dpi)["fy"], mf.fy0(c_ref, nom, fz, alpha, p)),
                          (script.aligning(c, fz, alpha, dpi), mf.mz0(c_ref, nom, fz, alpha, p)),
                          (script.lateral(c, fz[0], 0.0, dpi)["ky"], mf.cornering_stiffness(c_ref, nom, fz[0], p)),
                          (script_x.longitudinal(cx, fz[:4], kappa, dpi)["fx"], mfx.fx0(c_ref_x, nom, fz[:4], kappa, p)),
                          (script_x.longitudinal(cx, fz[0], 0.0, dpi)["kxk"], mfx.slip_stiffness(c_ref_x, nom, fz[0], p))]:
            np.testing.assert_allclose(mine, ref, rtol=1e-9, atol=1e-9 * np.max(np.abs(ref)))
    moved = script.lateral(c, fz, alpha, 0.25)["fy"] - script.lateral(c, fz, alpha)["fy"]
    moved_x = script_x.longitudinal(cx, fz[:4], kappa, 0.25)["fx"] - script_x.longitudinal(cx, fz[:4], kappa)["fx"]
    assert np.max(np.abs(moved)) > 0.01 * np.max(np.abs(script.lateral(c, fz, alpha)["fy"]))
    assert np.max(np.abs(moved_x)) > 0.01 * np.max(np.abs(script_x.longitudinal(cx, fz[:4], kappa)["fx"]))


COMMAND_CURVES = ("python examples/mf61_lateral.py runs/characterize/tire.tir --curves "
                  "runs/characterize/characterization.json --out runs/fy_curves.png")
CURVE_LINE = re.compile(r"over 0-8 deg = ([0-9.]+) % of the curve's peak, \|M_z0 - M_z\| = ([0-9.]+) %")


def test_tutorial_lateral_curves_command(tmp_path):
    """The page's --curves command, as written, on the synthetic characterization and its exported
    .tir: one comparison line per load at NOMPRES, each at round-off (the synthetic E10 curves are MF
    6.1 curves the fit recovers), and the PNG."""
    page = PAGE.read_text()
    blocks = re.split(r"^```.*$", page, flags=re.MULTILINE)[1::2]
    assert any(COMMAND_CURVES in b.splitlines() for b in blocks), "the page's code block with the command changed"
    (tmp_path / "examples").symlink_to(REPO / "examples")
    make_tir(tmp_path / "runs" / "characterize", tmp_path / "runs" / "characterize" / "tire.tir")
    r = subprocess.run([sys.executable, *shlex.split(COMMAND_CURVES)[1:]], cwd=tmp_path, capture_output=True,
                       text=True, check=False, timeout=120)
    assert r.returncode == 0, r.stderr
    errs = [tuple(map(float, m.groups())) for m in CURVE_LINE.finditer(r.stdout)]
    assert len(errs) == len(synthetic.LOADS_KG) and max(max(e) for e in errs) < 0.01, r.stdout
    assert (tmp_path / "runs" / "fy_curves.png").stat().st_size > 40_000


def test_lateral_curves_are_compared_in_iso_signs(script, tir_path):
    """The comparison can fail: the same curves with the SAE-to-ISO turn left out (F_y and M_z flipped
    as a reader that forgot the axes would see them) miss by about twice the peak, and a curve of
    another tire (F_y scaled by 0.9) by 10 % of the peak over 0-8 deg at most."""
    tir = script.parse_tir(tir_path)
    c, _ = script.coefficients(tir_path, tir)
    nompres = tir["OPERATING_CONDITIONS"]["NOMPRES"][1]
    sims = script.simulated_curves(tir_path.parent / "characterize" / "characterization.json", nompres)
    assert len(sims) == len(synthetic.LOADS_KG)

    def worst(curves, sign=1.0, scale=1.0):
        out = []
        for fz, _, a, fy, mz in curves:
            w = np.abs(a) <= np.radians(8.0)
            out.append(np.max(np.abs(script.lateral(c, fz, a[w])["fy"] - sign * scale * fy[w])) / np.max(np.abs(fy)))
        return max(out)

    assert worst(sims) < 1e-4
    assert worst(sims, sign=-1.0) > 1.0
    assert 0.02 < worst(sims, scale=0.9) <= 0.1 + 1e-9


def test_all_pressures_round_trip(tmp_path):
    """`jtire export-tir --all-pressures` on the synthetic characterization (its curves carry MF
    pressure terms), read back by both scripts with --curves --all-pressures: one line per condition
    (3 loads x 3 pressures), each at round-off. Without the pressure terms in the file (the default
    export, nominal pressure only) the off-nominal rows miss by more than 1 %: the terms are what
    carry the curves across pressures."""
    folder = tmp_path / "characterize"
    write_characterization(folder, synthetic.characterization())
    n = len(synthetic.LOADS_KG) * len(synthetic.PRESSURES_PSI)
    for extra, lo, hi in ((["--all-pressures"], 0.0, 0.01), ([], 1.0, 1e9)):
        tir_file = folder / "tire.tir"
        assert main(["export-tir", str(folder), "--out", str(tir_file), *extra]) == 0
        errs = {}
        for what, path, pattern in (("F_y", SCRIPT, r"kPa: max \|F_y0 - F_y\| over 0-8 deg = ([0-9.]+) %"),
                                    ("F_x", SCRIPT_X, r"kPa: max \|F_x0 - F_x\| over 0-10 % slip = ([0-9.]+) %")):
            r = subprocess.run([sys.executable, str(path), str(tir_file), "--curves", str(folder / "characterization.json"),
                                "--all-pressures", "--out", str(tmp_path / f"{what}.png")],
                               capture_output=True, text=True, check=False, timeout=120)
            assert r.returncode == 0, r.stderr
            errs[what] = [float(m.group(1)) for m in re.finditer(pattern, r.stdout)]
            assert len(errs[what]) == n, r.stdout
        if extra:
            assert max(errs["F_y"] + errs["F_x"]) < hi, errs
        else:
            assert lo < max(errs["F_y"]) and lo < max(errs["F_x"]), errs


def read_back_errors(folder):
    """A characterization's tire.tir read back by the two example evaluators (written without jtire)
    against its own curves at NOMPRES: {"F_y": [% of peak per load over 0-8 deg], "F_x": [... over
    0-10 % slip], "M_y": [|drag from M_y / R_l against E12's drag| in % per load]} and the two printouts."""
    folder = Path(folder)
    out, text = {}, []
    for what, script, pattern in (("F_y", SCRIPT, r"over 0-8 deg = ([0-9.]+) %"),
                                  ("F_x", SCRIPT_X, r"over 0-10 % slip = ([0-9.]+) %")):
        r = subprocess.run([sys.executable, str(script), str(folder / "tire.tir"), "--curves",
                            str(folder / "characterization.json"), "--out", str(folder / f"read_back_{what}.png")],
                           capture_output=True, text=True, check=False, timeout=120)
        assert r.returncode == 0, r.stderr
        out[what] = [float(m.group(1)) for m in re.finditer(pattern, r.stdout)]
        if what == "F_x":
            out["M_y"] = [abs(float(m.group(1))) for m in re.finditer(r"E12's drag \S+ N \(([-+0-9.]+) %\)", r.stdout)]
        text.append(r.stdout)
    return out, "\n".join(text)


@pytest.mark.parametrize("which", ["lateral", "longitudinal"])
@pytest.mark.parametrize("case", ["missing", "row_without_load", "curve_without_data", "all_pressures_alone"])
def test_bad_curves_exit_2(tir_path, tmp_path, which, case):
    """A --curves file that is missing, a row without its load, a curve without its data, and
    --all-pressures without --curves: exit 2, nothing on stdout, no PNG, the file (or option) named."""
    import json

    script = SCRIPT if which == "lateral" else SCRIPT_X
    key = "E10_curves" if which == "lateral" else "E06_curves"
    png, curves = tmp_path / "out.png", tmp_path / "c.json"
    char = json.loads((tir_path.parent / "characterize" / "characterization.json").read_text())
    if case == "row_without_load":
        for r in char["rows"]:
            del r["load_N"]
    elif case == "curve_without_data":
        for r in char["rows"]:
            r[key] = {"F_z_N": [1.0]}
    if case != "missing":
        curves.write_text(json.dumps(char))
    extra = ["--all-pressures"] if case == "all_pressures_alone" else ["--curves", str(curves)]
    r = subprocess.run([sys.executable, str(script), str(tir_path), *extra, "--out", str(png)],
                       capture_output=True, text=True, check=False, timeout=120)
    assert r.returncode == 2 and r.stdout == "" and not png.exists(), r.stderr
    named = "--all-pressures" if case == "all_pressures_alone" else str(curves)
    assert named in r.stderr.strip().splitlines()[-1], r.stderr
