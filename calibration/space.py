"""ParamSpace: the free parameters of a calibration <-> `MaterialParams` leaves, in log space.

A free parameter is one MaterialParams leaf, per part where the leaf is per part:

    parts.<part>.<field>   part in jtire.mesh.PART_NAMES, field in PER_PART_FIELDS
    undertread.E  undertread.thickness  tread.E  tread.G  tread.loss  tread.friction

Every search, surrogate, sampler and Jacobian works in theta = ln(value in SI): moduli that
span a factor of ten are searched evenly in log space, positivity is built in, and
d(response)/d(theta) is the response's change per relative change of the parameter (an
elasticity once divided by the response), comparable across parameters of different units.

`to_params(theta, base)` is pure jax (gathers and scatters with static indices), so a simulator
may jit, vmap, jvp or grad through it. The bounds are [lower, upper] of theta, shape (d,).
"""

import dataclasses
import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .. import units as U
from ..errors import ConfigError
from ..mesh import PART_NAMES

__all__ = ["PER_PART_FIELDS", "SCALAR_LEAVES", "ParamSpace", "allowed_names", "leaf_of"]

PER_PART_FIELDS = ("E_meridional", "E_circumferential", "G_shear", "E_bending", "thickness", "loss")
# config name -> MaterialParams field
SCALAR_LEAVES = {"undertread.E": "undertread_E", "undertread.thickness": "undertread_thickness",
                 "tread.E": "tread_E", "tread.G": "tread_G", "tread.loss": "tread_loss",
                 "tread.friction": "friction"}
# field -> (tire-TOML key, SI per file unit, file unit): the calibrated tire is written in these
_FILE_UNITS = {"E_meridional": ("E_meridional_MPa", U.MPA, "MPa"),
               "E_circumferential": ("E_circumferential_MPa", U.MPA, "MPa"),
               "G_shear": ("G_shear_MPa", U.MPA, "MPa"), "E_bending": ("E_bending_MPa", U.MPA, "MPa"),
               "thickness": ("thickness_mm", U.MM, "mm"), "loss": ("loss", 1.0, ""),
               "undertread_E": ("E_MPa", U.MPA, "MPa"), "undertread_thickness": ("thickness_mm", U.MM, "mm"),
               "tread_E": ("E_MPa", U.MPA, "MPa"), "tread_G": ("G_MPa", U.MPA, "MPa"),
               "tread_loss": ("loss", 1.0, ""), "friction": ("friction", 1.0, "")}


def allowed_names() -> str:
    """One line describing every allowed parameter name (for error messages)."""
    return (f"parts.<part>.<field> with part in {{{', '.join(PART_NAMES)}}} and field in "
            f"{{{', '.join(PER_PART_FIELDS)}}}, or {', '.join(SCALAR_LEAVES)}")


def leaf_of(name: str):
    """Config name -> (MaterialParams field, part index or -1 for a scalar leaf); None if unknown."""
    if name in SCALAR_LEAVES:
        return SCALAR_LEAVES[name], -1
    bits = name.split(".")
    if len(bits) == 3 and bits[0] == "parts" and bits[1] in PART_NAMES and bits[2] in PER_PART_FIELDS:
        return bits[2], PART_NAMES.index(bits[1])
    return None


