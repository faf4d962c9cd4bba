"""Fingerprints of the settings that determine a long job's numbers, and output folders that carry them.

Every long job (sweep, characterize, calibrate, sample, compete) writes its settings into its output
folder before it starts. A rerun into the same folder resumes only when its settings are the same;
otherwise it refuses with one line naming what differs (use another folder), so finished work from
one set of settings is never mixed with another's.
"""

import dataclasses
import functools
import json
from pathlib import Path

import numpy as np

from .errors import ConfigError
from .io import atomic_write_json, remove_stale_temps


def plain(x):
    """JSON-able form of settings: dataclasses, eqx Modules, arrays, tuples -> dicts, floats, lists."""
    import equinox as eqx

    if isinstance(x, eqx.Module) or dataclasses.is_dataclass(x):
        return {f.name: plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, dict):
        return {str(k): plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [plain(v) for v in x]
    if isinstance(x, Path):
        return str(x)
    if hasattr(x, "shape"):
        a = np.asarray(x)
        return a.tolist() if a.ndim else a.item()
    return x


@functools.cache
def code_version() -> str:
    """The installed jtire's version and a hash of its Python sources ("0.1.0+1a2b3c4d5e6f"): two builds
    with any source file apart give two versions, so a folder made by one is not resumed by the other.
    The same sources give the same hash installed as a wheel or in place (files keyed by module path)."""
    import hashlib
    import importlib.util
    from importlib.metadata import PackageNotFoundError, version

    try:
        v = version("jtire")
    except PackageNotFoundError:
        v = "unknown"
    files = {}
    for pkg in ("jtire", "jtire.calibration", "jtire.surrogates"):
        spec = importlib.util.find_spec(pkg)
        for root in (spec.submodule_search_locations or []) if spec else []:
            for f in Path(root).rglob("*.py"):
                if "__pycache__" not in f.parts:
                    files[pkg.replace(".", "/") + "/" + f.relative_to(root).as_posix()] = f
    h = hashlib.sha256()
    for key in sorted(files):
        h.update(key.encode() + b"\0" + files[key].read_bytes() + b"\0")
    return f"{v}+{h.hexdigest()[:12]}"


def _diff(a, b, prefix=""):
    if isinstance(a, dict) and isinstance(b, dict):
        out = []
        for k in sorted(set(a) | set(b)):
            out += _diff(a.get(k), b.get(k), f"{prefix}{k}.")
        return out
    return [] if a == b else [prefix.rstrip(".")]


def claim_folder(folder, settings: dict, name: str = "settings.json") -> bool:
    """Write `settings` into folder/name, or check that the folder's are the same.

    Returns True when the folder already held these settings (a resume: the temporary files of a
    write that a kill interrupted are removed). Raises ConfigError naming the differing fields when
    it holds other settings.
    """
    folder = Path(folder)
    path = folder / name
    settings = json.loads(json.dumps(plain(settings)))  # the form it has once read back
    if path.exists():
        try:
            old = json.loads(path.read_text())
        except (OSError, ValueError, UnicodeDecodeError):
            raise ConfigError(f"{path}: unreadable settings file; use another output folder") from None
        if old != settings:
            keys = _diff(old, settings)
            shown = ", ".join(keys[:6]) + (f" and {len(keys) - 6} more" if len(keys) > 6 else "")
            raise ConfigError(f"{folder}: holds results made with other settings (differs in {shown}); "
                              f"use another output folder")
        remove_stale_temps(folder)
        return True
    atomic_write_json(path, settings)
    return False
