"""The bad-input harness of the tests/test_bad_inputs*.py files: the cases' input builders, the trap
on every simulation entry point, and the one check every case goes through (see test_bad_inputs.py).
"""

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



def trap_simulations(monkeypatch):
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
        import jtire.calibration.tire.run as tc

        monkeypatch.setattr(tc, "calibrate_arsm", _trap)
        monkeypatch.setattr(tc, "calibrate_lm", _trap)
    if "sample" in _available():
        import jtire.calibration.posterior.run as sampling

        monkeypatch.setattr(sampling, "fit_emulator", _trap)
        monkeypatch.setattr(sampling, "run_sampler", _trap)
    if "export-tir" in _available():
        import jtire.rigid_ring.export as export

        monkeypatch.setattr(export, "export", _trap)


class Case:
    """argv(tmp) -> list of arguments (the inputs written under tmp); words: in the error line."""

    def __init__(self, name, argv, *words):
        self.name, self.argv, self.words = name, argv, words
        self.command = None  # set from the first argument when run

    def param(self):
        return pytest.param(self, id=self.name)


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


def check_one_line(case, tmp_path, monkeypatch, capsys):
    """Run one case through `jtire.cli.main` with the simulations trapped: exit code 2, exactly one
    error line holding the case's words, no traceback, refused before any simulation and within
    CASE_SECONDS."""
    from jtire.cli import main

    trap_simulations(monkeypatch)
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
