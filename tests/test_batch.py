"""The batch runner and the shared phase program (issue 8): one trace per phase structure, a batch
equals its single runs, sharding changes nothing, and every traced reduction (what calibration and
sensitivities differentiate) equals the host reduction of result.json.

All on the session's shared runs (conftest): nothing here compiles a program of its own.
"""

import jax
import numpy as np
import pytest

from jtire import batch, solve
from jtire.experiments.phases import Case

from .conftest import GRID, RATED, SIDEWALL, ok

# A batch vs its single runs, and 2 devices vs 1: the same per-case arithmetic, but XLA vectorizes the
# batched program differently (reductions over nodes summed in another order under vmap, fused
# differently for 1, 2 or 4 cases per device), so results agree to rounding amplified by ~6000 steps of
# a damped, settling integration -- not bit for bit. 1e-9 relative on the reduced quantities and on
# every saved output (measured: see the report of issue 8's tests; below 1e-11 on this machine).
TOL_BATCH = 1e-9
QUANTITIES = ("contact_length_m", "contact_width_m", "contact_area_m2", "deflection_m", "k_secant_N_per_m")


# Diagnostics of the fastest node at a phase's end (for the unstable-run message): at a settled end all
# speeds are ~1e-4 m/s of round-off-level differences, so which node is fastest is not reproducible
DIAGNOSTIC = ("speed_max", "where_max")


def max_rel_diff(a, b, floor):
    """Largest max|a - b| / (max|b| + floor) of every leaf of two output pytrees (normwise per leaf:
    a leaf's components that are zero by symmetry -- the rim force's x and y in E01, ~6e-8 N of
    round-off beside 4.7e4 N -- are compared at the leaf's scale; inf samples must match),
    diagnostics excluded. Returns (value, the leaf's path)."""
    worst, where = 0.0, None
    la = jax.tree_util.tree_leaves_with_path(a)
    lb = jax.tree_util.tree_leaves(b)
    for (path, x), y in zip(la, lb, strict=True):
        name = jax.tree_util.keystr(path)
        if any(d in name for d in DIAGNOSTIC):
            continue
        x, y = np.asarray(x, float), np.asarray(y, float)
        assert x.shape == y.shape
        fin = np.isfinite(y)
        assert np.array_equal(np.isfinite(x), fin), f"{name}: a phase ended at another sample"
        if fin.any():
            d = float(np.max(np.abs(x[fin] - y[fin])) / (np.max(np.abs(y[fin])) + floor))
            if d > worst:
                worst, where = d, name
    return worst, where


def assert_same_runs(results_a, results_b):
    for a, b in zip(results_a, results_b, strict=True):
        a, b = ok(a), ok(b)
        for k in QUANTITIES:
            assert a.quantities[k] == pytest.approx(b.quantities[k], rel=TOL_BATCH), (a.condition, k)
        assert a.info["phase_steps"] == b.info["phase_steps"], a.condition  # the same step counts
        # every saved signal, normwise per signal with a floor of the unit itself (1 m, 1 N, 1 N m,
        # 1 J): a signal that is zero by symmetry in E01 carries round-off only (measured: contact
        # moment 3e-10 N m, lateral contact force 4e-10 N, beside a 4.6e4 N load), so what is
        # checked there is an absolute 1e-9 of the unit; any other signal to 1e-9 of its largest value
        assert max_rel_diff(a.outputs, b.outputs, 1.0)[0] < TOL_BATCH, (a.condition, max_rel_diff(a.outputs, b.outputs, 1.0))


# ---- one trace per phase structure ------------------------------------------------------------------
# A trace is made per phase structure (flat road or rigid belt) and per device placement of the batch
# (the inputs' sharding is part of what a trace is specialized on: sharded over 2 devices, or on one).
def test_grid_traces_the_phase_program_once(e01_grid):
    # 2 phases (inflate, load) x 4 cases of one structure: at most one trace; exactly one when no phase
    # program was traced before in this process (the suite asks for this grid first)
    assert e01_grid.traces_added <= 1 + e01_grid.clears[1] - e01_grid.clears[0]
    if e01_grid.traces_before == 0:
        assert e01_grid.traces_added == 1


