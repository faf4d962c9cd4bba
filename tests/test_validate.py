"""The rigid-ring validation's shell runs (`jtire.validate`): the slip-angle step at each condition is
saved as it finishes (DIR/validation), a resume runs only what is missing or failed, a folder made with
other settings refuses, progress is reported per condition, and a failed step is an error and a visible
"SHELL RUN FAILED" row, never a silent "not compared".

Fast: the folder machinery, with the shell simulator replaced by a stand-in that returns made-up steps
and the ring's scenarios (~20 s per condition, tested in test_rigid_ring_*.py) left out: the rows hold
the shell's numbers only. Slow: one real slip step on the coarse ring, whose quantities are the ones the
experiment declares.
"""

import numpy as np
import pytest

from jtire import batch
from jtire.errors import ConfigError, SimulationError
from jtire.experiments import REGISTRY
from jtire.experiments.result import ExperimentResult
from jtire.rigid_ring import synthetic
from jtire.rigid_ring.table import write_characterization
from jtire.validate import DEFAULT_CONDITIONS, validate

from .conftest import REPO

CHAR = REPO / "configs" / "characterize.toml"
STEP_TABLE = {"speeds_m_per_s": [5.0, 15.0]}


def _step(condition) -> ExperimentResult:
    """A made-up slip step result with every quantity the experiment writes (a first-order build-up)."""
    s = np.linspace(0.0, 3.0, 50)
    q = {n: 1.0 for n in REGISTRY["slip_step"].quantity_names}
    sig = {}
    for v in (5, 15):
        q |= {f"F_y_steady_SAE_N_{v}": -3000.0, f"M_z_steady_SAE_Nm_{v}": 120.0, f"s63_m_{v}": 0.4}
        sig |= {f"distance_m_{v}": s, f"F_y_SAE_N_{v}": -3000.0 * (1 - np.exp(-s / 0.4)), f"M_z_SAE_Nm_{v}": 0 * s}
    return ExperimentResult("slip_step", dict(condition), q, signals=sig)


@pytest.fixture
def plan_and_folder(tmp_path):
    from jtire.characterize import load_plan

    write_characterization(tmp_path, synthetic.characterization())
    return load_plan(CHAR), tmp_path


def _steady(condition, speed) -> ExperimentResult:
    """A made-up steady cornering result at 0, 1 and 2 deg (the validation's steady reference)."""
    sig = {"slip_angle_deg": np.array([0.0, 1.0, 2.0]), "F_y_SAE_N": np.array([0.0, -1600.0, -3100.0]),
           "M_z_SAE_Nm": np.array([0.0, 60.0, 118.0])}
    return ExperimentResult("cornering", dict(condition), {"speed_m_per_s": speed}, signals=sig)


def fake_runs(monkeypatch, fail_loads_kg=(), steady=None):
    """batch.run replaced: slip steps at the given loads fail; returns the list of slip-step conditions
    run (the steady references' (condition, speed) go to `steady` when given)."""
    ran = []

    def run(exp, tire, conditions, *a, on_result=None, **kw):
        out = []
        for i, c in enumerate(conditions):
            if exp.name == "cornering":
                v = float(exp.speed)
                if steady is not None:
                    steady.append((c, v))
                on_result(i, _steady(c, v))
                continue
            ran.append(c)
            fail = any(abs(c["load_N"] - kg * 9.81) < 1e-6 for kg in fail_loads_kg)
            r = batch.CaseFailure(c, SimulationError("slip step: blew up at 0.12 s")) if fail else _step(c)
            on_result(i, r)
            out.append(r)
        return out

    monkeypatch.setattr(batch, "run", run)
    monkeypatch.setattr("jtire.tire.make_tire", lambda spec: None)
    monkeypatch.setattr("jtire.validate.ring_results", lambda *a, **k: {})
    return ran


