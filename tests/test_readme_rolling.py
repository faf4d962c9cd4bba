"""docs/rigid-ring.md's rolling-resistance commands (E12's drag into the .tir, read back by the example
evaluator), run as a user runs them on the coarse ring (tests/test_readme_commands.py holds the coverage check)."""

import json
import re
import subprocess
import sys

from .conftest import REPO
from .test_readme_commands import QUICK_SIM, jtire


def test_characterize_rolling_resistance(user_dir, capsys):
    """docs/rigid-ring.md's rolling-resistance commands on the coarse ring at two loads and 120 psi: E12's
    steady drag into QSY1 and QSY7, read back by the example evaluator (no jtire) against the drag the
    shell simulated. Two loads, two unknowns: the ln fit passes through both, so the file gives each drag
    back to the script's printed 0.01 %, which holds only if the export and the script agree on M_y and R_l."""
    small = ["--set", "grid.loads_kg=[2312.5, 4625.0]", "--set", "grid.pressures_psi=[120.0]", *QUICK_SIM]
    assert jtire("jtire characterize --out runs/char_rr --no-validate --set "
                 "'experiments=[\"vertical_stiffness\", \"rolling_resistance\"]'", *small) == 0
    out = user_dir / "runs" / "char_rr"
    rows = json.loads((out / "characterization.json").read_text())["rows"]
    drag = sorted(r["rolling_resistance_N"] for r in rows)
    assert len(drag) == 2 and 0 < drag[0] < drag[1]  # the drag rises with load
    tir = (out / "tire.tir").read_text()
    assert re.search(r"^QSY7\s+= [0-9.e+-]+\s+\$ln\|M_y\| vs ln\(F_z/FNOMIN\) over 2 loads", tir, re.M), tir
    r = subprocess.run([sys.executable, str(REPO / "examples" / "mf61_longitudinal.py"), "runs/char_rr/tire.tir",
                        "--curves", "runs/char_rr/characterization.json", "--all-pressures", "--out", "runs/fx_rr.png"],
                       capture_output=True, text=True, timeout=120, cwd=user_dir)
    assert r.returncode == 0, r.stderr
    errs = [abs(float(m.group(1))) for m in re.finditer(r"E12's drag \S+ N \(([-+0-9.]+) %\)", r.stdout)]
    assert len(errs) == 2 and max(errs) <= 0.01, r.stdout
    assert (user_dir / "runs" / "fx_rr.png").stat().st_size > 10_000
