"""Typed config fields and table validation: the one place a config value is checked and converted.

A `Field` declares a value's type, its unit factor to SI, its allowed range in the file's unit and
its default. `validate(raw, schema, prefix)` checks a whole table against a schema (nested dicts of
Fields): an unknown key, a wrong type, a value out of range or a missing field is a `ConfigError`
naming the dotted field and what is allowed, in one line. Booleans are never numbers (TOML `true` is
not 1), and numbers are never booleans. Experiment modules declare their own tables with Fields;
`jtire.config` assembles whole configs from them.
"""

import dataclasses
import math

from .errors import ConfigError


@dataclasses.dataclass(frozen=True)
class Field:
    """A field: python type (float, int, bool, str, list = list of numbers), SI factor, allowed range
    in the file's unit, default (None = required), unit text, and for str the allowed choices."""

    type: type
    factor: float = 1.0
    lo: float = -math.inf
    hi: float = math.inf
    default: object = None
    unit: str = ""
    choices: tuple = ()
    min_len: int = 1

    def parse(self, path, value):
        if self.type is list:
            if (not isinstance(value, list) or len(value) < self.min_len
                    or not all(_is_number(v) for v in value)):
                raise ConfigError(f"{path} = {_show(value)}: must be a list of at least {self.min_len} "
                                  f"number{'s' if self.min_len > 1 else ''}{self._range()}")
            for v in value:
                self._check_range(path, float(v))
            return tuple(float(v) * self.factor for v in value)
        if self.type is float:
            if not _is_number(value):
                raise ConfigError(f"{path} = {_show(value)}: must be a number{self._range()}")
            self._check_range(path, float(value))
            return float(value) * self.factor
        if self.type is int:
            if not isinstance(value, int) or isinstance(value, bool):
                raise ConfigError(f"{path} = {_show(value)}: must be an integer{self._range()}")
            self._check_range(path, float(value))
            return value
        if self.type is bool:
            if not isinstance(value, bool):
                raise ConfigError(f"{path} = {_show(value)}: must be true or false")
            return value
        if self.type is str:
            if not isinstance(value, str):
                raise ConfigError(f"{path} = {_show(value)}: must be a string"
                                  + (f", one of {', '.join(self.choices)}" if self.choices else ""))
            if self.choices and value not in self.choices:
                raise ConfigError(f"{path} = {value!r}: must be one of {', '.join(self.choices)}")
            return value
        raise TypeError(f"Field type {self.type!r} is not supported")

    def _check_range(self, path, v):
        if not (self.lo <= v <= self.hi) or math.isnan(v):
            raise ConfigError(f"{path} = {v:g}: must be in [{self.lo:g}, {self.hi:g}]{' ' + self.unit if self.unit else ''}")

    def _range(self):
        if self.lo > -math.inf or self.hi < math.inf:
            return f" in [{self.lo:g}, {self.hi:g}]{' ' + self.unit if self.unit else ''}"
        return f" ({self.unit})" if self.unit else ""


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _show(v) -> str:
    s = repr(v)
    return s if len(s) <= 60 else s[:57] + "..."


def validate(raw, schema: dict, prefix: str = "") -> dict:
    """Check `raw` (a parsed TOML table) against `schema`; returns the values in SI.

    Nested schema dicts are sub-tables (a sub-table may be omitted when all its fields have
    defaults). Defaults are written in the file's units too.
    """
    where = prefix.rstrip(".") or "config"
    if not isinstance(raw, dict):
        raise ConfigError(f"{where}: must be a table (got {_show(raw)})")
    for key in raw:
        if key not in schema:
            allowed = ", ".join(sorted(schema)) or "none"
            raise ConfigError(f"{prefix}{key}: unknown field (allowed here: {allowed})")
    out = {}
    for key, sub in schema.items():
        path = prefix + key
        if isinstance(sub, dict):
            if key not in raw:
                if all(isinstance(f, Field) and f.default is not None for f in sub.values()):
                    out[key] = validate({}, sub, path + ".")
                    continue
                raise ConfigError(f"{path}: missing table")
            out[key] = validate(raw[key], sub, path + ".")
        elif key in raw:
            out[key] = sub.parse(path, raw[key])
        elif sub.default is not None:
            out[key] = sub.parse(path, sub.default)
        else:
            raise ConfigError(f"{path}: missing field{sub._range()}")
    return out


def check_range_pair(path: str, pair, unit: str = "", scale: float = 1.0):
    """A [lo, hi] pair with lo < hi (values in SI; `scale` turns them back into the file's unit)."""
    if len(pair) != 2 or not pair[0] < pair[1]:
        shown = [round(v / scale, 10) for v in pair]
        raise ConfigError(f"{path} = {shown}: must be [lo, hi] with lo < hi{' ' + unit if unit else ''}")
    return tuple(pair)
