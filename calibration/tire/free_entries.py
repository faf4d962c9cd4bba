"""Checks of one [[free]] entry that need more than its own numbers: a bias entry against the
calibration's targets, a geometry entry's range against the mesh's rules for a section
(`ParamSpace.from_config` calls them)."""

import dataclasses
import math

from ...errors import ConfigError

_SI_UNIT = {"_N": "N", "_m": "m", "_N_per_m": "N/m", "": ""}


def is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_geometry_bounds(geometry, field, bounds, at, file_factor=1.0):
    """Both ends of a geometry parameter's range must give a section the mesh builds (each check
    is monotone in one field, so the ends decide the whole range)."""
    from ...config import _check_geometry

    for v in bounds:
        try:
            _check_geometry(dataclasses.replace(geometry, **{field: v}))
        except ConfigError as e:
            raise ConfigError(f"{at}: at {v / file_factor:g} the section is not valid: {e}") from None


def parse_bias(e, at, name, targets):
    """A bias entry's (lower, upper, target names, SI unit), checked against the targets."""
    from .targets import _quantity_suffix

    if "factor" in e:
        raise ConfigError(f"{at}.factor ({name}): a bias has no tire value to scale; give "
                          "bounds = [lo, hi] in its targets' SI unit")
    b = e.get("bounds")
    if not (isinstance(b, list) and len(b) == 2 and all(is_num(x) for x in b)):
        raise ConfigError(f"{at}.bounds = {b!r} ({name}): must be two numbers [lo, hi] in the SI "
                          "unit of its targets")
    if not 0 <= b[0] < b[1]:
        raise ConfigError(f"{at}.bounds = {b!r} ({name}): must satisfy 0 <= lo < hi (a bias is "
                          "non-negative: what the tire alone cannot give)")
    known = {t.name: t for t in (targets or ())}
    tn = e.get("targets")
    if not (isinstance(tn, list) and tn and all(isinstance(x, str) for x in tn)):
        raise ConfigError(f"{at}.targets = {tn!r} ({name}): must be a non-empty list of target names")
    for x in tn:
        if x not in known:
            raise ConfigError(f"{at}.targets: {x!r} is not a target (targets: "
                              f"{', '.join(known) or 'none'})")
    suffixes = {_quantity_suffix(known[x].quantity) for x in tn}
    if len(suffixes) != 1:
        raise ConfigError(f"{at}.targets = {tn!r} ({name}): one bias adds to quantities of one "
                          "unit; these differ")
    return float(b[0]), float(b[1]), tuple(tn), _SI_UNIT[suffixes.pop()]
