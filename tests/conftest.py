"""Shared fixtures. Tests run on the CPU in float64 (importing jtire enables it).

Compile cost shapes this file. Every distinct phase program (phase structure x batch shape x device
count) costs 40-140 s to compile on the coarse mesh on this 2-core machine, so the suite compiles as
few as it can and runs every simulation through the `runs` factory, which caches results for the
whole session (test files share them). The fast suite uses:
    one tire (`coarse_tire`: 32 segments, 4 crown elements) and ONE solver protocol (`protocol`);
    flat-road program, 1 case on 1 device   ("singles": E01, E02, E04, E09, E12, custom plans, CLI runs);
    the same on the second device           (grids case by case, side by side: `jtire sweep`'s default);
    flat-road program, 4 cases on 2 devices ("grids": the E01 grid, the E10 sweep);
    rigid-belt program, 1 case on 1 device  (E05, E07, E08).
The physics gate (`pytest -m gate`, beside the fast suite in CI) adds programs only its checks need: the
flat-road program for 4 cases on 1 device (the unsharded E01 grid: sharded = unsharded), the drum
program (E03, once), E13's pushes. Anything else (the default mesh, other drum runs) is under
@pytest.mark.slow.

Persistent compilation cache: ON, in the default folder (`jtire.cache`: $JTIRE_CACHE_DIR if set, else
the user's cache folder; JTIRE_CACHE_DIR=off turns it off). The command-line tests and the
subprocesses (`jtire sweep` killed and resumed, the wheel install) enable it anyway (the CLI's
default), so sharing it lets them load the programs this process compiled instead of compiling them
again; a cold run (CI) writes it, a rerun only traces. Set JTIRE_CACHE_DIR to a fresh folder to time a
cold suite.
"""

import dataclasses
import json
import os
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

import jtire  # noqa: E402,F401  (float64, one CPU device per core)
import pytest  # noqa: E402

from jtire import cache  # noqa: E402
from jtire import units as U  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
TIRE_TOML = REPO / "configs" / "tires" / "xone_xda.toml"

cache.enable()

# The coarse tire and the one protocol as command-line overrides (for CLI and subprocess tests), so
# that they run the very programs the in-process tests compiled.
COARSE_SET = ["tire.mesh.n_theta=32", "tire.mesh.n_crown=4"]
PROTOCOL = dict(settle_damping=300.0, ke_tol=1e-3, inflate_ramp=0.04, inflate_max=0.4, load_ramp=0.05, settle_max=0.3)
SOLVER_SET = ["solver.settle_damping_per_s=300.0", "solver.ke_tol_J=0.001", "solver.inflate_ramp_s=0.04",
              "solver.inflate_max_s=0.4", "solver.load_ramp_s=0.05", "solver.settle_max_s=0.3"]

# The standard conditions: rated, and the E01 grid (light, rated, high and low pressure).
P_RATED, LOAD_RATED = 120 * U.PSI, 4625 * U.G0
RATED = {"pressure_Pa": P_RATED, "load_N": LOAD_RATED}
GRID = [{"pressure_Pa": P_RATED, "load_N": 2312.5 * U.G0}, RATED,
        {"pressure_Pa": 150 * U.PSI, "load_N": LOAD_RATED}, {"pressure_Pa": 70 * U.PSI, "load_N": LOAD_RATED}]


@pytest.fixture(autouse=True)
def _room_for_programs():
    """Before every test: drop JAX's in-memory programs if this process's memory maps near the
    kernel's cap (`jtire.cache.release_programs_if_crowded`; the library does it between runs too).
    A test that checks trace counts sees the clears it spans in `cache.clears()`."""
    cache.release_programs_if_crowded()
    yield


@pytest.fixture(scope="session")
def spec():
    from jtire.config import load_tire

    return load_tire(TIRE_TOML)


