"""Every long job is safe to kill: SIGKILL at a random point, rerun, and the final files are the
ones an uninterrupted run writes, with nothing finished computed twice.

For `jtire compete --quick` (stand-in objective), `jtire calibrate --standin` and `jtire sample
--check --standin` (no shell model needed), and `jtire sweep` and `jtire characterize` (the shell model on
the coarse ring, its static experiments: E01, E02 and E09's static part, solved case by case, so a kill
can land between the cases of one experiment): a reference run goes uninterrupted; another run into
a fresh folder is killed (SIGKILL, the signal nobody can catch) at a seeded random point that lands
mid-run -- after a random number of finished records (or progress lines), plus a random delay --
then rerun to the end. Checks:

- every result file is byte-identical to the reference, except the recorded wall times (removed
  before comparing: their values are timings, not results; a case's result.json is compared without
  its `wall_s_per_case_in_batch`, everything else in it byte for byte as JSON values) and the HDF5 chain, whose arrays (chain,
  log-probabilities, acceptance counts, random state) are compared instead of its bytes (HDF5's
  layout depends on the order its writes happened in);
- histories have no duplicate record: every call/evaluation index appears once, in order; and the
  resumed run computed only what the killed runs had not finished.

Quick versions (one kill each) of compete and calibrate run in the fast suite; sample's (~60 s) and
characterize's (~95 s) are slow checks (the chain's exact resume is also tested in-process by
tests/test_posterior.py, the check's by tests/test_calibration_cli.py); the soaks (10 kills in a row
into one folder, each resumed run killed again, then one run to the end) are slow too.
"""

import json
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from .conftest import COARSE_SET, REPO, SOLVER_SET

CAL = REPO / "configs" / "calibration"
ENTRY = ["-c", "import sys; from jtire.cli import main; sys.exit(main())"]
TIMEOUT = 600  # s: an uninterrupted run takes 5-40 s here; a hung one fails the test
# wall times are recorded for the user, not results: removed before comparing records and files
WALL_KEYS = {"wall_s", "batch_wall_s", "simulator_wall_s", "wall_s_per_case_in_batch"}
SAMPLE_STEPS = 2000
QUICK = [a for s in COARSE_SET + SOLVER_SET for a in ("--set", s)]
# 2 loads x 2 pressures of the 3 static experiments: 12 cases, about 1-2 s each after the (cached) compile, each
# saved as it finishes (static solves run case by case): the soak's 10 kills each land between two of them
GRID = ["--set", "grid.loads_kg=[2312.5, 4625.0]", "--set", "grid.pressures_psi=[70.0, 120.0]",
        "--set", "grid.rated_load_kg=4625.0", "--set", "grid.rated_pressure_psi=120.0"]
STATIC = ["--set", 'experiments=["footprint", "vertical_stiffness", "lateral_stiffness"]',
          "--set", "lateral_stiffness.decay_s=0.0"]


def _argv(kind, out, history=None):
    if kind == "compete":
        return ["compete", str(CAL / "soil_competition.toml"), "--quick", "--objective", "standin",
                "--out", str(out)]
    if kind == "calibrate":
        return ["calibrate", str(CAL / "study.toml"), "--standin", "--out", str(out)]
    if kind == "characterize":
        return ["characterize", str(REPO / "configs" / "characterize.toml"), *STATIC, *GRID, *QUICK, "--no-validate",
                "--out", str(out)]
    if kind == "sweep":
        return ["sweep", str(REPO / "configs" / "experiments" / "vertical_stiffness.toml"), *QUICK,
                # 12 cases: the soak's 10 kills each land between two of them
                "--set", "sweep.loads_kg=[2312.5, 3500.0, 4625.0, 5500.0]", "--set", "sweep.pressures_psi=[70.0, 120.0, 150.0]",
                "--out", str(out)]
    # a short chain (2000 steps in chunks of 50) on the linear emulator: ~1 min
    return ["sample", str(CAL / "posterior.toml"), "--history", str(history), "--standin", "--check",
            "--out", str(out), "--set", f"sampler.max_steps={SAMPLE_STEPS}", "--set", "sampler.check_every=50",
            "--set", "sampler.walkers=40", "--set", 'emulator.candidates=["linear"]']


def _start(argv, log):
    env = dict(os.environ, PYTHONWARNINGS="ignore", MPLBACKEND="Agg")
    f = open(log, "ab")
    return subprocess.Popen([sys.executable, *ENTRY, *argv], stdout=f, stderr=f, env=env), f


def _run(argv, log):
    p, f = _start(argv, log)
    try:
        rc = p.wait(timeout=TIMEOUT)
    finally:
        f.close()
    return rc


