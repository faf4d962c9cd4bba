"""The package as a user gets it: build the wheel, install it into a fresh virtual environment, and
run `jtire` from a folder that is not the repository (the configs must come from the package data).

Slow: building and installing (dependencies from the pip cache or index) take minutes.
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import COARSE_SET, REPO, SOLVER_SET



def test_every_package_is_in_the_wheel():
    """Fast: every Python package folder of the source tree is listed in pyproject's `packages` (the
    list is explicit; jtire.equilibrium was once missing and a wheel install failed on import)."""
    import tomllib

    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    mapped = {"surrogates": "jtire.surrogates", "calibration": "jtire.calibration"}
    found = set()
    for init in [*REPO.glob("jtire/**/__init__.py"), *REPO.glob("surrogates/**/__init__.py"),
                 *REPO.glob("calibration/**/__init__.py")]:
        parts = init.parent.relative_to(REPO).parts
        found.add(".".join([mapped.get(parts[0], parts[0]), *parts[1:]]))
    assert found <= listed, sorted(found - listed)


def _run(args, **kw):
    p = subprocess.run([str(a) for a in args], capture_output=True, text=True, **kw)
    assert p.returncode == 0, f"{args}: {p.stdout[-2000:]}\n{p.stderr[-4000:]}"
    return p


@pytest.mark.slow
@pytest.mark.gate
def test_wheel_installs_and_runs(tmp_path):
    wheels = tmp_path / "wheels"
    _run([sys.executable, "-m", "pip", "wheel", REPO, "--no-deps", "-q", "-w", wheels], timeout=600)
    (wheel,) = wheels.glob("jtire-*.whl")
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", venv], timeout=300)
    bin_ = venv / "bin"
    _run([bin_ / "python", "-m", "pip", "install", "-q", wheel], timeout=1800)
    jtire = bin_ / "jtire"
    work = tmp_path / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("VIRTUAL_ENV", "PYTHONPATH")}
    env |= {"PATH": f"{bin_}{os.pathsep}{env.get('PATH', '')}", "MPLBACKEND": "Agg"}
    # the installed package, not the checkout
    where = _run([bin_ / "python", "-c", "import jtire, sys; print(jtire.__file__)"], cwd=work, env=env).stdout
    assert Path(where.strip()).is_relative_to(venv)
    assert "--set KEY=VALUE" in _run([jtire, "run", "--help"], cwd=work, env=env).stdout
    # the same sources give the same code version installed as a wheel as in place (run folders made by
    # one are resumed by the other; a build with any source apart is refused)
    from jtire.fingerprint import code_version

    cmd = "from jtire.fingerprint import code_version; print(code_version())"
    assert _run([bin_ / "python", "-c", cmd], cwd=work, env=env).stdout.strip() == code_version()
    # one short run: the shipped default config (E01, E02, E09 at rated) on the coarse ring
    sets = [a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)]
    p = _run([jtire, "run", *sets, "--out", "out"], cwd=work, env=env, timeout=1800)
    assert "footprint: pressure 827.4 kPa" in p.stdout
    for name in ("footprint", "vertical_stiffness", "lateral_stiffness"):
        d = json.loads((work / "out" / name / "result.json").read_text())
        # E01, E02 and E09 (static part): static equilibria (converged)
        assert d["checks"].get("static_converged", d["checks"].get("load_settled")), name
    assert (work / "out" / "summary.csv").is_file()
