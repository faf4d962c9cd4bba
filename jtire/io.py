"""Result files written atomically (temp file in the same folder, then os.replace).

A reader (or a run killed half way) never sees a half-written file. Append-only histories
(JSON lines) are flushed and fsynced per record, and readers ignore a torn last line.
"""

import csv
import io
import json
import os
import tempfile
from pathlib import Path


def current_umask() -> int:
    """The process's file-creation mask (read without changing it where /proc allows)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)  # elsewhere: the only portable way to read it is to set it
    os.umask(mask)
    return mask


def atomic_write_bytes(path, data: bytes) -> Path:
    """Write `data` to `path` atomically, with the permissions a plain open() would give it
    (0666 less the umask; mkstemp alone would make every result file private, 0600)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o666 & ~current_umask())
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_write_text(path, text: str) -> Path:
    return atomic_write_bytes(path, text.encode())


def remove_stale_temps(folder) -> int:
    """Delete the temporary files (`.NAME.XXXXXXXX.tmp`, as `atomic_write_bytes` names them) that a
    process killed in the middle of a write left anywhere under `folder`. Called when a job resumes
    into its folder (one job per folder at a time). Returns how many were removed."""
    n = 0
    for p in Path(folder).rglob(".*.tmp"):
        if p.is_file():
            p.unlink(missing_ok=True)
            n += 1
    return n


def atomic_savefig(fig, path, dpi: int = 120) -> Path:
    """Save a matplotlib figure atomically (format from the suffix, e.g. .png) and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)
    return atomic_write_bytes(path, buf.getvalue())


def _jsonable(x):
    import numpy as np

    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if hasattr(x, "tolist"):  # numpy / jax arrays and scalars
        return _jsonable(np.asarray(x).tolist())
    if isinstance(x, float) and not (x == x and abs(x) != float("inf")):
        return None  # JSON has no NaN/inf; None marks "not available"
    return x


def atomic_write_json(path, obj) -> Path:
    return atomic_write_text(path, json.dumps(_jsonable(obj), indent=2) + "\n")


def atomic_write_csv(path, header, rows) -> Path:
    """rows: iterable of sequences, or a dict of equal-length columns (then header may be None)."""
    if isinstance(rows, dict):
        header = list(rows.keys()) if header is None else header
        cols = [list(map(_jsonable, rows[h])) for h in header]
        rows = list(zip(*cols))
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow(_jsonable(list(r)))
    return atomic_write_text(path, buf.getvalue())


def drop_torn_tail(path) -> None:
    """Cut a JSON-lines file back to its last complete line: a kill during an append leaves a torn
    last line, and the next append would glue onto it (making both unreadable)."""
    path = Path(path)
    if not path.exists():
        return
    data = path.read_bytes()
    if data and not data.endswith(b"\n"):
        with open(path, "r+b") as f:
            f.truncate(data.rfind(b"\n") + 1)
            f.flush()
            os.fsync(f.fileno())


def append_jsonl(path, record: dict) -> None:
    """Append one record and fsync, so a completed record survives a kill at any moment (a torn
    line left by an earlier kill is cut off first)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    drop_torn_tail(path)
    with open(path, "a") as f:
        f.write(json.dumps(_jsonable(record)) + "\n")
        f.flush()
        os.fsync(f.fileno())


def read_jsonl(path) -> list:
    """Read complete records; a torn last line (killed mid-write) is dropped."""
    path = Path(path)
    if not path.exists():
        return []
    out = []
    for line in path.read_text().splitlines():
        try:
            out.append(json.loads(line))
        except json.JSONDecodeError:
            break
    return out


def check_writable(folder) -> Path:
    """Make `folder` (and its parents) and check a file can be written there, before any work is
    done; an OSError (reported by the CLI as one line) otherwise."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".write-check.", suffix=".tmp")
    os.close(fd)
    os.unlink(tmp)
    return folder
