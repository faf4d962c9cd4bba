"""Every bad input to every subcommand is one clear line, exit code 2, before any simulation.

Table-driven (issue 13): each case builds its inputs in a temp folder, runs `jtire.cli.main` in
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
import time
from pathlib import Path

import numpy as np
import pytest

from jtire.cli import SUBCOMMANDS, _available

from .conftest import REPO, TIRE_TOML

# In process, after the first import, every case here takes well under a second (measured:
# slowest ~1.5 s, the stand-in's Jacobian compile in `sensitivity`); 10 s leaves room for a
# loaded 2-core machine while still catching anything that starts a simulation.
CASE_SECONDS = 10.0
CONFIGS = REPO / "configs"
COMPETITION = (CONFIGS / "calibration" / "soil_competition.toml").read_text()
TRACK = (CONFIGS / "data" / "track_rolling_resistance.csv").read_text()
SANDBOX = (CONFIGS / "data" / "sandbox_rolling_resistance.csv").read_text()
STUDY = str(CONFIGS / "calibration" / "study.toml")
POSTERIOR = str(CONFIGS / "calibration" / "posterior.toml")
COND = "[condition]\nload_kg = 4625.0\npressure_psi = 120.0\n"
FOOTPRINT = f'tire_file = "tire.toml"\nexperiment = "footprint"\n{COND}'
VERTICAL = (f'tire_file = "tire.toml"\nexperiment = "vertical_stiffness"\n{COND}'
            "[vertical_stiffness]\nmax_load_kN = 75.0\n")  # above the sweep's largest load (68 kN)
CHAR = ('tire_file = "tire.toml"\nexperiments = ["footprint", "vertical_stiffness"]\n'
        "[grid]\nloads_kg = [4625.0]\npressures_psi = [120.0]\n")


class SimulationReached(BaseException):
    """Raised by the trapped simulation entry points (BaseException: no handler may take it)."""


def _trap(*args, **kwargs):
    raise SimulationReached


def _trap_objective(cfg):
    return _trap


@pytest.fixture
def trapped(monkeypatch):
    """Replace every entry point into a simulation by the trap."""
    import jtire.batch
    import jtire.tire

    monkeypatch.setattr(jtire.batch, "run", _trap)
    monkeypatch.setattr(jtire.tire, "make_tire", _trap)
    if "compete" in _available():
        import jtire.cli.compete as compete

        monkeypatch.setattr(compete, "soil_objective", _trap_objective)
        monkeypatch.setattr(compete, "standin_objective", _trap_objective)
    if "calibrate" in _available():
        import jtire.calibration.tire_calibration as tc

        monkeypatch.setattr(tc, "calibrate_arsm", _trap)
        monkeypatch.setattr(tc, "calibrate_lm", _trap)
    if "sample" in _available():
        import jtire.calibration.sampling as sampling

        monkeypatch.setattr(sampling, "fit_emulator", _trap)
        monkeypatch.setattr(sampling, "run_sampler", _trap)
    if "export-tir" in _available():
        import jtire.rigid_ring.export as export

        monkeypatch.setattr(export, "export", _trap)


class Case:
    """argv(tmp) -> list of arguments (the inputs written under tmp); words: in the error line."""

    def __init__(self, name, argv, *words, xfail=None):
        self.name, self.argv, self.words, self.xfail = name, argv, words, xfail
        self.command = None  # set from the first argument when run

    def param(self):
        marks = [pytest.mark.xfail(reason=self.xfail, strict=True)] if self.xfail else []
        return pytest.param(self, id=self.name, marks=marks)


def _w(tmp, name, data):
    p = Path(tmp) / name
    p.parent.mkdir(parents=True, exist_ok=True)
    if isinstance(data, bytes):
        p.write_bytes(data)
    else:
        p.write_text(data)
    return str(p)


def _exp(tmp, body, name="exp.toml", tire=None):
    """An experiment config `body` beside a copy of the shipped tire (or `tire` text)."""
    _w(tmp, "tire.toml", TIRE_TOML.read_text() if tire is None else tire)
    return _w(tmp, name, body)


def _data_dir(tmp, track=None, sandbox=None):
    d = Path(tmp) / "data"
    _w(d, "track_rolling_resistance.csv", TRACK if track is None else track)
    _w(d, "sandbox_rolling_resistance.csv", SANDBOX if sandbox is None else sandbox)
    return str(d)


def _exact_track():
    """The track table with every RRC replaced by an exact line in Fz (no scatter at all)."""
    out = []
    for line in TRACK.splitlines():
        if line.startswith(("#", "config")):
            out.append(line)
            continue
        f = line.split(",")
        f[7] = repr(0.01 + 1e-5 * float(f[6]))
        out.append(",".join(f))
    return "\n".join(out) + "\n"


def _blocked(tmp):
    """An output folder that cannot be made (its parent is a file)."""
    _w(tmp, "a_file", "")
    return str(Path(tmp) / "a_file" / "out")


def _comp(tmp, old, new, name="comp.toml"):
    assert old in COMPETITION, old
    return _w(tmp, name, COMPETITION.replace(old, new, 1))


def _track_sub(old, new):
    assert old in TRACK, old
    return TRACK.replace(old, new, 1)


def _out(tmp):
    return ["--out", str(Path(tmp) / "out")]


NON_UTF8 = b"# jtire config\nexperiment = \"footprint\"\n# caf\xe9 \xff\n"
TIRE_PREFIX_XFAIL = ("jtire/characterize.py load_plan calls tire_from_dict without the 'tire file NAME: tire.' "
                     "prefix that load_run_config and calibration.spec give (owned by another helper)")

CASES = [
    # ---- run -------------------------------------------------------------------------------------
    Case("run-non-utf8-config", lambda t: ["run", _w(t, "bad.toml", b"\xff\xfe")], "bad.toml", "not UTF-8", "line 1"),
    Case("run-non-utf8-tire", lambda t: ["run", _exp_bytes_tire(t)], "tire.toml", "not UTF-8"),
    Case("run-folder-as-config", lambda t: ["run", str(t)], "is a folder, not a config file"),
    Case("run-missing-config", lambda t: ["run", str(Path(t) / "nope.toml")], "nope.toml", "no such config file"),
    Case("run-malformed-toml", lambda t: ["run", _w(t, "m.toml", "experiment = [\n")], "m.toml", "not valid TOML"),
    Case("run-set-empty-key", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "=5"], "--set '=5'", "dotted field name"),
    Case("run-set-no-equals", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.load_kg"], "KEY=VALUE"),
    Case("run-load-1e-6-kg", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.load_kg=1e-6"],
         "condition.load_kg = 1e-06: must be in [50, 50000]"),
    Case("run-pressure-boolean", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "condition.pressure_psi=true"],
         "condition.pressure_psi = True: must be a number"),
    Case("run-unknown-top-key", lambda t: ["run", _exp(t, 'colour = "red"\n' + FOOTPRINT)], "colour: unknown field"),
    Case("run-experiment-and-experiments", lambda t: ["run", _exp(t, 'experiments = ["footprint"]\n' + FOOTPRINT)],
         "not both"),
    Case("run-unknown-experiment", lambda t: ["run", _exp(t, FOOTPRINT.replace('"footprint"', '"flying"'))],
         "experiment = 'flying': unknown"),
    Case("run-table-of-experiment-not-run", lambda t: ["run", _exp(
        t, FOOTPRINT + "[vertical_stiffness]\nmax_load_kN = -60.0\n")], "vertical_stiffness.max_load_kN = -60"),
    Case("run-slip-angles-booleans", lambda t: ["run", _exp(t, FOOTPRINT.replace(
        '"footprint"', '"cornering"') + "[cornering]\nslip_angles_deg = [true, false]\n")],
         "cornering.slip_angles_deg = [True, False]: must be a list"),
    Case("run-second-experiment-table-bad", lambda t: ["run", _exp(t, FOOTPRINT.replace(
        'experiment = "footprint"', 'experiments = ["footprint", "vertical_stiffness"]')
        + "[vertical_stiffness]\nmax_load_kN = 60.0\nstated_load_kN = 70.0\n")], "vertical_stiffness."),
    Case("run-two-loads", lambda t: ["run", _exp(t, FOOTPRINT + "load_kN = 45.0\n")], "give exactly one of load_kg"),
    Case("run-no-tire-file", lambda t: ["run", _w(t, "e.toml", f'experiment = "footprint"\n{COND}')],
         "tire_file: missing"),
    Case("run-tire-file-missing", lambda t: ["run", _w(t, "e.toml", FOOTPRINT.replace("tire.toml", "no_tire.toml"))],
         "no_tire.toml", "no such tire file"),
    Case("run-tread-wider-than-section", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.tread_width_mm=1000"],
         "tire file tire.toml: tire.tire.tread_width_mm = 1000: must be in [tire.belt_width_mm = 360"),
    Case("run-crown-radius-50", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.crown_radius_mm=50"],
         "tire file tire.toml: tire.tire.crown_radius_mm = 50: must be above"),
    Case("run-tread-depth-60", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.tire.tread_depth_mm=60"],
         "tire.tire.tread_depth_mm = 60: must be below"),
    Case("run-mesh-n-theta-8", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.mesh.n_theta=8"],
         "tire file tire.toml: tire.mesh.n_theta = 8: must be in [16, 1024]"),
    Case("run-belt-heavier-than-tire", lambda t: ["run", _exp(t, FOOTPRINT), "--set", "tire.mass.belt_kg=90"],
         "tire.mass.belt_kg = 90: must be below mass.tire_kg"),
    Case("run-settle-damping-below-range", lambda t: ["run", _exp(t, FOOTPRINT), "--set",
                                                      "solver.settle_damping_per_s=0.5"],
         "solver.settle_damping_per_s = 0.5: must be in"),
    Case("run-out-unwritable", lambda t: ["run", _exp(t, FOOTPRINT), "--out", _blocked(t)],
         "cannot read or write", "a_file"),
    # ---- sweep -----------------------------------------------------------------------------------
    Case("sweep-non-utf8-config", lambda t: ["sweep", _w(t, "bad.toml", NON_UTF8)], "bad.toml", "not UTF-8",
         "line 3"),
    Case("sweep-negative-batch", lambda t: ["sweep", _exp(t, VERTICAL), "--batch", "-1", *_out(t)],
         "--batch -1: must be >= 0"),
    Case("sweep-boolean-loads", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloads_kg = [true]\n"), *_out(t)],
         "sweep.loads_kg = [True]: must be a list"),
    Case("sweep-unknown-key", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloadz_kg = [4625.0]\n"), *_out(t)],
         "sweep.loadz_kg: unknown field"),
    Case("sweep-load-twice", lambda t: ["sweep", _exp(t, VERTICAL + "[sweep]\nloads_kg = [4625.0, 4625.0]\n"),
                                        *_out(t)], "sweep.loads_kg: lists a value twice"),
    Case("sweep-two-experiments", lambda t: ["sweep", _exp(t, VERTICAL.replace(
        'experiment = "vertical_stiffness"', 'experiments = ["vertical_stiffness", "footprint"]')), *_out(t)],
         "exactly one experiment"),
    Case("sweep-out-unwritable", lambda t: ["sweep", _exp(t, VERTICAL), "--out", _blocked(t)], "cannot read or write"),
    Case("sweep-resume-other-settings", lambda t: _sweep_claimed(t) + ["--set", "vertical_stiffness.max_load_kN=70"],
         "holds results made with other settings"),
    Case("sweep-no-config", lambda t: ["sweep"], "the following arguments are required: config"),
    # ---- characterize ----------------------------------------------------------------------------
    Case("characterize-non-utf8-tire", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--tire",
                                                  _w(t, "t2.toml", b"[tire]\n\xff"), *_out(t)],
         "t2.toml", "not UTF-8", "line 2"),
    Case("characterize-negative-batch", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--batch", "-2",
                                                   *_out(t)], "--batch -2: must be >= 0"),
    Case("characterize-boolean-grid", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                 "grid.loads_kg=[true]", *_out(t)], "grid.loads_kg = [True]"),
    Case("characterize-rated-off-grid", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                   "grid.rated_load_kg=1000", *_out(t)], "grid.rated_load_kg"),
    Case("characterize-unknown-key", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set", "colour=1",
                                                *_out(t)], "colour: unknown field"),
    Case("characterize-relaxation-listed", lambda t: ["characterize", _exp(t, CHAR.replace(
        '"footprint", ', '"relaxation_length", '), name="char.toml"), *_out(t)], "relaxation_length is derived"),
    Case("characterize-folder-as-config", lambda t: ["characterize", str(t), *_out(t)], "is a folder"),
    Case("characterize-out-unwritable", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--out",
                                                   _blocked(t)], "cannot read or write"),
    Case("characterize-resume-other-settings", lambda t: _characterize_claimed(t) + [
        "--set", "vertical_stiffness.max_load_kN=70"], "holds results made with other settings"),
    Case("characterize-tire-error-names-file", lambda t: ["characterize", _exp(t, CHAR, name="char.toml"), "--set",
                                                          "tire.tire.tread_width_mm=1000", *_out(t)],
         "tire file tire.toml: tire.tire.tread_width_mm = 1000", xfail=TIRE_PREFIX_XFAIL),
    # ---- data ------------------------------------------------------------------------------------
    Case("data-non-utf8-csv", lambda t: ["data", "--data-dir", _data_dir(t, track=TRACK.encode() + b"9,\xff\n"),
                                         *_out(t)], "track_rolling_resistance.csv", "not UTF-8", "line 35"),
    Case("data-empty-csv", lambda t: ["data", "--data-dir", _data_dir(t, sandbox=""), *_out(t)],
         "sandbox_rolling_resistance.csv", "empty"),
    Case("data-header-only-csv", lambda t: ["data", "--data-dir", _data_dir(t, track="\n".join(
        TRACK.splitlines()[:4]) + "\n"), *_out(t)], "no data rows (only the header)"),
    Case("data-duplicate-column", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "fz_lbs,rrc", "fz_lbs,fz_lbs")), *_out(t)], "line 4", "['fz_lbs'] appear more than once"),
    Case("data-short-row", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1A,28.43782,", "1A,")), *_out(t)], "line 5: 7 fields, the header has 8"),
    Case("data-not-a-number", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1A,28.43782", "1A,lots")), *_out(t)], "line 5: fx_lbs = 'lots': must be a number"),
    Case("data-inf", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub("1A,28.43782", "1A,inf")),
                                *_out(t)], "line 5: fx_lbs = inf: must be finite"),
    Case("data-unterminated-quote", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1,bobtail,120", '1,"bobtail,120')), *_out(t)], "line 5: not valid CSV"),
    Case("data-config-rows-disagree", lambda t: ["data", "--data-dir", _data_dir(t, track=_track_sub(
        "1,bobtail,120,1160.95,1A", "1,bobtail,80,1160.95,1A")), *_out(t)],
         "configuration 1 has runs with different pressure_psi"),
    Case("data-exact-fit", lambda t: ["data", "--data-dir", _data_dir(t, track=_exact_track()), *_out(t)],
         "fit track_120psi", "lie exactly on the linear trend"),
    Case("data-no-120-psi-runs", lambda t: ["data", "--data-dir", _data_dir(t, track="\n".join(
        ln for ln in TRACK.splitlines() if ",120," not in ln) + "\n"), *_out(t)],
         "fit track_120psi", "0 points: a fit with confidence intervals needs at least 3"),
    Case("data-missing-dir", lambda t: ["data", "--data-dir", str(Path(t) / "nowhere"), *_out(t)],
         "track_rolling_resistance.csv: not found"),
    Case("data-reference-malformed", lambda t: ["data", "--reference", _w(t, "r.toml", "[calibration\n"), *_out(t)],
         "r.toml: not valid TOML"),
    Case("data-reference-inf", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = inf\nforce_N = 1529.39\n"),
        *_out(t)], "r.toml: calibration.targets.rolling_resistance_1.vertical_load_kN = inf: must be in (0, 500]"),
    Case("data-reference-nan", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = 38.7\nforce_N = nan\n"),
        *_out(t)], "rolling_resistance_1.force_N = nan"),
    Case("data-reference-negative", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = -38.7\nforce_N = 1529.39\n"),
        *_out(t)], "vertical_load_kN = -38.7"),
    Case("data-reference-boolean", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = true\nforce_N = 1529.39\n"),
        *_out(t)], "vertical_load_kN = True: must be a number"),
    Case("data-reference-force-above-load", lambda t: ["data", "--reference", _w(
        t, "r.toml", "[calibration.targets.rolling_resistance_1]\nvertical_load_kN = 1.0\nforce_N = 1500.0\n"),
        *_out(t)], "force_N = 1500: must be below the vertical load"),
    Case("data-reference-not-tables", lambda t: ["data", "--reference", _w(t, "r.toml", "calibration = 3\n"),
                                                 *_out(t)], "calibration.targets must be a table"),
    Case("data-reference-folder", lambda t: ["data", "--reference", str(t), *_out(t)], "is a folder"),
    Case("data-reference-non-utf8", lambda t: ["data", "--reference", _w(t, "r.toml", b"\xfe"), *_out(t)],
         "r.toml: not UTF-8"),
    Case("data-confidence-1", lambda t: ["data", "--confidence", "1", *_out(t)], "--confidence 1: must be in (0, 1)"),
    Case("data-confidence-nan", lambda t: ["data", "--confidence", "nan", *_out(t)], "--confidence nan"),
    Case("data-rrc-choice", lambda t: ["data", "--rrc", "both", *_out(t)], "argument --rrc: invalid choice"),
    Case("data-out-unwritable", lambda t: ["data", "--out", _blocked(t)], "cannot read or write", "a_file"),
    # ---- compete ---------------------------------------------------------------------------------
    Case("compete-non-utf8", lambda t: ["compete", _w(t, "bad.toml", b"\xff\xfe"), *_out(t)], "bad.toml",
         "not UTF-8"),
    Case("compete-misspelled-table", lambda t: ["compete", _comp(t, "[competition]", "[competiton]"), *_out(t)],
         "competiton: unknown field"),
    Case("compete-unknown-top-key", lambda t: ["compete", _w(t, "c.toml", "colour = 1\n" + COMPETITION), *_out(t)],
         "colour: unknown field"),
    Case("compete-seeds-boolean", lambda t: ["compete", _comp(t, "seeds = 20", "seeds = true"), *_out(t)],
         "competition.seeds = True: must be an integer"),
    Case("compete-budget-float", lambda t: ["compete", _comp(t, "budget = 50", "budget = 50.5"), *_out(t)],
         "competition.budget = 50.5"),
    Case("compete-unknown-key", lambda t: ["compete", _comp(t, "budget = 50", "budget = 50\nbudgte = 3"), *_out(t)],
         "competition.budgte: unknown field"),
    Case("compete-ga-population-above-budget", lambda t: ["compete", _comp(t, "pop_size = 10", "pop_size = 100"),
                                                          *_out(t)], "competition.options.ga", "pop_size = 100"),
    Case("compete-option-type", lambda t: ["compete", _comp(t, "min_width = 1e-4", 'min_width = "small"'), *_out(t)],
         "competition.options.arsm.min_width = 'small': must be a finite number"),
    Case("compete-anchor-unknown-method", lambda t: ["compete", _comp(t, "arsm = { error", "asrm = { error"),
                                                     *_out(t)], "competition.anchor.asrm: unknown method"),
    Case("compete-soil-unknown", lambda t: ["compete", _comp(t, "bekker_n = 0.7", "bekker_m = 0.7"), *_out(t)],
         "soil.bekker_m: unknown field"),
    Case("compete-soil-nan", lambda t: ["compete", _comp(t, "bekker_n = 0.7", "bekker_n = nan"), *_out(t)],
         "soil.bekker_n = nan"),
    Case("compete-bounds-inverted", lambda t: ["compete", _comp(t, "[1200.0, 2200.0]", "[2200.0, 1200.0]"), *_out(t)],
         "bounds.density_kg_m3"),
    Case("compete-method-twice", lambda t: ["compete", _comp(t, '["arsm", "ga", "mc"]', '["arsm", "arsm"]'),
                                            *_out(t)], "each method at most once"),
    Case("compete-seeds-flag", lambda t: ["compete", _comp(t, "", ""), "--seeds", "0", *_out(t)],
         "--seeds 0: must be in [1, 10000]"),
    Case("compete-methods-flag-empty", lambda t: ["compete", _comp(t, "", ""), "--methods", ",", *_out(t)],
         "--methods ','"),
    Case("compete-set-boolean", lambda t: ["compete", _comp(t, "", ""), "--set", "competition.budget=true", *_out(t)],
         "competition.budget = True"),
    Case("compete-out-unwritable", lambda t: ["compete", _comp(t, "", ""), "--out", _blocked(t)],
         "cannot read or write"),
    Case("compete-resume-other-soil", lambda t: _compete_claimed(t) + ["--set", "soil.pressure_Pa=80000.0"],
         "holds a competition with other soil"),
    Case("compete-history-of-other-settings", lambda t: _compete_foreign_history(t),
         "arsm_seed000.jsonl", "call 0 asks for x"),
    # ---- calibrate -------------------------------------------------------------------------------
    Case("calibrate-non-utf8", lambda t: ["calibrate", _w(t, "c.toml", b"\xff"), "--standin", *_out(t)], "c.toml",
         "not UTF-8"),
    Case("calibrate-seed-boolean", lambda t: ["calibrate", STUDY, "--standin", "--set", "arsm.seed=true", *_out(t)],
         "arsm.seed = True: must be an integer"),
    Case("calibrate-tire-error-names-file", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                       "tire.tire.crown_radius_mm=50", *_out(t)],
         "tire file xone_xda.toml: tire.tire.crown_radius_mm = 50"),
    Case("calibrate-budget-zero", lambda t: ["calibrate", STUDY, "--standin", "--budget", "0", *_out(t)],
         "--budget = 0: must be >= 1"),
    Case("calibrate-unknown-key", lambda t: ["calibrate", STUDY, "--standin", "--set", "colour=1", *_out(t)],
         "colour: unknown field"),
    Case("calibrate-negative-target", lambda t: ["calibrate", STUDY, "--standin", "--set",
                                                 "targets.DZ.measured_mm=-1", *_out(t)], "targets.DZ.measured_mm = -1"),
    Case("calibrate-out-unwritable", lambda t: ["calibrate", STUDY, "--standin", "--out", _blocked(t)],
         "cannot read or write"),
    Case("calibrate-method-choice", lambda t: ["calibrate", STUDY, "--method", "newton", *_out(t)],
         "argument --method: invalid choice"),
    Case("calibrate-check-tire-missing", lambda t: ["calibrate", STUDY, "--standin", "--check-tire",
                                                    str(Path(t) / "none.toml")], "no such tire file"),
    Case("calibrate-check-tire-not-a-tire", lambda t: ["calibrate", STUDY, "--standin", "--check-tire", STUDY],
         "tire file study.toml"),
    # ---- sample ----------------------------------------------------------------------------------
    Case("sample-no-history", lambda t: ["sample", POSTERIOR, "--history", str(Path(t) / "none"), *_out(t)],
         "no history.jsonl"),
    Case("sample-walkers-boolean", lambda t: ["sample", POSTERIOR, "--set", "sampler.walkers=true", *_out(t)],
         "sampler.walkers = True: must be an integer"),
    Case("sample-walkers-odd", lambda t: ["sample", POSTERIOR, "--set", "sampler.walkers=41", *_out(t)],
         "sampler.walkers = 41: must be even"),
    Case("sample-non-utf8", lambda t: ["sample", _w(t, "p.toml", b"\xfe"), *_out(t)], "p.toml", "not UTF-8"),
    Case("sample-prior-kind", lambda t: ["sample", POSTERIOR, "--set", "prior.kind=flat", *_out(t)],
         "prior.kind = 'flat'"),
    Case("sample-out-unwritable", lambda t: ["sample", POSTERIOR, "--out", _blocked(t)], "cannot read or write"),
    # ---- sensitivity -----------------------------------------------------------------------------
    Case("sensitivity-rel-tol", lambda t: ["sensitivity", STUDY, "--standin", "--rel-tol", "2", *_out(t)],
         "--rel-tol = 2: must be in (0, 1)"),
    Case("sensitivity-at-not-a-calibration", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(t), *_out(t)],
         "no summary.json there"),
    Case("sensitivity-at-non-utf8", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(Path(
        _w(t, "cal/summary.json", b"\xff")).parent), *_out(t)], "summary.json: not UTF-8"),
    Case("sensitivity-at-no-theta", lambda t: ["sensitivity", STUDY, "--standin", "--at", str(Path(
        _w(t, "cal/summary.json", '{"x": 1}')).parent), *_out(t)], "holds no best point"),
    Case("sensitivity-unknown-quantity", lambda t: ["sensitivity", STUDY, "--standin", "--quantities", "nosuch",
                                                    *_out(t)], "--quantities", "nosuch"),
    Case("sensitivity-out-unwritable", lambda t: ["sensitivity", STUDY, "--standin", "--out", _blocked(t)],
         "cannot read or write"),
    # ---- export-tir ------------------------------------------------------------------------------
    Case("export-tir-missing", lambda t: ["export-tir", str(Path(t) / "none.json")], "no file"),
    Case("export-tir-non-utf8", lambda t: ["export-tir", _w(t, "c.json", b"\xff")], "c.json: not UTF-8"),
    Case("export-tir-not-json", lambda t: ["export-tir", _w(t, "c.json", "{not json")], "not valid JSON"),
    Case("export-tir-wrong-format", lambda t: ["export-tir", _w(t, "c.json", "{}")], "format"),
    Case("export-tir-longvl-nan", lambda t: ["export-tir", _w(t, "c.json", "{}"), "--longvl", "nan"],
         "--longvl nan: must be a speed"),
    Case("export-tir-fittyp-choice", lambda t: ["export-tir", _w(t, "c.json", "{}"), "--fittyp", "52"],
         "argument --fittyp: invalid choice"),
    # ---- export-vtk and run --frames ------------------------------------------------------------------
    Case("export-vtk-missing", lambda t: ["export-vtk", str(Path(t) / "nofolder")], "nofolder", "no such frames file"),
    Case("export-vtk-not-npz", lambda t: ["export-vtk", _w(t, "f.npz", b"not a zip file")], "f.npz",
         "not a readable .npz file"),
    Case("export-vtk-missing-arrays", lambda t: ["export-vtk", _npz(t, t=np.zeros(2))], "missing arrays"),
    Case("export-vtk-wrong-shape", lambda t: ["export-vtk", _npz(t, t=np.zeros(2), nodes=np.zeros((2, 4, 5, 3)),
                                                                  nodes_ref=np.zeros((4, 6, 3)))],
         "nodes has shape (2, 4, 5, 3), expected (2, 4, 6, 3)"),
    Case("run-frames-out-of-range", lambda t: ["run", _exp(t, FOOTPRINT), "--frames", "1", *_out(t)],
         "--frames: 1 is out of range", "2 to 200"),
    Case("run-frames-without-out", lambda t: ["run", _exp(t, FOOTPRINT), "--frames", "5"], "--frames: needs --out"),
    Case("run-method-unknown", lambda t: ["run", _exp(t, FOOTPRINT), "--set", 'footprint.method="implicit"'],
         "footprint.method = 'implicit': must be one of static, transient"),
    Case("run-static-with-decay", lambda t: ["run", _exp(t, FOOTPRINT.replace('"footprint"', '"lateral_stiffness"')),
                                             "--set", 'lateral_stiffness.method="static"',
                                             "--set", "lateral_stiffness.decay_s=0.3"],
         'lateral_stiffness.method = "static" with decay_s = 0.3: a static solve has no release decay'),
    # ---- the command line itself -----------------------------------------------------------------
    Case("unknown-subcommand", lambda t: ["simulate"], "invalid choice: 'simulate'"),
    Case("no-subcommand", lambda t: [], "the following arguments are required: command"),
]


def _npz(folder, **arrays):
    path = Path(folder) / "frames.npz"
    np.savez(path, **arrays)
    return str(path)


def _exp_bytes_tire(t):
    cfg = _exp(t, FOOTPRINT)
    _w(t, "tire.toml", TIRE_TOML.read_bytes() + b"\n# caf\xe9\n")
    return cfg


def _sweep_claimed(t):
    """A sweep folder claimed by a first run (stopped by the trap at its first simulation)."""
    from jtire.cli import main

    argv = ["sweep", _exp(t, VERTICAL), *_out(t)]
    with pytest.raises(SimulationReached):
        main(argv)
    assert (Path(t) / "out" / "settings.json").is_file()
    return argv


def _characterize_claimed(t):
    from jtire.cli import main

    argv = ["characterize", _exp(t, CHAR, name="char.toml"), *_out(t)]
    with pytest.raises(SimulationReached):
        main(argv)
    assert (Path(t) / "out" / "settings.json").is_file()
    return argv


def _compete_claimed(t):
    from jtire.cli import main

    argv = ["compete", _comp(t, "", ""), "--objective", "standin", *_out(t)]
    with pytest.raises(SimulationReached):
        main(argv)
    assert (Path(t) / "out" / "standin" / "competition.json").is_file()
    return argv


def _compete_foreign_history(t):
    """A competition folder whose ARSM history holds another point than this config asks for."""
    import json

    argv = _compete_claimed(t)
    hist = Path(t) / "out" / "standin" / "histories" / "arsm_seed000.jsonl"
    hist.parent.mkdir(parents=True, exist_ok=True)
    hist.write_text(json.dumps({"method": "arsm", "seed": 0, "call": 0, "x": [1.0, 1.0], "f": 1.0}) + "\n")
    return argv


def test_the_table_is_large_and_covers_every_subcommand():
    assert len(CASES) >= 60
    names = {"-".join(c.name.split("-")[:2]) if c.name.startswith("export-") else c.name.split("-")[0] for c in CASES}
    for sub in SUBCOMMANDS:
        assert sub in names, f"no bad-input case for `jtire {sub}`"


@pytest.mark.parametrize("case", [c.param() for c in CASES])
def test_bad_input_is_one_line_exit_2_before_any_simulation(case, tmp_path, trapped, capsys):
    from jtire.cli import main

    argv = case.argv(tmp_path)
    command = argv[0] if argv and argv[0] in SUBCOMMANDS else None
    if command is not None and command not in _available():
        pytest.skip(f"`jtire {command}` is not registered in this build (its module is missing)")
    capsys.readouterr()  # drop what building the inputs printed
    t0 = time.perf_counter()
    try:
        rc = main(argv)
    except SystemExit as e:  # argparse
        rc = e.code
    except SimulationReached:
        pytest.fail(f"{case.name}: a simulation started before the bad input was refused")
    wall = time.perf_counter() - t0
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    prefix = f"jtire {command}: error: " if command else "jtire: error: "
    assert rc == 2, (rc, err)
    assert "Traceback" not in err
    assert len(lines) == 1, err
    assert lines[0].startswith(prefix), lines[0]
    for words in case.words:
        assert words in lines[0], f"{words!r} not in {lines[0]!r}"
    assert wall < CASE_SECONDS, f"{case.name}: {wall:.1f} s"


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