def _is_num(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


@dataclasses.dataclass(frozen=True)
class ParamSpace:
    """d free parameters, log space.

    names: (d,) config names; fields: (d,) MaterialParams fields; parts: (d,) part index or -1;
    lower, upper: (d,) bounds of theta = ln(SI value); default: (d,) theta of the base tire;
    reasons: (d,) the config's one-line reason for each parameter.
    """

    names: tuple
    fields: tuple
    parts: tuple
    lower: np.ndarray
    upper: np.ndarray
    default: np.ndarray
    reasons: tuple = ()

    @property
    def d(self) -> int:
        return len(self.names)

    @property
    def width(self) -> np.ndarray:
        return self.upper - self.lower

    # -- coordinates -------------------------------------------------------------------------
    def to_unit(self, theta):
        """theta (..., d) -> unit coordinates (..., d) of the log box."""
        return (np.asarray(theta, float) - self.lower) / self.width

    def from_unit(self, u):
        """unit coordinates (..., d) -> theta (..., d)."""
        return self.lower + np.asarray(u, float) * self.width

    def clip(self, theta):
        return np.clip(np.asarray(theta, float), self.lower, self.upper)

    # -- MaterialParams ----------------------------------------------------------------------
    def to_params(self, theta, base):
        """MaterialParams with the free leaves set to exp(theta); theta (d,) jax or numpy.

        Pure jax with static indices: traceable under jit, vmap (theta batched), jvp and grad.
        Leaves keep the base's dtype.
        """
        theta = jnp.asarray(theta)
        groups = {}
        for i, (f, p) in enumerate(zip(self.fields, self.parts)):
            groups.setdefault(f, []).append((i, p))
        new = []
        for f, items in groups.items():
            leaf = getattr(base, f)
            idx = np.array([i for i, _ in items])
            vals = jnp.exp(theta[idx]).astype(leaf.dtype)
            if items[0][1] < 0:
                new.append(vals[0])
            else:
                new.append(leaf.at[np.array([p for _, p in items])].set(vals))
        fields = tuple(groups)
        return eqx.tree_at(lambda m: tuple(getattr(m, f) for f in fields), base, tuple(new))

    def from_params(self, params) -> np.ndarray:
        """theta (d,) of a MaterialParams (numpy)."""
        out = []
        for f, p in zip(self.fields, self.parts):
            leaf = np.asarray(getattr(params, f), dtype=float)
            out.append(float(leaf) if p < 0 else float(leaf[p]))
        return np.log(np.array(out))

    def values(self, theta) -> dict:
        """{name: SI value} at theta (d,)."""
        return {n: float(v) for n, v in zip(self.names, np.exp(np.asarray(theta, float)))}

    def file_values(self, theta) -> list:
        """[(toml table, toml key, value in the file's unit, unit)] at theta, for the tire TOML."""
        out = []
        for n, f, p, v in zip(self.names, self.fields, self.parts, np.exp(np.asarray(theta, float))):
            key, factor, unit = _FILE_UNITS[f]
            table = f"parts.{PART_NAMES[p]}" if p >= 0 else n.rsplit(".", 1)[0]
            out.append((table, key, float(v) / factor, unit))
        return out

    def file_unit(self, i: int):
        """(SI per file unit, unit name) of parameter i."""
        _, factor, unit = _FILE_UNITS[self.fields[i]]
        return factor, unit

    def as_dict(self) -> dict:
        """JSON-able description (for fingerprints and reports)."""
        return {"names": list(self.names), "lower": self.lower.tolist(),
                "upper": self.upper.tolist(), "default": self.default.tolist()}

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_config(cls, free, base, where: str = "free") -> "ParamSpace":
        """Parse the [[free]] array of tables against a base MaterialParams.

        Each entry: name = "<parameter>", and either factor = [lo, hi] (times the base tire's
        value) or bounds = [lo, hi] in the tire file's unit of that leaf (MPa for moduli, mm for
        thicknesses, none for loss tangents and friction); why = "one-line reason" (optional).
        """
        if not isinstance(free, list) or not free or not all(isinstance(e, dict) for e in free):
            raise ConfigError(f"{where}: must be a non-empty array of tables [[{where}]] with "
                              "name and factor or bounds")
        names, fields, parts, lo, hi, reasons = [], [], [], [], [], []
        for k, e in enumerate(free):
            at = f"{where}[{k}]"
            for key in e:
                if key not in ("name", "factor", "bounds", "why"):
                    raise ConfigError(f"{at}.{key}: unknown field (allowed: name, factor, bounds, why)")
            name = e.get("name")
            if not isinstance(name, str):
                raise ConfigError(f"{at}.name: missing (a parameter name: {allowed_names()})")
            leaf = leaf_of(name)
            if leaf is None:
                raise ConfigError(f"{at}.name = {name!r}: unknown parameter; allowed: {allowed_names()}")
            if name in names:
                raise ConfigError(f"{at}.name = {name!r}: listed twice")
            field, part = leaf
            v0 = np.asarray(getattr(base, field), dtype=float)
            v0 = float(v0) if part < 0 else float(v0[part])
            if ("factor" in e) == ("bounds" in e):
                raise ConfigError(f"{at} ({name}): give exactly one of factor = [lo, hi] (times the "
                                  "tire's value) or bounds = [lo, hi] (the tire file's unit)")
            key = "factor" if "factor" in e else "bounds"
            b = e[key]
            if not (isinstance(b, list) and len(b) == 2 and all(_is_num(x) for x in b)):
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must be two numbers [lo, hi]")
            if not 0 < b[0] < b[1]:
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must satisfy 0 < lo < hi (an empty "
                                  "or inverted range cannot be searched)")
            factor, unit = _FILE_UNITS[field][1:]
            lo_si, hi_si = ((b[0] * v0, b[1] * v0) if key == "factor"
                            else (b[0] * factor, b[1] * factor))
            if not v0 > 0:
                raise ConfigError(f"{at}.name = {name!r}: the tire's value is {v0:g}; a log-space "
                                  "parameter must start > 0")
            if not lo_si * (1 - 1e-12) <= v0 <= hi_si * (1 + 1e-12):
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must contain the tire's value "
                                  f"{v0 / factor:g}{' ' + unit if unit else ''}")
            names.append(name), fields.append(field), parts.append(part)
            lo.append(math.log(lo_si)), hi.append(math.log(hi_si))
            r = e.get("why", "")
            if not isinstance(r, str):
                raise ConfigError(f"{at}.why: must be a string (a one-line reason)")
            reasons.append(r)
        space = cls(tuple(names), tuple(fields), tuple(parts), np.array(lo), np.array(hi),
                    np.zeros(len(names)), tuple(reasons))
        default = np.clip(space.from_params(base), space.lower, space.upper)
        return dataclasses.replace(space, default=default)