def test_failed_step_is_a_visible_row_saved_and_retried_on_resume(plan_and_folder, monkeypatch):
    plan, folder = plan_and_folder
    ran = fake_runs(monkeypatch, fail_loads_kg=[2312.5])
    seen = []
    res = validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE, on_case=lambda *a: seen.append(a))
    assert len(ran) == 3 and [a[1:] for a in seen] == [(0, 3), (1, 3), (2, 3), (3, 3)]  # a step per condition
    by_load = {round(c["load_N"] / 9.81, 3): (rows, err) for c, rows, _, _, err in res}
    rows, err = by_load[2312.5]
    assert "blew up at 0.12 s" in err
    steps = [r for r in rows if r.metric.startswith("step_")]
    assert len(steps) == 6 and all(r.verdict == "SHELL RUN FAILED" for r in steps)
    rows, err = by_load[4625.0]
    steps = [r for r in rows if r.metric.startswith("step_")]
    assert err is None and all(r.shell is not None and r.verdict == "not compared" for r in steps)  # no ring here
    cases = sorted((folder / "validation" / "cases").iterdir())
    assert [bool(list(c.glob("error.txt"))) for c in cases] == [False, True, False]
    assert all((c / "signals.csv").is_file() == (c / "result.json").is_file() for c in cases)
    # the resume runs the failed condition only; the others are read back (signals too)
    ran = fake_runs(monkeypatch)
    seen.clear()
    res = validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE, on_case=lambda *a: seen.append(a))
    assert [round(c["load_N"] / 9.81, 3) for c in ran] == [2312.5]
    assert seen[0][1:] == (2, 3) and seen[-1][1:] == (3, 3) and len(seen) == 2
    assert all(err is None for *_, err in res)
    assert not list((folder / "validation" / "cases").glob("*/error.txt"))
    for _, rows, s_sig, _, _ in res:
        assert "step_5" in s_sig and not any(r.verdict == "SHELL RUN FAILED" for r in rows)


def test_steady_references_are_saved_per_speed_and_resumed(plan_and_folder, monkeypatch):
    """Beside the steps, the shell's steady solve at each step's speed and angle (E10's method) is run
    per condition into DIR/validation/steady_<v>_m_s, with the step's angle as the last of three, and a
    resume runs none of them again."""
    from jtire.validate import steady_references

    plan, folder = plan_and_folder
    steady, seen = [], []
    fake_runs(monkeypatch, steady=steady)
    validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE, on_steady=lambda *a: seen.append(a[1:]))
    assert sorted({round(v, 6) for _, v in steady}) == [5.0, 15.0] and len(steady) == 6
    assert seen == [(k, 6) for k in range(7)]  # progress per (condition, speed)
    for v in (5, 15):
        cases = sorted((folder / "validation" / f"steady_{v}_m_s" / "load_levels_2" / "cases").iterdir())
        assert len(cases) == 3 and all((c / "result.json").is_file() for c in cases)
    refs = steady_references(folder, plan, [c for c, _ in steady[:3]], STEP_TABLE)
    assert list(refs) == [5.0, 15.0] and all(len(r) == 3 and r[0].signals["slip_angle_deg"][-1] == 2.0
                                             for r in refs.values())
    steady.clear()
    validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE)
    assert steady == []


def test_a_failed_steady_reference_is_tried_again_with_more_load_levels(plan_and_folder, monkeypatch):
    """A condition whose steady loading at speed failed is run again with 3, then 5 load levels (each
    try its own folder), only that condition; what finally fails is returned as its error."""
    from jtire.validate import REFERENCE_LOAD_LEVELS, steady_references

    plan, folder = plan_and_folder
    tries = []

    def run(exp, tire, conditions, *a, on_result=None, **kw):
        for i, c in enumerate(conditions):
            tries.append((exp.load_levels, round(c["load_N"])))
            ok = c["load_N"] > 40000 or tries[-1][0] == 3  # the light condition converges with 3 levels
            on_result(i, _steady(c, float(exp.speed)) if ok else
                      batch.CaseFailure(c, SimulationError("steady rolling, load 1/2: not found")))

    monkeypatch.setattr(batch, "run", run)
    monkeypatch.setattr("jtire.tire.make_tire", lambda spec: None)
    conds = [{"load_N": 45000.0, "pressure_Pa": 8.27e5}, {"load_N": 22500.0, "pressure_Pa": 8.27e5}]
    refs = steady_references(folder, plan, conds, {"speeds_m_per_s": [15.0]})
    assert REFERENCE_LOAD_LEVELS[:2] == (2, 3)
    assert tries == [(2, 45000), (2, 22500), (3, 22500)]
    assert all(not isinstance(r, str) for r in refs[15.0])
    # a condition that fails every try: its last error
    tries.clear()
    monkeypatch.setattr(batch, "run", lambda exp, tire, conditions, *a, on_result=None, **kw: [
        on_result(i, batch.CaseFailure(c, SimulationError(f"load 1/{exp.load_levels}: not found")))
        for i, c in enumerate(conditions)])
    refs = steady_references(folder / "again", plan, conds[:1], {"speeds_m_per_s": [15.0]})
    assert refs[15.0] == [f"load 1/{REFERENCE_LOAD_LEVELS[-1]}: not found"]


