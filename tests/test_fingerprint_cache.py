"""Output folders that carry the settings of their results (jtire.fingerprint), and where the
persistent compilation cache lives (jtire.cache). No simulation."""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from jtire import cache
from jtire.errors import ConfigError
from jtire.fingerprint import claim_folder, plain


def test_plain_settings_are_json(coarse_tire, protocol):
    from jtire.experiments import REGISTRY

    exp = REGISTRY["footprint"](proto=protocol)
    d = plain({"exp": exp, "tire": coarse_tire.spec, "t": (1, 2.0), "a": np.arange(3.0)})
    assert json.loads(json.dumps(d)) == d
    assert d["exp"]["proto"]["load_ramp"] == pytest.approx(float(protocol.load_ramp))
    assert d["tire"]["n_theta"] == 32 and d["a"] == [0.0, 1.0, 2.0] and d["t"] == [1, 2.0]


def test_claim_folder_resumes_same_and_refuses_other_settings(tmp_path):
    s = {"solver": {"ke_tol": 1e-3, "load_ramp": 0.05}, "conditions": [{"load_N": 1.0}], "jtire": "0.1.0"}
    assert claim_folder(tmp_path, s) is False  # a new folder: claimed
    assert claim_folder(tmp_path, json.loads(json.dumps(s))) is True  # the same settings: a resume
    other = dict(s, solver={"ke_tol": 2e-3, "load_ramp": 0.05})
    with pytest.raises(ConfigError, match=r"differs in solver\.ke_tol\); use another output folder"):
        claim_folder(tmp_path, other)
    # the refusal never rewrites the folder's settings
    assert json.loads((tmp_path / "settings.json").read_text())["solver"]["ke_tol"] == 1e-3
    (tmp_path / "settings.json").write_text("{torn")
    with pytest.raises(ConfigError, match="unreadable settings file"):
        claim_folder(tmp_path, s)


def test_resume_removes_the_temporary_files_a_kill_left(tmp_path):
    """A kill between mkstemp and the rename leaves `.NAME.XXXXXXXX.tmp`: the resume removes those (and
    only those), so the finished folder is the uninterrupted run's; a refused rerun touches nothing."""
    s = {"jtire": "0.1.0"}
    claim_folder(tmp_path, s)
    case = tmp_path / "cases" / "000_p120psi"
    case.mkdir(parents=True)
    (case / ".result.json.k3j2x9_a.tmp").write_text('{"quanti')
    (case / "signals.csv").write_text("t\n0\n")
    (tmp_path / ".hidden_user_file").write_text("mine")
    with pytest.raises(ConfigError):
        claim_folder(tmp_path, {"jtire": "0.2.0"})
    assert (case / ".result.json.k3j2x9_a.tmp").exists()
    assert claim_folder(tmp_path, s) is True
    assert sorted(p.name for p in case.iterdir()) == ["signals.csv"]
    assert (tmp_path / ".hidden_user_file").read_text() == "mine"


def test_cache_folder_rules(monkeypatch, tmp_path):
    monkeypatch.setenv("JTIRE_CACHE_DIR", str(tmp_path / "c"))
    assert cache.cache_dir() == tmp_path / "c"
    for off in ("off", "0", "none", ""):
        monkeypatch.setenv("JTIRE_CACHE_DIR", off)
        assert cache.cache_dir() is None and cache.enable() is None
    monkeypatch.delenv("JTIRE_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    d = cache.cache_dir()
    # keyed by machine: programs compiled for one CPU and JAX version are never loaded on another
    assert d.parent == tmp_path / "xdg" / "jtire" and d.name == cache.machine_key()
    import jax

    assert jax.__version__ in d.name


_CROWDED = r"""
import jax, jax.numpy as jnp
from jax import lax
from jtire import cache

def make(k):
    def f(x):
        for i in range(40):  # cumsum kernels: each its own code, in memory maps of its own
            x = lax.optimization_barrier(jnp.cumsum(jnp.sin(x * (i + k)))[::-1] * 1e-2)
        return x
    return jax.jit(f)

x = jnp.ones(16)
fs = [make(k) for k in range(4)]
first = [float(f(x)[0]) for f in fs]
n0 = cache.map_count()
assert not cache.release_programs_if_crowded(fraction=(n0 + 1000) / cache.map_limit())  # not crowded
assert cache.release_programs_if_crowded(fraction=(n0 - 1) / cache.map_limit())  # crowded: cleared
n1 = cache.map_count()
again = [float(f(x)[0]) for f in fs]  # the same functions run again (compiled anew), same numbers
print(n0, n1, cache.clears(), first == again)
"""


@pytest.mark.skipif(cache.map_count() is None or cache.map_limit() is None, reason="no /proc maps to count")
def test_programs_are_dropped_when_the_maps_near_the_cap():
    """A process holding compiled programs past the share of vm.max_map_count drops them (each CPU
    program's kernels sit in memory maps of their own; past the cap XLA's loader segfaults), and the
    jitted functions still work. In a subprocess: clearing here would make the suite trace again."""
    import os
    import subprocess
    import sys

    env = dict(os.environ, JTIRE_CACHE_DIR="off")
    p = subprocess.run([sys.executable, "-c", _CROWDED], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]
    n0, n1, clears, same = p.stdout.split()
    # four 40-kernel programs hold several hundred maps; the clear frees nearly all of them
    assert int(n0) - int(n1) > 300, (n0, n1)
    assert clears == "1" and same == "True"


def test_code_version_hashes_the_sources(tmp_path, monkeypatch):
    """code_version is the package version plus a hash of every source file: editing one file (here a
    copy of the package on the import path with one comment added) gives another version."""
    import re
    import shutil
    import subprocess
    import sys

    from jtire.fingerprint import code_version

    v = code_version()
    assert re.fullmatch(r"\S+\+[0-9a-f]{12}", v), v
    import jtire

    src = Path(jtire.__file__).parent
    copy = tmp_path / "jtire"
    shutil.copytree(src, copy, ignore=shutil.ignore_patterns("__pycache__"))
    cmd = "from jtire.fingerprint import code_version; import jtire; print(jtire.__file__, code_version())"
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    same = subprocess.run([sys.executable, "-c", cmd], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert same.stdout.split()[0].startswith(str(copy)) and same.stdout.split()[1] == v, same.stderr[-2000:]
    (copy / "units.py").write_text((copy / "units.py").read_text() + "# an edit\n")
    edited = subprocess.run([sys.executable, "-c", cmd], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert edited.stdout.split()[1] != v, edited.stderr[-2000:]


def test_compile_clock_counts_making_a_program_not_running_it():
    """cache.CompileClock: a new program's trace, lowering and compile are counted (more than 0, and
    no more than the block's wall: a trace nested in another's counts once), the same call again
    makes nothing (0); the calibration charges a Jacobian its wall less this."""
    import time

    import jax
    import jax.numpy as jnp

    c0 = float(np.random.default_rng().random())  # a constant no earlier program holds: a fresh compile
    inner = jax.jit(lambda x: jnp.sin(x) * c0)
    f = jax.jit(lambda x: inner(x) + jnp.cos(inner(x)))
    x = jnp.arange(7.0)
    with cache.CompileClock() as first:
        t0 = time.perf_counter()
        f(x).block_until_ready()
        wall = time.perf_counter() - t0
    assert 0.0 < first.seconds <= wall + 1e-3
    with cache.CompileClock() as again:
        f(x).block_until_ready()
    assert again.seconds == 0.0
    assert not any(first._on == cb for cb in jax._src.monitoring._event_time_span_listeners)  # unregistered