def test_one_trace_per_structure_and_placement(e01_grid, e01_singles, e02, e09, e04, e04_transient,
                                               e09_release, e12, e10, sidewall_runs, sidewall_transient):
    """Every experiment, table, condition and batch size of one structure and placement shares one
    trace (and one compiled program per batch shape): only the first run of each group may trace (a
    weakly typed leaf, a drive field that is batched in one experiment and not in another, would show
    here as a second trace). A transient started from a static state (E04, E09's release, the rigid
    belt's release: method "static") runs its phases on the same program, vmapped over its one case.
    E04's record (2.5 kHz) is longer than the other phases' N_SAVE samples: its own group."""
    runs = [e01_grid, *e01_singles, e02, e09, e04, e04_transient, e09_release, e12, e10,
            sidewall_transient, *[r for n in SIDEWALL for r in sidewall_runs[n].values()]]
    groups = {}
    for r in sorted(runs, key=lambda r: r.order):
        # the saved record's length is part of the program: E04 saves at drop_test.sample_rate_Hz
        # (2.5 kHz), every other phase N_SAVE samples
        key = (r.exp.name in SIDEWALL, r.devices, getattr(r.exp, "n_save", solve.N_SAVE))
        groups.setdefault(key, []).append(r)
    n_drop = e04.exp.n_save
    assert n_drop != solve.N_SAVE and e04_transient.exp.n_save == n_drop
    assert set(groups) == {(False, 2, solve.N_SAVE), (False, 1, solve.N_SAVE), (True, 1, solve.N_SAVE), (False, 1, n_drop)}
    first_sharded = min(r.order for r in groups[(False, 2, solve.N_SAVE)])
    for key, rs in groups.items():
        # Known and not fixed: the first one-device flat-road run made after a 2-device one traces the
        # phase program twice (its inflate phase, then its load phase). Under JAX 0.10's eager vmap the
        # contact height the load phase starts from (a min over the inflated tread, computed eagerly)
        # comes out with the 2-device batch's abstract mesh in its type although it lives on one
        # device: one more trace (and one more compile or cache load), once per process.
        # (which run shows it depends on the order the fixtures were first asked for: with the steady
        # tests first, E12's one-device run follows E10's 2-device grid and the second trace lands on
        # the next one-device run): the group as a whole traces once, twice after a 2-device run
        after_sharded = key[:2] == (False, 1) and any(r.order > first_sharded for r in rs)
        # a process that dropped its in-memory programs (jtire.cache: too many memory maps) traces
        # again once per group after each clear
        cleared = rs[-1].clears[1] - rs[0].clears[0]
        assert rs[0].traces_added >= 1 or rs[0].traces_before > 0, (key, rs[0].exp.name)
        assert sum(r.traces_added for r in rs) <= (2 if after_sharded else 1) + cleared, (
            key, first_sharded, str([(r.exp.name, r.order, r.traces_added, r.exp.shardable) for r in rs if r.traces_added]))


def test_program_traces_is_the_phase_program_count():
    from jtire.experiments.program import phase_traces

    assert batch.program_traces() == phase_traces()


# ---- batches, shards --------------------------------------------------------------------------------
def test_batch_equals_single_runs(e01_grid, e01_singles):
    """4 cases in one batch, 2 on each device, = the 4 cases run one by one."""
    assert_same_runs(e01_grid.results, [s.results[0] for s in e01_singles])


# gate: the 4-case batch on one device is a program (and 2 traces) no fast test needs (~100 s here)
@pytest.mark.slow
@pytest.mark.gate
def test_sharded_equals_unsharded(e01_grid, e01_grid_unsharded, e01_singles):
    """The same 4-case batch split over 2 devices = on one device = the 4 single runs."""
    assert len(jax.devices()) >= 2, "jtire asks for one CPU device per core; this machine should have 2"
    assert_same_runs(e01_grid.results, e01_grid_unsharded.results)
    assert_same_runs(e01_grid_unsharded.results, [s.results[0] for s in e01_singles])


def test_case_by_case_side_by_side_is_the_single_runs(coarse_tire, e01_singles):
    """The commands' default (batch = 1): a transient grid's cases run one per batch, side by side on
    the devices (one at a time each), and each is handed over (saved, counted) the moment it finishes.
    Each case is its single run bit for bit: the same one-case program, only placed on another device.
    (Two cases: one on each device.)"""
    assert len(jax.devices()) >= 2
    got = []
    res = batch.run(e01_singles[0].exp, coarse_tire, GRID[:2], batch=1, devices=2, keep_outputs=True,
                    on_result=lambda i, r: got.append(i))
    assert sorted(got) == [0, 1]
    for r, single in zip(res, e01_singles[:2], strict=True):
        s = ok(single.results[0])
        assert ok(r).quantities == s.quantities
        assert max_rel_diff(r.outputs, s.outputs, 1.0)[0] == 0.0


def test_results_come_back_in_condition_order(e01_grid):
    assert [ok(r).condition for r in e01_grid.results] == GRID


def test_padding_to_the_device_count():
    # 3 cases on 2 devices run as a batch of 4 (the last case repeated, its result dropped)
    assert batch.n_devices_for(3, 2) == 2 and batch.n_devices_for(1, 2) == 1 and batch.n_devices_for(5, 1) == 1