def test_steady_reference_experiment_is_the_steps_angle_and_speed(plan_and_folder, monkeypatch):
    """The reference is E10's steady method at the step's speed, its angles 0, half and all of the
    step's (a step of -3 deg: a range over [-3, 0]); a step of 0 deg has none."""
    from jtire.validate import steady_references

    plan, folder = plan_and_folder
    seen = []

    def run(exp, tire, conditions, *a, on_result=None, **kw):
        seen.append(exp)
        for i, c in enumerate(conditions):
            on_result(i, _steady(c, float(exp.speed)))

    monkeypatch.setattr(batch, "run", run)
    monkeypatch.setattr("jtire.tire.make_tire", lambda spec: None)
    conds = [{"load_N": 45000.0, "pressure_Pa": 8.27e5}]
    steady_references(folder, plan, conds, {"speeds_m_per_s": [7.0], "slip_angle_deg": -3.0})
    (exp,) = seen
    assert exp.method == "steady" and float(exp.speed) == pytest.approx(7.0, rel=1e-12)
    assert np.degrees(exp.slip_angles) == pytest.approx([0.0, -1.5, -3.0], abs=1e-12)
    assert steady_references(folder, plan, conds, {"speeds_m_per_s": [7.0], "slip_angle_deg": 0.0}) == {}
    # a step faster than E10's config allows (60 mph = 26.8 m/s) has no reference, and no error
    seen.clear()
    assert list(steady_references(folder / "again", plan, conds, {"speeds_m_per_s": [7.0, 30.0]})) == [7.0]


def test_resume_runs_nothing_finished_and_other_settings_refuse(plan_and_folder, monkeypatch):
    plan, folder = plan_and_folder
    fake_runs(monkeypatch)
    validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE)
    ran = fake_runs(monkeypatch)
    validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE)
    assert ran == []
    with pytest.raises(ConfigError, match="holds results made with other settings.*slip_step"):
        validate(folder, plan, DEFAULT_CONDITIONS, {"speeds_m_per_s": [5.0, 15.0], "distance_m": 2.0})
    with pytest.raises(ConfigError, match="holds results made with other settings.*conditions"):
        validate(folder, plan, DEFAULT_CONDITIONS[:2], STEP_TABLE)
    assert ran == []


def test_slip_step_runs_on_the_finer_contact_and_its_folder_says_so(plan_and_folder, monkeypatch):
    """The shell's slip step runs on the tire with the config's `validation.step_contact_subpoints`
    contact points per segment (default 8; the default tire has 2), everything else the tire's; the
    steady references on the tire as it is; the step's folder records the tire it ran on, so a folder
    made on the coarser contact refuses."""
    import dataclasses
    import json

    from jtire.validate import step_tire

    plan, folder = plan_and_folder
    fake_runs(monkeypatch)
    specs = []
    monkeypatch.setattr("jtire.tire.make_tire", specs.append)
    validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE)
    n = plan.validation["step_contact_subpoints"]
    assert plan.tire.contact_subpoints == 2 < n == 8
    assert specs[0] == dataclasses.replace(plan.tire, contact_subpoints=n)  # the step
    assert len(specs) > 1 and all(s == plan.tire for s in specs[1:])  # the steady references
    saved = json.loads((folder / "validation" / "settings.json").read_text())
    assert saved["tire"]["contact_subpoints"] == n
    finer = dataclasses.replace(plan.tire, contact_subpoints=n)
    assert step_tire(dataclasses.replace(plan, tire=finer)) == finer  # never coarser than the tire's own
    assert step_tire(dataclasses.replace(plan, validation={"step_contact_subpoints": 1})) == plan.tire
    saved["tire"]["contact_subpoints"] = 2  # a folder the coarser contact made
    (folder / "validation" / "settings.json").write_text(json.dumps(saved))
    with pytest.raises(ConfigError, match="holds results made with other settings.*contact_subpoints"):
        validate(folder, plan, DEFAULT_CONDITIONS, STEP_TABLE)


