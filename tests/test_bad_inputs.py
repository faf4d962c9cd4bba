"""Every bad input to every subcommand is one clear line, exit code 2, before any simulation.

Table-driven (issue 13): the tables are tests/test_bad_inputs_simulation.py and
tests/test_bad_inputs_calibration.py, the harness tests/bad_input_harness.py. Each case builds its inputs in a temp folder, runs `jtire.cli.main` in
process and checks: exit code 2; exactly one line on stderr, `jtire <command>: error: ...` (or
`jtire: error:` for the top-level parser), holding the words that name the field or file; no
traceback; and that it was found BEFORE any simulation -- the simulation entry points (the batch
runner, the tire builder, the optimizers, the sampler, the characterization fit) are replaced by
a trap that fails the case if reached, and each case must finish within CASE_SECONDS.

Cases that need a simulation to detect (a settle damping so low that the load is not carried, a
geometry the mesh builds but that does not settle) are not here: they are SimulationErrors of the
experiments' own tests. Subcommands not registered in `jtire.cli.SUBCOMMANDS` are skipped with
their reason.
"""

import os
import subprocess
import sys

import pytest

from jtire.cli import SUBCOMMANDS

from .bad_input_harness import _data_dir, _exp_bytes_tire, _out, _w
from .test_bad_inputs_calibration import CASES as CALIBRATION_CASES
from .test_bad_inputs_simulation import CASES as SIMULATION_CASES

CASES = SIMULATION_CASES + CALIBRATION_CASES


def test_the_table_is_large_and_covers_every_subcommand():
    assert len(CASES) >= 60
    assert len({c.name for c in CASES}) == len(CASES), "two cases share a name"
    names = {"-".join(c.name.split("-")[:2]) if c.name.startswith(("export-", "new-")) else c.name.split("-")[0]
             for c in CASES}
    for sub in SUBCOMMANDS:
        assert sub in names, f"no bad-input case for `jtire {sub}`"


ENCODING_CASES = [  # the real entry point, in a fresh interpreter (as a user meets them)
    ("run", lambda t: ["run", _w(t, "bad.toml", b"\xff\xfe")]),
    ("compete", lambda t: ["compete", _w(t, "bad.toml", b"\xff\xfe")]),
    ("data", lambda t: ["data", "--data-dir", _data_dir(t, sandbox=b"config\n\xff\n"), *_out(t)]),
    ("sweep", lambda t: ["sweep", _exp_bytes_tire(t), *_out(t)]),
]


@pytest.mark.parametrize("command,argv", ENCODING_CASES, ids=[c[0] for c in ENCODING_CASES])
def test_non_utf8_input_from_the_shell_is_one_line(command, argv, tmp_path):
    env = dict(os.environ, LC_ALL="C", PYTHONIOENCODING="ascii")  # no help from a UTF-8 locale
    r = subprocess.run([sys.executable, "-c", "import sys; from jtire.cli import main; sys.exit(main())",
                        *argv(tmp_path)], capture_output=True, text=True, env=env, timeout=120)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2, r.stderr
    assert len(lines) == 1 and lines[0].startswith(f"jtire {command}: error: ") and "not UTF-8" in lines[0], r.stderr