@pytest.fixture(scope="session")
def coarse_tire(spec):
    """The default tire on a coarse ring (32 segments, 4 crown elements): the same physics at a
    quarter of the cost, for invariant and trend tests (not for the reported numbers)."""
    from jtire.tire import make_tire

    return make_tire(dataclasses.replace(spec, n_theta=32, n_crown=4))


@pytest.fixture(scope="session")
def protocol():
    """The one solver protocol of the suite. A 50 ms load ramp and a 0.3 s settle limit: the coarse
    ring's belt modes are > 25 Hz and near-critically damped while settling (300 1/s), so a 50 ms ramp
    is still quasi-static; every settled phase is also checked for force balance by the runs."""
    from jtire.experiments.phases import Protocol

    return Protocol.from_dict(PROTOCOL)


def make_experiment(name, protocol, spec, **table):
    """An experiment built from its config table (file units), validated like a config file."""
    from jtire.config import validate_table
    from jtire.experiments import REGISTRY

    cls = REGISTRY[name]
    return cls.from_table(validate_table(table, cls.schema, name), protocol, spec)


@dataclasses.dataclass
class Run:
    """One cached batch run: the experiment, its results (ExperimentResult with .outputs, or
    CaseFailure), the phase-program traces it added (and how many there were before it), the
    devices it ran on and its place in the session's runs."""

    exp: object
    results: list
    traces_added: int
    traces_before: int
    devices: int  # devices the batch ran on
    order: int  # runs made before this one in the session
    table: dict = dataclasses.field(default_factory=dict)  # the experiment's table (file units)
    clears: tuple = (0, 0)  # cache.clears() before and after the run (a clear makes the next run trace again)


class Runs:
    """runs(name, conditions, devices=1, tire=None, **table) -> Run, cached for the session."""

    def __init__(self, spec, tire, protocol):
        self.spec, self.tire, self.protocol = spec, tire, protocol
        self.cache = {}

    def __call__(self, name, conditions, devices=1, tire=None, **table):
        from jtire import batch

        tire = self.tire if tire is None else tire
        key = (name, json.dumps(table, sort_keys=True), json.dumps(conditions, sort_keys=True), devices, id(tire))
        if key not in self.cache:
            exp = make_experiment(name, self.protocol, self.spec, **table)
            before, c0 = batch.program_traces(), cache.clears()
            res = batch.run(exp, tire, [dict(c) for c in conditions], devices=devices, keep_outputs=True)
            n_cases = sum(len(exp.cases(c)) for c in conditions)
            self.cache[key] = Run(exp, res, batch.program_traces() - before, before,
                                  batch.n_devices_for(n_cases, devices), len(self.cache), dict(table),
                                  (c0, cache.clears()))
        return self.cache[key]


@pytest.fixture(scope="session")
def runs(spec, coarse_tire, protocol):
    return Runs(spec, coarse_tire, protocol)


def contact_patch(tire, run):
    """(x (m), k_t (N/m)) of the tread points in contact at the end of a static run (E01's state), for
    the brush-model bounds of the tests: positions along the road and tread shear stiffnesses."""
    import numpy as np

    out = ok(run.results[0]).outputs[0]
    m, y = tire.model, out["y"]
    P = m.tread_points(m.assemble(y.x, y.q))
    inside = np.asarray(P.z) < float(out["z_road"])
    _, k_t, _ = m.contact_stiffness(tire.params)
    return np.asarray(P.x)[inside], np.asarray(k_t)[inside]


def ok(result):
    """The ExperimentResult, or fail the test with the simulation's own message."""
    from jtire.batch import CaseFailure

    if isinstance(result, CaseFailure):
        pytest.fail(f"{result.condition}: {result.error}")
    return result


# ---- the shared runs (each simulated once per session) ---------------------------------------------
@pytest.fixture(scope="session")
def e01_grid(runs):
    """E01 (transient method: the shared phase program) over GRID, 4 cases on 2 devices. Requested
    before every other flat-road run of the suite (the fixtures below depend on it), so its trace
    count is that of a fresh process."""
    return runs("footprint", GRID, devices=2, method="transient")


