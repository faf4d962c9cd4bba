"""Result files: atomic writes keep the user's umask; torn JSON-lines tails are cut."""

import os
import stat

import pytest

from jtire.io import append_jsonl, atomic_write_bytes, atomic_write_json, atomic_write_text, read_jsonl


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_atomic_write_honours_the_umask(tmp_path, mask):
    # a plain open() makes 0666 & ~umask; mkstemp alone would give 0600 whatever the umask
    old = os.umask(mask)
    try:
        atomic_write_text(tmp_path / "a.txt", "x")
        atomic_write_json(tmp_path / "sub" / "b.json", {"a": 1})
        with open(tmp_path / "plain.txt", "w") as f:
            f.write("x")
    finally:
        os.umask(old)
    want = stat.S_IMODE((tmp_path / "plain.txt").stat().st_mode)
    assert want == 0o666 & ~mask
    for p in (tmp_path / "a.txt", tmp_path / "sub" / "b.json"):
        assert stat.S_IMODE(p.stat().st_mode) == want, p
    assert not [p for p in tmp_path.rglob(".*.tmp")]  # no temp file left behind


def test_atomic_write_replaces_and_keeps_no_temp_on_error(tmp_path):
    p = tmp_path / "r.txt"
    atomic_write_text(p, "old")
    atomic_write_text(p, "new")
    assert p.read_text() == "new"
    with pytest.raises(TypeError):
        atomic_write_bytes(p, "not bytes")  # fails after the temp file is made, before the replace
    assert p.read_text() == "new" and not list(tmp_path.glob(".*.tmp"))


def test_torn_jsonl_tail_is_cut_before_append(tmp_path):
    p = tmp_path / "h.jsonl"
    append_jsonl(p, {"i": 0})
    with open(p, "a") as f:
        f.write('{"i": 1, "x"')  # a kill in the middle of an append
    assert read_jsonl(p) == [{"i": 0}]
    append_jsonl(p, {"i": 2})
    assert read_jsonl(p) == [{"i": 0}, {"i": 2}]
