"""Output folders that carry the settings of their results (jtire.fingerprint), and where the
persistent compilation cache lives (jtire.cache). No simulation."""

import json

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