def test_simulate_batch_is_traceable(coarse_tire, e01_grid):
    """simulate_batch under jax.eval_shape: the shapes of a 3-case batch without running it."""
    exp = e01_grid.exp
    cases = jax.tree_util.tree_map(lambda *a: np.stack(a), *[Case.of(c["load_N"], c["pressure_Pa"], 2e-5)
                                                            for c in GRID[:3]])
    shapes = jax.eval_shape(lambda c: batch.simulate_batch(exp, coarse_tire.model, coarse_tire.params, c), cases)
    assert shapes["phases"].t_end.shape == (3, 2)  # cases x phases
    assert shapes["y"].q.shape == (3, 6)


# ---- traced reductions = host reductions ------------------------------------------------------------
# The traced reductions read the same outputs as the host ones:
#   E01: the patch extent by the same crossing rule on the same fine surface; the host evaluates the
#        periodic spline with scipy, the traced one as a fixed linear operator (the same spline, other
#        rounding): 1e-9 relative. The deflection is the same number.
#   E02: the secant at the stated load, interpolated between the same two ramp samples: 1e-9.
#   E09, E05/E07/E08: the same end positions: 1e-12.
#   E12: means over the same samples (numpy vs XLA summation order): 1e-9.
#   E10: least-squares slopes over the same means (numpy polyfit vs a centred formula): 1e-9.
TOL_TRACED = {"footprint": 1e-9, "vertical_stiffness": 1e-9, "lateral_stiffness": 1e-12, "rolling_resistance": 1e-9,
              "cornering": 1e-9, "inplane_rotation": 1e-12, "sidewall_translation": 1e-12, "sidewall_camber": 1e-12}
CHECKED = {"footprint": ("contact_length_m", "contact_width_m", "deflection_m"),
           "vertical_stiffness": ("k_sv_N_per_m", "deflection_m"),
           "lateral_stiffness": ("k_l_N_per_m", "lateral_deflection_m"),
           "rolling_resistance": ("rolling_resistance_N", "rolling_resistance_from_power_N", "rrc"),
           "cornering": ("k_f_N_per_rad", "k_m_Nm_per_rad"),
           "inplane_rotation": ("k_btheta_Nm_per_rad", "theta_ss_rad"),
           "sidewall_translation": ("k_by_N_per_m", "y_ss_m"),
           "sidewall_camber": ("k_bgamma_Nm_per_rad", "gamma_ss_rad")}


def _traced_vs_host(run, tire):
    exp = run.exp
    assert set(CHECKED[exp.name]) <= set(exp.traced_names)
    for res in run.results:
        res = ok(res)
        tr = exp.traced(tire.model, tire.params, exp.cases(res.condition), res.outputs)
        for k in CHECKED[exp.name]:
            assert float(tr[k]) == pytest.approx(res.quantities[k], rel=TOL_TRACED[exp.name]), (exp.name, k)


def test_traced_equals_host_footprint(e01_grid, coarse_tire):
    _traced_vs_host(e01_grid, coarse_tire)


def test_traced_equals_host_static(e01_static, e02_static, e09_static, coarse_tire):
    """E01, E02 and E09 solved as static equilibria: the traced reductions read the same levels."""
    _traced_vs_host(e01_static, coarse_tire)
    _traced_vs_host(e02_static, coarse_tire)
    _traced_vs_host(e09_static, coarse_tire)


def test_static_batch_is_its_single_runs(runs, e01_static):
    """A static experiment's batch runs its cases one by one through the unbatched solve (a vmapped
    Newton loop runs both branches of its conditionals): the rated case of a 2-case batch is the
    single run bit for bit, and the lighter case deflects less."""
    light, rated = (ok(r) for r in runs("footprint", [GRID[0], RATED]).results)
    single = ok(e01_static.results[0])
    assert rated.quantities == single.quantities
    assert max_rel_diff(rated.outputs, single.outputs, 1.0)[0] == 0.0
    assert light.quantities["deflection_m"] < rated.quantities["deflection_m"]


def test_traced_equals_host_vertical_and_lateral(e02, e09, coarse_tire):
    _traced_vs_host(e02, coarse_tire)
    _traced_vs_host(e09, coarse_tire)


def test_traced_equals_host_rolling_and_cornering(e12, e10, coarse_tire):
    _traced_vs_host(e12, coarse_tire)
    _traced_vs_host(e10, coarse_tire)


def test_traced_equals_host_steady(e12_steady, e10_steady, coarse_tire):
    """The steady E12 and E10: the traced reductions read the same equilibrium levels (E12: the same
    numbers; E10: slopes by another formula, 1e-9)."""
    _traced_vs_host(e12_steady, coarse_tire)
    _traced_vs_host(e10_steady, coarse_tire)


@pytest.mark.parametrize("name", SIDEWALL)
def test_traced_equals_host_sidewall(sidewall_runs, coarse_tire, name):
    for run in sidewall_runs[name].values():
        _traced_vs_host(run, coarse_tire)