@pytest.fixture(scope="session")
def e01_grid_unsharded(runs, e01_grid):
    return runs("footprint", GRID, devices=1, method="transient")


@pytest.fixture(scope="session")
def e01_singles(runs, e01_grid):
    return [runs("footprint", [c], method="transient") for c in GRID]


# 0.15 s: 2 % quasi-static on the coarse ring (its modes are faster than the default's)
E02_TABLE = dict(ramp_s=0.15, method="transient")


@pytest.fixture(scope="session")
def e02(runs, e01_grid):
    return runs("vertical_stiffness", [RATED], **E02_TABLE)


# The static method (the default of E01 and E02): one compiled static program (13 load levels),
# shared by both. The command-line tests run the same program at the same conditions.
@pytest.fixture(scope="session")
def e01_static(runs):
    return runs("footprint", [RATED])


@pytest.fixture(scope="session")
def e02_static(runs, e01_static):
    return runs("vertical_stiffness", [RATED])


@pytest.fixture(scope="session")
def e09_static(runs, e01_static):
    """E09's static part as a static equilibrium (decay_s = 0: method "auto" is static), on the
    program of E01 and E02."""
    return runs("lateral_stiffness", [RATED], decay_s=0.0)


@pytest.fixture(scope="session")
def e09(runs, e01_grid):
    """E09 as a transient throughout (inflate, load, lateral force settled by dynamic relaxation), with
    its release decay (0.15 s: ~5 periods of the ~30 Hz lateral mode)."""
    return runs("lateral_stiffness", [RATED], decay_s=0.15, method="transient")


@pytest.fixture(scope="session")
def e09_release(runs, e09_static):
    """E09 as a user runs it with a decay (the default method): the static path, then the release
    transient from the held static state."""
    return runs("lateral_stiffness", [RATED], decay_s=0.15)


@pytest.fixture(scope="session")
def e04(runs, e01_static):
    """E04 as a user runs it (the default method): inflation and rest as static equilibria (E01's
    static program), the drop a transient from the inflated static state."""
    return runs("drop_test", [RATED], duration_s=0.25)


@pytest.fixture(scope="session")
def e04_transient(runs, e01_grid):
    """E04 with every phase explicit: inflation and the rest after the drop by dynamic relaxation."""
    return runs("drop_test", [RATED], duration_s=0.25, method="transient")


E12_LOAD = 41.4e3  # N: the second calibration load (target 1701.11 N)


@pytest.fixture(scope="session")
def e12(runs, e01_grid):
    """E12 as a transient with its default stages at the calibration load 41.4 kN (coarse ring)."""
    return runs("rolling_resistance", [{"pressure_Pa": P_RATED, "load_N": E12_LOAD}], method="transient")


@pytest.fixture(scope="session")
def e12_steady(runs):
    """E12 as a steady-rolling equilibrium (the default method) at 41.4 kN (coarse ring)."""
    return runs("rolling_resistance", [{"pressure_Pa": P_RATED, "load_N": E12_LOAD}])


# E10 on 4 slip angles (4 cases: the grid program): +-2 deg for antisymmetry, 0, 1, 2 for k_f, k_m.
E10_TABLE = dict(slip_angles_deg=[-2.0, 0.0, 1.0, 2.0], kf_range_deg=[0.0, 2.0], km_range_deg=[0.0, 2.0],
                 settle_s=0.1, ramp_s=0.03, release_s=0.01, measure_s=0.02)


@pytest.fixture(scope="session")
def e10(runs, e01_grid):
    return runs("cornering", [RATED], devices=2, method="transient", **E10_TABLE)


# The steady E10 (the default method) on the same angles and more: -4 .. 4 deg, one continuation.
E10_STEADY_TABLE = dict(slip_angles_deg=[-4.0, -2.0, -1.0, 0.0, 1.0, 2.0, 4.0], kf_range_deg=[0.0, 2.0],
                        km_range_deg=[0.0, 2.0])