def _complete_lines(path) -> int:
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        return 0
    return data.count(b"\n")


def _progress(kind, out, log):
    """Finished units so far: history records (compete, calibrate) or chain chunks reported on
    stderr by this process (sample: its HDF5 file is not read while being written)."""
    if kind == "compete":
        return sum(_complete_lines(p) for p in (Path(out) / "standin" / "histories").glob("*.jsonl"))
    if kind == "calibrate":
        return _complete_lines(Path(out) / "history.jsonl")
    if kind in ("characterize", "sweep"):  # finished cases (a case folder's result.json is written last)
        return len(list(Path(out).glob("**/cases/*/result.json")))
    if not (Path(out) / "fingerprint.json").exists():
        return -1  # not started: the emulator is fitted right after the fingerprint is written
    return Path(log).read_text(errors="replace").count(" steps, max tau")


def _printed_steps(log) -> int:
    """The last chain length a sample run reported (0 if none)."""
    steps = [int(ln.split()[0]) for ln in Path(log).read_text(errors="replace").splitlines()
             if ln.endswith(tuple("0123456789")) and " steps, max tau" in ln]
    return max(steps, default=0)


def _kill_at(kind, argv, out, log, target, delay):
    """Start the command, wait until `target` units are finished (None: no wait), sleep `delay`
    s, SIGKILL. Returns True when it was killed before it finished."""
    Path(log).write_text("")
    p, f = _start(argv, log)
    try:
        t0 = time.monotonic()
        while p.poll() is None and target is not None and _progress(kind, out, log) < target:
            if time.monotonic() - t0 > TIMEOUT:
                raise TimeoutError(f"{kind}: no progress to {target} in {TIMEOUT} s")
            time.sleep(0.002)
        time.sleep(delay)
        if p.poll() is not None:
            return False
        p.send_signal(signal.SIGKILL)
        p.wait()
        return True
    finally:
        f.close()


def _records(path) -> list:
    out = []
    for line in Path(path).read_text().splitlines():
        r = json.loads(line)
        out.append({k: v for k, v in r.items() if k not in WALL_KEYS})
    return out


def _strip_walls(x):
    if isinstance(x, dict):
        return {k: _strip_walls(v) for k, v in x.items() if k not in WALL_KEYS}
    if isinstance(x, list):
        return [_strip_walls(v) for v in x]
    return x


def _chain(path) -> dict:
    import h5py

    with h5py.File(path, "r") as f:
        g = f["mcmc"]
        return {"chain": g["chain"][...], "log_prob": g["log_prob"][...], "accepted": g["accepted"][...],
                "iteration": int(g.attrs["iteration"]),
                "random_state": [np.asarray(v) for k, v in sorted(g.attrs.items()) if k.startswith("random_state_")]}


def _result_dir(kind, out):
    return Path(out) / "standin" if kind == "compete" else Path(out)


def assert_same_results(kind, ref, got):
    """Every file of the reference folder, in the resumed folder, the same (see module docstring)."""
    ref, got = _result_dir(kind, ref), _result_dir(kind, got)
    ref_files = sorted(p.relative_to(ref) for p in ref.rglob("*") if p.is_file())
    got_files = sorted(p.relative_to(got) for p in got.rglob("*") if p.is_file())
    assert got_files == ref_files  # and no temp file left behind
    for rel in ref_files:
        a, b = ref / rel, got / rel
        if rel.suffix == ".jsonl":
            ra, rb = _records(a), _records(b)
            # no duplicate: each call / evaluation once, in order
            key = "call" if kind == "compete" else "i" if rel.name == "check_runs.jsonl" else "eval"
            assert [r[key] for r in rb] == list(range(len(rb))), rel
            if kind == "calibrate":  # how the points were batched is bookkeeping: a resumed batch is smaller
                skip = ("batch", "batch_size", "piece")
                ra = [{k: v for k, v in r.items() if k not in skip} for r in ra]
                rb = [{k: v for k, v in r.items() if k not in skip} for r in rb]
            assert rb == ra, rel
        elif rel.suffix == ".h5":
            ca, cb = _chain(a), _chain(b)
            assert cb["iteration"] == ca["iteration"]
            for k in ("chain", "log_prob", "accepted"):
                np.testing.assert_array_equal(cb[k], ca[k], err_msg=k)
            assert all(np.array_equal(x, y) for x, y in zip(ca["random_state"], cb["random_state"]))
        elif rel.name == "result.json" and kind in ("characterize", "sweep"):
            assert _strip_walls(json.loads(b.read_text())) == _strip_walls(json.loads(a.read_text())), rel
        elif rel.name == "summary.json" and kind == "calibrate":
            assert _strip_walls(json.loads(b.read_text())) == _strip_walls(json.loads(a.read_text()))
        else:
            assert b.read_bytes() == a.read_bytes(), rel


