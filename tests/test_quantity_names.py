"""Each experiment declares the quantities its `reduce` writes (`Experiment.quantity_names`, and
`produces(table)` where a table option adds or removes some), and calibration targets are checked
against the declaration before anything runs (tests/test_bad_inputs_calibration.py). Here each
declaration is checked against what `reduce` actually wrote on the suite's cached coarse runs: the
same names, none missing, none extra. E11 is checked where it is computed from real E09 and E10 runs
(tests/test_cornering.py); the experiments without a run in the fast suite are checked in their slow
tests (named below)."""

import pytest

from jtire.config import validate_table
from jtire.experiments import REGISTRY

from .conftest import SIDEWALL, ok

# every cached run of the fast suite, by its fixture (each experiment with every table option that
# changes its quantities: E01/E02 static and transient, E09 with and without its release decay, E10 and E12
# transient and steady; E06 steady, its transient in the slow suite)
RUN_FIXTURES = ("e01_grid", "e01_static", "e02", "e02_static", "e04", "e09", "e09_static", "e10", "e12",
                "e10_steady", "e12_steady", "e06_steady")
# E03 (its own drum program, ~80 s cold) is checked in the physics gate, with the drum-cleat tests
GATE_RUN_FIXTURES = {"e03": "drum_cleat"}
# checked outside this file, and why
ELSEWHERE = {"relaxation_length": "a composite of E10 and E09: tests/test_cornering.py",
             "slip_step": "the rigid-ring validation's shell run: tests/test_validate.py"}


def declared(run) -> set:
    cls = REGISTRY[run.exp.name]
    return set(cls.produces(validate_table(run.table, cls.schema, cls.name)))


def check_run(run):
    want = declared(run)
    for r in run.results:
        got = set(ok(r).quantities)
        assert got == want, f"{run.exp.name}: not declared {sorted(got - want)}, declared but missing {sorted(want - got)}"


@pytest.mark.parametrize("fixture", [*RUN_FIXTURES, *(pytest.param(f, marks=[pytest.mark.slow, pytest.mark.gate])
                                                       for f in GATE_RUN_FIXTURES)])
def test_declared_quantities_are_what_reduce_wrote(fixture, request):
    check_run(request.getfixturevalue(fixture))


@pytest.mark.parametrize("name", SIDEWALL)
def test_declared_quantities_of_the_rigid_belt_experiments(name, sidewall_runs):
    for run in sidewall_runs[name].values():
        check_run(run)


# gate, with tests/test_sidewall.py's fore-aft spring: E13's two pushes (~22 s here)
@pytest.mark.slow
@pytest.mark.gate
def test_declared_quantities_of_e13(e13_runs):
    for run in e13_runs.values():
        check_run(run)


def test_declared_quantities_of_e14(e14):
    for run in e14.values():
        check_run(run)


def test_every_experiment_is_checked_somewhere(request):
    names = ({request.getfixturevalue(f).exp.name for f in RUN_FIXTURES} | set(SIDEWALL) | set(ELSEWHERE)
             | {"sidewall_longitudinal", "longitudinal_stiffness"} | set(GATE_RUN_FIXTURES.values()))
    assert names == set(REGISTRY)
    for cls in REGISTRY.values():  # the traced quantities are among those reduce writes
        assert set(cls.traced_names) <= set(cls.quantity_names), cls.name