@pytest.fixture(scope="session")
def e10_steady(runs, e12_steady):
    return runs("cornering", [RATED], **E10_STEADY_TABLE)


# The steady E06 on a flat road, slips 0-6 % (1 % apart), k_k fitted over 0-5 %.
E06_STEADY_TABLE = dict(surface="flat", slip_max_percent=6.0, slip_levels=6, fit_range_percent=[0.0, 5.0])


@pytest.fixture(scope="session")
def e06_steady(runs, e12_steady):
    return runs("traction", [RATED], **E06_STEADY_TABLE)


# E03 on a near-flat drum (20 m) at 30 km/h, 0.2 s of record: the linear vertical belt mode of the tire
# on the flat road (tests/test_drum_cleat.py) is the mode it excites. Its own program (drum surfaces):
# ~35 s to compile here, 7 s to run.
E03_TABLE = dict(drum_diameter_m=20.0, speed_kmh=30.0, roll_settle_s=0.05, record_s=0.2)


@pytest.fixture(scope="session")
def e03(runs):
    """E03 as a user runs it: inflated and loaded onto the still drum in static levels, then rolled."""
    return runs("drum_cleat", [RATED], **E03_TABLE)


@pytest.fixture(scope="session")
def e03_transient(runs):
    """E03 with the inflation and the loading by dynamic relaxation (method "transient")."""
    return runs("drum_cleat", [RATED], method="transient", **E03_TABLE)


SIDEWALL = ("inplane_rotation", "sidewall_translation", "sidewall_camber")
SIDEWALL_DECAY = {"decay_s": 0.1}  # ~3 periods of the 25-37 Hz belt modes: two peaks and the fit
P_LOW = 80 * U.PSI


@pytest.fixture(scope="session")
def e14(runs):
    """E14 at the rated condition, pushed forward and backward."""
    return {d: runs("longitudinal_stiffness", [RATED], direction=d) for d in ("forward", "backward")}


@pytest.fixture(scope="session")
def sidewall_runs(runs):
    """{name: {pressure: Run}} at 120 and 80 psi (E05, E07, E08: per pressure, no load), the default
    method: inflation and hold as static equilibria, the release a transient from the held state."""
    return {n: {p: runs(n, [{"pressure_Pa": p}], **SIDEWALL_DECAY) for p in (P_RATED, P_LOW)} for n in SIDEWALL}


@pytest.fixture(scope="session")
def sidewall_transient(runs):
    """E07 at 120 psi with the inflation and the hold by dynamic relaxation (method "transient")."""
    return runs("sidewall_translation", [{"pressure_Pa": P_RATED}], method="transient", **SIDEWALL_DECAY)


@pytest.fixture(scope="session")
def e13_runs(runs):
    """E13 at 120 psi pushed fore-aft (x, the default) and vertically (z): the rigid-belt program."""
    return {d: runs("sidewall_longitudinal", [{"pressure_Pa": P_RATED}], direction=d, **SIDEWALL_DECAY)
            for d in ("x", "z")}


@pytest.fixture(scope="session")
def undamped_tire(coarse_tire):
    """The coarse tire with every rubber loss zero (same leaves and dtypes: the same programs)."""
    return dataclasses.replace(coarse_tire, params=coarse_tire.params.without_damping())


@pytest.fixture
def user_dir(tmp_path, monkeypatch):
    """A fresh working folder with configs/ linked from the repository (a user's checkout): the README's and
    docs' commands run here."""
    (tmp_path / "configs").symlink_to(REPO / "configs", target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.fixture(scope="module")
def char():
    """The synthetic characterization (study magnitudes, jtire.rigid_ring.synthetic): no simulation.
    Several rigid-ring test modules define their own."""
    from jtire.rigid_ring import synthetic

    return synthetic.characterization()


@pytest.fixture(scope="module")
def rated(char):
    """The rated row of `char`."""
    return char.rated_row()