def test_storage_tire_scales_the_rubber_by_its_storage_modulus(plan_and_folder):
    """Every part's four moduli and the tread's E and G times E'(f)/K of their own loss
    (materials.dynamic_modulus); thickness, loss, undertread and friction as they were; at 0 Hz the tire."""
    from jtire.materials import dynamic_modulus
    from jtire.validate import storage_tire

    tire = plan_and_folder[0].tire
    assert storage_tire(tire, 0.0) == tire
    st = storage_tire(tire, 15.0)
    tau = np.asarray(tire.relaxation_times)
    for name, p in tire.parts.items():
        s = float(dynamic_modulus(p["loss"], tau, 15.0)[1])
        assert 1.05 < s < 1.5
        for k in ("E_meridional", "E_circumferential", "G_shear", "E_bending"):
            assert st.parts[name][k] == pytest.approx(s * p[k], rel=1e-12)
        assert st.parts[name]["thickness"] == p["thickness"] and st.parts[name]["loss"] == p["loss"]
    s = float(dynamic_modulus(tire.tread_loss, tau, 15.0)[1])
    assert (st.tread_E, st.tread_G) == pytest.approx((s * tire.tread_E, s * tire.tread_G), rel=1e-12)
    assert (st.undertread_E, st.friction, st.tread_loss) == (tire.undertread_E, tire.friction, tire.tread_loss)


def test_storage_pushes_run_once_per_condition_with_a_frequency(plan_and_folder, monkeypatch):
    """E09's static push (no release) on the storage tire at each condition's frequency, saved in its own
    folder under DIR/lateral_storage; a condition without a frequency is not run; a rerun reads them back."""
    from jtire import results
    from jtire import units as U
    from jtire.validate import storage_pushes, storage_tire

    plan, folder = plan_and_folder
    conds = [{"load_N": kg * U.G0, "pressure_Pa": psi * U.PSI} for kg, psi in DEFAULT_CONDITIONS]
    ran, specs = [], []

    def run(exp, tire, conditions, *a, on_result=None, **kw):
        assert exp.name == "lateral_stiffness" and not exp.with_decay and exp.method == "static"
        for i, c in enumerate(conditions):
            ran.append(c)
            on_result(i, ExperimentResult("lateral_stiffness", dict(c), {"k_l_N_per_m": 7.7e5}))

    monkeypatch.setattr(batch, "run", run)
    monkeypatch.setattr("jtire.tire.make_tire", specs.append)
    root = folder / results.LATERAL_STORAGE
    out = storage_pushes(root, plan, conds, [15.0, None, 13.5])
    # the two pushes run side by side over the devices: in either order
    assert sorted(map(str, ran)) == sorted(map(str, [conds[0], conds[2]])) and out[1] is None
    want = [storage_tire(plan.tire, 15.0), storage_tire(plan.tire, 13.5)]
    assert len(specs) == 2 and all(w in specs for w in want)
    assert [r.quantities["k_l_N_per_m"] for r in (out[0], out[2])] == [7.7e5, 7.7e5]
    for c in (conds[0], conds[2]):
        tail = results.case_name(0, c)
        assert results.is_done(results.cases_dir(root / tail) / tail)
    ran.clear()
    again = storage_pushes(root, plan, conds, [15.0, None, 13.5])
    assert ran == [] and again[0].quantities == out[0].quantities


def test_lateral_springs_push_each_condition_at_e09s_own_frequency(plan_and_folder, monkeypatch):
    """`characterize.lateral_springs` pushes E09 on the storage tire at the release frequency E09 measured
    at each grid condition (none where E09 has no result), into DIR/lateral_storage; `characterization`
    puts that k_l and frequency in the condition's row, and `derive` reports their ratio to the static k_l."""
    from jtire import characterize as ch
    from jtire.rigid_ring.params import derive
    from jtire.validate import storage_tire

    plan, folder = plan_and_folder
    freqs = [13.0 + 0.25 * i for i in range(len(plan.conditions))]
    found = {"lateral_stiffness": [None if i == 4 else {"quantities": {"k_l_N_per_m": 7.0e5, "f_d_fit_Hz": f}}
                                   for i, f in enumerate(freqs)]}
    pushed = []

    def run(exp, tire, conditions, *a, on_result=None, **kw):
        for i, c in enumerate(conditions):
            pushed.append((dict(c), tire))
            on_result(i, ExperimentResult("lateral_stiffness", dict(c), {"k_l_N_per_m": 7.7e5}))

    monkeypatch.setattr(batch, "run", run)
    monkeypatch.setattr("jtire.tire.make_tire", lambda spec: spec)
    out = ch.lateral_springs(plan, folder, found)
    assert out[4] is None and len(pushed) == len(plan.conditions) - 1
    # side by side over the devices, in either order: each condition on the tire of its own frequency
    at = {str(c): i for i, c in enumerate(plan.conditions)}
    assert sorted(at[str(c)] for c, _ in pushed) == [i for i in range(len(freqs)) if i != 4]
    assert all(t == storage_tire(plan.tire, freqs[at[str(c)]]) for c, t in pushed)
    pushed.clear()
    char = ch.characterization(plan, folder, found)
    assert pushed == []  # read back, not run again
    for i, (c, row) in enumerate(zip(plan.conditions, char.rows)):
        assert (row.load_N, row.pressure_Pa) == (c["load_N"], c["pressure_Pa"])
        if i == 4:
            assert "k_l_storage_N_per_m" not in row.q
        else:
            assert (row.q["k_l_storage_N_per_m"], row.q["f_l_storage_Hz"]) == (7.7e5, freqs[i])
            assert derive(row, char.tire).lateral_storage_ratio == pytest.approx(1.1, rel=1e-12)


