"""Wrong numbers that only a simulation can reveal (issue 13): they must end as one error line, exit 2,
with no result written -- never a plain exit 0 with the number. (Bad inputs found before any
simulation are tests/test_bad_inputs.py's table.)"""

from jtire.cli import main

from .conftest import COARSE_SET, REPO, SOLVER_SET

def test_a_run_that_does_not_settle_is_an_error_not_a_number(tmp_path, capsys, e01_grid):
    """Issue 13's `--set solver.settle_damping_per_s=1` (within its range [1, 1e4]): on main it reported a
    'settled' load phase carrying 40.8 kN of 45.4 kN. E01's default method is now a static solve, which
    has no settle damping; the transient method with that damping must fail in one line naming the phase,
    time and kinetic energy (or, had the kinetic-energy event fired at a turning point, the force
    balance: `experiments.program.require_equilibrium`), exit 2, and write no result. Coarse ring and
    the suite's protocol (the program `e01_grid` compiled: the damping is an input, not a constant)."""
    over = [a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)]
    code = main(["run", str(REPO / "configs" / "experiments" / "footprint.toml"), *over,
                 "--set", "solver.settle_damping_per_s=1", "--set", "footprint.method=transient",
                 "--out", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    err = lines[-1]  # after the progress line "running footprint ..."
    assert code == 2 and "Traceback" not in "".join(lines), lines
    assert [ln for ln in lines if "error" in ln] == [err] and err.startswith("jtire run: error: footprint: load:")
    assert "did not settle" in err or "not in equilibrium" in err, err
    assert not list(tmp_path.glob("out/**/result.json"))