@pytest.fixture(scope="module")
def calibration_history(tmp_path_factory):
    """A stand-in calibration folder: the sampler's emulator is trained on its history."""
    out = tmp_path_factory.mktemp("cal_for_sample")
    assert _run(_argv("calibrate", out), out / "log.txt") == 0
    return out


@pytest.fixture(scope="module")
def references(tmp_path_factory, calibration_history):
    """Uninterrupted runs, built on first use: kind -> (folder, units of work it finished)."""
    cache = {}

    def get(kind):
        if kind not in cache:
            out = tmp_path_factory.mktemp(f"ref_{kind}")
            log = out.parent / f"ref_{kind}.log"
            t0 = time.monotonic()
            rc = _run(_argv(kind, out / "o", calibration_history), log)
            wall = time.monotonic() - t0
            assert rc == (1 if kind == "sample" else 0), log.read_text()[-2000:]  # sample: 1 = not converged
            cache[kind] = (out / "o", _progress(kind, out / "o", log), wall)
        return cache[kind]

    return get


def _kills(kind, references, calibration_history, tmp_path, n_kills, seed):
    ref, total, wall = references(kind)
    rng = random.Random(seed)
    out, log = tmp_path / "o", tmp_path / "log.txt"
    argv = _argv(kind, out, calibration_history)
    killed, saved_steps = 0, 0
    for k in range(n_kills):
        if kind == "sample":  # chunks reported by this process (0: emulator fit or first chunk)
            target, delay = rng.randint(0, 1), rng.uniform(0.0, 0.5)
        else:  # finished records of all runs so far: the kills spread over the rest
            done = _progress(kind, out, log)
            step = max(1, (total - done) // (n_kills - k))
            target, delay = min(total, done + rng.randint(1, step)), rng.uniform(0.0, 0.05)
            if done >= total:  # every record done: kill while the outputs are written, late in a
                # run as long as the reference (startup and replay come first)
                target, delay = None, rng.uniform(0.75, 1.0) * wall
        killed += _kill_at(kind, argv, out, log, target, delay)
        if kind == "sample":  # the chain length the killed run had reported saved
            saved_steps = max(saved_steps, _printed_steps(log))
    done_before = _progress(kind, out, log)
    Path(log).write_text("")
    rc = _run(argv, log)
    assert rc == (1 if kind == "sample" else 0), Path(log).read_text()[-2000:]
    if kind == "sample":
        # the resumed run says how many steps it ran itself: none of those reported saved before
        # (the first chain's report: "(N new; ..."; a refined round, if any, reports its own after it)
        new = int(re.search(r"\((\d+) new\b", Path(log).read_text()).group(1))
        assert new <= SAMPLE_STEPS - saved_steps, (new, saved_steps)
    elif kind in ("characterize", "sweep"):  # the cases the killed runs finished were not run again
        assert _progress(kind, out, log) == total
        if done_before:
            assert f"{done_before} of {total} cases already done" in Path(log).read_text(), Path(log).read_text()[-2000:]
    else:  # each record once: those finished before the kill were replayed, not redone
        assert _progress(kind, out, log) == total
    assert_same_results(kind, ref, out)
    return killed


# (the quick kill of `jtire sweep` is tests/test_sweep.py's; its soak is here)
# sample's quick kill (~60 s) and characterize's (~95 s: a reference run and a killed one on the shell
# model) are slow, to keep the fast suite under 15 minutes; the soaks below cover them with ten kills
@pytest.mark.parametrize("kind,seed", [("compete", 11), ("calibrate", 12),
                                       pytest.param("sample", 13, marks=pytest.mark.slow),
                                       pytest.param("characterize", 14, marks=pytest.mark.slow)])
def test_one_kill_then_resume_gives_the_uninterrupted_files(kind, seed, references, calibration_history, tmp_path):
    killed = _kills(kind, references, calibration_history, tmp_path, 1, seed)
    assert killed == 1, "the kill landed after the run had finished: it tested nothing"


@pytest.mark.slow
@pytest.mark.parametrize("kind,seed", [("compete", 21), ("calibrate", 22), ("sample", 23), ("characterize", 24),
                                       ("sweep", 25)])
def test_ten_kills_in_a_row_then_resume(kind, seed, references, calibration_history, tmp_path):
    killed = _kills(kind, references, calibration_history, tmp_path, 10, seed)
    assert killed >= 8, f"only {killed} of 10 kills landed mid-run"