def test_the_steps_contact_is_a_config_field(tmp_path):
    """`validation.step_contact_subpoints` comes from the characterization config (`--set`), in 1-8;
    out of range or misspelt is one ConfigError line naming it."""
    from jtire.characterize import load_plan

    cfg = REPO / "configs" / "characterize.toml"
    assert load_plan(cfg).validation == {"step_contact_subpoints": 8}
    assert load_plan(cfg, overrides=["validation.step_contact_subpoints=2"]).validation["step_contact_subpoints"] == 2
    with pytest.raises(ConfigError, match="validation.step_contact_subpoints"):
        load_plan(cfg, overrides=["validation.step_contact_subpoints=9"])
    with pytest.raises(ConfigError, match="validation.step_subpoints"):
        load_plan(cfg, overrides=["validation.step_subpoints=2"])


def test_characterize_reports_a_failed_step_as_an_error(plan_and_folder, monkeypatch, capsys):
    """The command's validation: the failure is listed for the final error line (exit 2) and written
    under its condition in validation.md; the progress bar moves per condition (stderr)."""
    from jtire.cli.characterize import _validate

    plan, folder = plan_and_folder
    fake_runs(monkeypatch, fail_loads_kg=[4625.0])
    monkeypatch.setattr("jtire.rigid_ring.diagnosis.diagnose", lambda *a, **k: [])
    monkeypatch.setattr("jtire.rigid_ring.validation.validation_figure", lambda *a, **k: None)
    lines = []
    written, failed = _validate(plan, folder, lambda s, err=False: lines.append(s))
    assert len(failed) == 2 and all("blew up at 0.12 s" in f for f in failed)  # rated and soft: 4625 kg
    md = (folder / "validation.md").read_text()
    assert md.count("| SHELL RUN FAILED |") == 12 and md.count("rerun the command to retry it") == 2
    # one summary line of the verdicts over every condition, in the file and last on the screen
    summary = lines[-1]
    assert summary.startswith("validation: ") and "12 SHELL RUN FAILED" in summary
    for verdict in ("pass", "FAIL", "not compared"):
        n = md.count(f"| {verdict} |")
        assert (f"{n} {verdict}" in summary) == (n > 0), verdict
    assert f"Metrics over the 3 conditions: {summary[len('validation: '):].split(' (')[0]}." in md
    assert "validation slip steps" in capsys.readouterr().err


@pytest.mark.slow
def test_real_slip_step_writes_its_declared_quantities(spec, protocol, coarse_tire):
    """One slip step at 5 m/s on the coarse ring (about a minute here): a finite steady F_y of the SAE
    sign for a positive slip angle, and the quantities the experiment declares, no more, no fewer."""
    from jtire.config import validate_table

    from .conftest import RATED, make_experiment, ok

    table = {"speeds_m_per_s": [5.0], "distance_m": 1.0}
    exp = make_experiment("slip_step", protocol, spec, **table)
    (r,) = batch.run(exp, coarse_tire, [RATED])
    r = ok(r)
    assert set(r.quantities) == set(REGISTRY["slip_step"].produces(validate_table(table, exp.schema, "slip_step")))
    assert np.isfinite(r.quantities["F_y_steady_SAE_N_5"]) and r.quantities["F_y_steady_SAE_N_5"] < 0
