"""Write a calibrated tire: the input tire TOML with the calibrated values substituted.

The file is edited line by line, not re-serialized: every comment, blank line and key order
stays as the user wrote it; only the value of each calibrated key changes (in the file's unit:
MPa, mm, or none), with a trailing note of the old value. The result is parsed back and checked
to hold exactly the new values (and to be a valid tire), so every command can take it.
"""

import re
import tomllib

from ...config import tire_from_dict
from ...errors import ConfigError
from ...io import atomic_write_text

__all__ = ["substitute", "write_calibrated_tire"]

_HEADER = re.compile(r"^\s*\[([A-Za-z0-9_.]+)\]\s*(#.*)?$")
_KEY = re.compile(r"^(\s*)([A-Za-z0-9_]+)(\s*=\s*)([^#\n]*?)(\s*)(#.*)?$")


def _fmt(v: float) -> str:
    return f"{v:.6g}" if "e" not in f"{v:.6g}" else repr(float(v))


def substitute(text: str, values, note: str = "calibrated") -> str:
    """text with each (table, key, value) of `values` replaced in place (comments kept).

    values: iterable of (table, key, value, unit) as from ParamSpace.file_values. A key that is
    not found in its table is a ConfigError (the tire file does not hold that parameter).
    """
    want = {(t, k): v for t, k, v, _ in values}
    done = set()
    table = ""
    out = []
    for line in text.splitlines(keepends=True):
        body = line.rstrip("\n")
        h = _HEADER.match(body)
        if h:
            table = h.group(1)
        else:
            m = _KEY.match(body)
            if m and (table, m.group(2)) in want:
                v = want[(table, m.group(2))]
                old = m.group(4).strip()
                comment = (m.group(6) or "").lstrip("# ").strip()
                tail = f"  # {note} (was {old})" + (f"; {comment}" if comment else "")
                body = f"{m.group(1)}{m.group(2)}{m.group(3)}{_fmt(v)}{tail}"
                done.add((table, m.group(2)))
                line = body + ("\n" if line.endswith("\n") else "")
        out.append(line)
    missing = [f"{t}.{k}" for t, k in want if (t, k) not in done]
    if missing:
        raise ConfigError(f"tire file: no key {', '.join(missing)} to calibrate (the tire TOML "
                          "must list every calibrated parameter)")
    return "".join(out)


def write_calibrated_tire(path, tire_text: str, space, theta, header: str = "") -> tuple:
    """Write the calibrated tire TOML; returns (path, TireSpec parsed back from it).

    header: comment lines put at the top (what produced the file). The values are checked to
    round-trip to 6 significant digits.
    """
    values = space.file_values(theta)
    text = substitute(tire_text, values)
    if header:
        text = "".join(f"# {h}\n" for h in header.splitlines()) + text
    raw = tomllib.loads(text)
    for table, key, v, _ in values:
        d = raw
        for part in table.split("."):
            d = d[part]
        if abs(d[key] - v) > 1e-5 * abs(v):
            raise RuntimeError(f"calibrated tire: {table}.{key} reads back {d[key]}, not {v}")
    spec = tire_from_dict(raw)
    return atomic_write_text(path, text), spec
