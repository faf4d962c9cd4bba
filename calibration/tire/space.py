"""ParamSpace: the free parameters of a calibration <-> `MaterialParams` leaves, in log space.

A free parameter is one MaterialParams leaf, per part where the leaf is per part:

    parts.<part>.<field>   part in jtire.mesh.PART_NAMES, field in PER_PART_FIELDS
    undertread.E  undertread.thickness  tread.E  tread.G  tread.loss  tread.friction

or a geometry parameter of the section (not traceable: the mesh is built in numpy, so a simulator
builds one model per geometry, and its Jacobian takes these columns by finite differences):

    geometry.crown_radius  geometry.widest_point_ratio

or a measurement-model parameter that is not part of the tire:

    bias.<label>   an additive bias b >= 0 on the targets it names (`targets = [...]`): what those
                   targets measure is the tire's response plus b (rolling resistance measured on a
                   track or drum holds non-tire drag: bearings, aerodynamics, the rig). theta = b in
                   the targets' SI unit (linear, so b = 0 is inside the box); it never enters the
                   tire file; the simulators add it to their responses (`add_bias`).

Every search, surrogate, sampler and Jacobian works in theta = ln(value in SI): moduli that
span a factor of ten are searched evenly in log space, positivity is built in, and
d(response)/d(theta) is the response's change per relative change of the parameter (an
elasticity once divided by the response), comparable across parameters of different units.

`to_params(theta, base)` (bias and geometry entries skipped) is pure jax (gathers and scatters with static indices), so a simulator
may jit, vmap, jvp or grad through it. The bounds are [lower, upper] of theta, shape (d,).
"""

import dataclasses
import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ... import units as U
from ...errors import ConfigError
from ...mesh import PART_NAMES
from .free_entries import check_geometry_bounds, is_num, parse_bias

__all__ = ["PER_PART_FIELDS", "SCALAR_LEAVES", "ParamSpace", "allowed_names", "leaf_of"]

PER_PART_FIELDS = ("E_meridional", "E_circumferential", "G_shear", "E_bending", "thickness", "loss")
# config name -> MaterialParams field
SCALAR_LEAVES = {"undertread.E": "undertread_E", "undertread.thickness": "undertread_thickness",
                 "tread.E": "tread_E", "tread.G": "tread_G", "tread.loss": "tread_loss",
                 "tread.friction": "friction", "model_form.nodal_damping": "nodal_damping"}
# searched linearly (theta = the SI value): their zero is a meaningful, default value (off)
# field -> (tire-TOML key, SI per file unit, file unit): the calibrated tire is written in these
_FILE_UNITS = {"E_meridional": ("E_meridional_MPa", U.MPA, "MPa"),
               "E_circumferential": ("E_circumferential_MPa", U.MPA, "MPa"),
               "G_shear": ("G_shear_MPa", U.MPA, "MPa"), "E_bending": ("E_bending_MPa", U.MPA, "MPa"),
               "thickness": ("thickness_mm", U.MM, "mm"), "loss": ("loss", 1.0, ""),
               "undertread_E": ("E_MPa", U.MPA, "MPa"), "undertread_thickness": ("thickness_mm", U.MM, "mm"),
               "tread_E": ("E_MPa", U.MPA, "MPa"), "tread_G": ("G_MPa", U.MPA, "MPa"),
               "tread_loss": ("loss", 1.0, ""), "friction": ("friction", 1.0, ""),
               "nodal_damping": ("nodal_damping_per_s", 1.0, "1/s")}


# config name -> Geometry field (the section's shape: `jtire.mesh.section_profile`)
GEOMETRY_LEAVES = {"geometry.crown_radius": "crown_radius", "geometry.widest_point_ratio": "widest_point_ratio"}
GEOMETRY_FIELDS = tuple(GEOMETRY_LEAVES.values())
_FILE_UNITS.update({"crown_radius": ("crown_radius_mm", U.MM, "mm"),
                    "widest_point_ratio": ("widest_point_ratio", 1.0, "")})
BIAS = "bias"  # the field of a bias entry (not a MaterialParams leaf)
LINEAR_FIELDS = (BIAS, "nodal_damping")


def allowed_names() -> str:
    """One line describing every allowed parameter name (for error messages)."""
    return (f"parts.<part>.<field> with part in {{{', '.join(PART_NAMES)}}} and field in "
            f"{{{', '.join(PER_PART_FIELDS)}}}, {', '.join(SCALAR_LEAVES)}, {', '.join(GEOMETRY_LEAVES)}, "
            "or bias.<label> "
            "(with targets = [...])")


def leaf_of(name: str):
    """Config name -> (MaterialParams field, part index or -1 for a scalar leaf); None if unknown."""
    if name in SCALAR_LEAVES:
        return SCALAR_LEAVES[name], -1
    if name in GEOMETRY_LEAVES:
        return GEOMETRY_LEAVES[name], -1
    if name.startswith("bias.") and len(name) > 5 and "." not in name[5:]:
        return BIAS, -1
    bits = name.split(".")
    if len(bits) == 3 and bits[0] == "parts" and bits[1] in PART_NAMES and bits[2] in PER_PART_FIELDS:
        return bits[2], PART_NAMES.index(bits[1])
    return None


@dataclasses.dataclass(frozen=True)
class ParamSpace:
    """d free parameters, log space.

    names: (d,) config names; fields: (d,) MaterialParams fields; parts: (d,) part index or -1;
    lower, upper: (d,) bounds of theta = ln(SI value) (a bias: theta = b, SI); default: (d,)
    theta of the base tire (a bias: its lower bound); reasons: (d,) the config's one-line reason
    for each parameter; bias_targets: (d,) the target names a bias entry adds to, () for a tire
    leaf; bias_units: (d,) the SI unit of a bias entry ("" for a tire leaf); base_geometry: the
    tire's `jtire.mesh.Geometry` (the value of every geometry field that is not free).
    """

    names: tuple
    fields: tuple
    parts: tuple
    lower: np.ndarray
    upper: np.ndarray
    default: np.ndarray
    reasons: tuple = ()
    bias_targets: tuple = ()
    bias_units: tuple = ()
    base_geometry: object = None

    @property
    def d(self) -> int:
        return len(self.names)

    def is_bias(self, i: int) -> bool:
        return self.fields[i] == BIAS

    def is_linear(self, i: int) -> bool:
        """theta_i is the SI value itself (a bias, the nodal damping), not its log."""
        return self.fields[i] in LINEAR_FIELDS

    def is_geometry(self, i: int) -> bool:
        return self.fields[i] in GEOMETRY_FIELDS

    @property
    def geometry_indices(self) -> list:
        return [i for i in range(self.d) if self.is_geometry(i)]

    def geometry_at(self, theta):
        """The section's Geometry at theta (d,) (numpy): the base tire's with the free fields set."""
        theta = np.asarray(theta, float)
        new = {self.fields[i]: float(np.exp(theta[i])) for i in self.geometry_indices}
        return dataclasses.replace(self.base_geometry, **new) if new else self.base_geometry

    def geometry_values(self, theta) -> dict:
        """{Geometry field: value (SI)} of every calibratable geometry field at theta (jax-traceable;
        a field that is not free keeps the base tire's value)."""
        out = {f: getattr(self.base_geometry, f) for f in GEOMETRY_FIELDS} if self.base_geometry else {}
        for i in self.geometry_indices:
            out[self.fields[i]] = jnp.exp(jnp.asarray(theta)[i])
        return out

    @property
    def has_bias(self) -> bool:
        return BIAS in self.fields

    @property
    def tire_indices(self) -> list:
        """Indices of the tire parameters (every entry but the biases)."""
        return [i for i in range(self.d) if not self.is_bias(i)]

    def bias_matrix(self, response_names) -> np.ndarray:
        """B (m, d): 1 where bias parameter j adds to response i, else 0."""
        B = np.zeros((len(response_names), self.d))
        for j in range(self.d):
            for t in (self.bias_targets[j] if self.is_bias(j) else ()):
                if t in response_names:
                    B[list(response_names).index(t), j] = 1.0
        return B

    def add_bias(self, thetas, values, response_names) -> np.ndarray:
        """values (n, m) of the tire -> what the targets measure: tire + the biases at thetas (n, d)."""
        values = np.asarray(values, float)
        if not self.has_bias:
            return values
        return values + np.atleast_2d(np.asarray(thetas, float)) @ self.bias_matrix(response_names).T

    def add_bias_jacobian(self, theta, values, J, response_names) -> tuple:
        """(values, J) of the tire at theta (d,) -> what the targets measure: + b and + dB/dtheta."""
        if not self.has_bias:
            return values, J
        B = self.bias_matrix(response_names)
        return values + B @ np.asarray(theta, float), J + B

    def biases(self, theta) -> dict:
        """{name: (b in SI, unit, target names)} of the bias entries at theta (d,)."""
        theta = np.asarray(theta, float)
        return {self.names[j]: (float(theta[j]), self.bias_units[j], list(self.bias_targets[j]))
                for j in range(self.d) if self.is_bias(j)}

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
        """MaterialParams with the free leaves set to exp(theta) (a linear leaf: theta); theta (d,)
        jax or numpy.

        Pure jax with static indices: traceable under jit, vmap (theta batched), jvp and grad.
        Leaves keep the base's dtype.
        """
        theta = jnp.asarray(theta)
        groups = {}
        for i, (f, p) in enumerate(zip(self.fields, self.parts)):
            if f != BIAS and f not in GEOMETRY_FIELDS:
                groups.setdefault(f, []).append((i, p))
        if not groups:
            return base
        new = []
        for f, items in groups.items():
            leaf = getattr(base, f)
            idx = np.array([i for i, _ in items])
            vals = (theta[idx] if f in LINEAR_FIELDS else jnp.exp(theta[idx])).astype(leaf.dtype)
            if items[0][1] < 0:
                new.append(vals[0])
            else:
                new.append(leaf.at[np.array([p for _, p in items])].set(vals))
        fields = tuple(groups)
        return eqx.tree_at(lambda m: tuple(getattr(m, f) for f in fields), base, tuple(new))

    def from_params(self, params, geometry=None) -> np.ndarray:
        """theta (d,) of a MaterialParams (numpy) and a section (`geometry`, a Geometry; default: the
        base tire's); a bias entry gets its lower bound (no bias)."""
        out = []
        for i, (f, p) in enumerate(zip(self.fields, self.parts)):
            if f == BIAS:
                out.append(float(self.lower[i]) if len(self.lower) > i else 0.0)
                continue
            if f in GEOMETRY_FIELDS:  # not in MaterialParams: the section's
                out.append(math.log(getattr(geometry or self.base_geometry, f)))
                continue
            leaf = np.asarray(getattr(params, f), dtype=float)
            v = float(leaf) if p < 0 else float(leaf[p])
            out.append(v if f in LINEAR_FIELDS else (math.log(v) if v > 0 else -math.inf))
        return np.array(out)

    def values(self, theta) -> dict:
        """{name: SI value} at theta (d,)."""
        theta = np.asarray(theta, float)
        return {n: float(self.value(i, theta[i])) for i, n in enumerate(self.names)}

    def value(self, i: int, theta_i):
        """Parameter i's SI value(s) from theta_i (a linear one is its own theta)."""
        return np.asarray(theta_i, float) if self.is_linear(i) else np.exp(np.asarray(theta_i, float))

    def file_values(self, theta) -> list:
        """[(toml table, toml key, value in the file's unit, unit)] at theta, for the tire TOML
        (tire parameters only: a bias is not part of the tire)."""
        out = []
        theta = np.asarray(theta, float)
        for i, (n, f, p) in enumerate(zip(self.names, self.fields, self.parts)):
            if f == BIAS:
                continue
            v = self.value(i, theta[i])
            key, factor, unit = _FILE_UNITS[f]
            table = (f"parts.{PART_NAMES[p]}" if p >= 0 else "tire" if f in GEOMETRY_FIELDS
                     else n.rsplit(".", 1)[0])
            out.append((table, key, float(v) / factor, unit))
        return out

    def file_unit(self, i: int):
        """(SI per file unit, unit name) of parameter i."""
        if self.is_bias(i):
            return 1.0, self.bias_units[i]
        _, factor, unit = _FILE_UNITS[self.fields[i]]
        return factor, unit

    def as_dict(self) -> dict:
        """JSON-able description (for fingerprints and reports)."""
        out = {"names": list(self.names), "lower": self.lower.tolist(),
               "upper": self.upper.tolist(), "default": self.default.tolist()}
        if self.has_bias:  # (absent without one: older folders keep their fingerprint)
            out["bias_targets"] = {self.names[j]: list(self.bias_targets[j])
                                   for j in range(self.d) if self.is_bias(j)}
        return out

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_config(cls, free, base, where: str = "free", targets=None, geometry=None) -> "ParamSpace":
        """Parse the [[free]] array of tables against a base MaterialParams.

        Each tire entry: name = "<parameter>", and either factor = [lo, hi] (times the base tire's
        value) or bounds = [lo, hi] in the tire file's unit of that leaf (MPa for moduli, mm for
        thicknesses, none for loss tangents and friction); why = "one-line reason" (optional).
        A bias entry: name = "bias.<label>", bounds = [lo, hi] with 0 <= lo < hi in the SI unit of
        its targets, targets = [names of calibration targets] (`targets`: the parsed Targets).
        A geometry entry (geometry.<field>) is bounded like a tire leaf; `geometry` is the tire's
        Geometry, and both bounds must give a section the mesh can build.
        """
        if not isinstance(free, list) or not free or not all(isinstance(e, dict) for e in free):
            raise ConfigError(f"{where}: must be a non-empty array of tables [[{where}]] with "
                              "name and factor or bounds")
        names, fields, parts, lo, hi, reasons, btargets, bunits = [], [], [], [], [], [], [], []
        for k, e in enumerate(free):
            at = f"{where}[{k}]"
            name = e.get("name")
            allowed = ("name", "factor", "bounds", "why") + (
                ("targets",) if isinstance(name, str) and name.startswith("bias.") else ())
            for key in e:
                if key not in allowed:
                    raise ConfigError(f"{at}.{key}: unknown field (allowed: {', '.join(allowed)})")
            if not isinstance(name, str):
                raise ConfigError(f"{at}.name: missing (a parameter name: {allowed_names()})")
            leaf = leaf_of(name)
            if leaf is None:
                raise ConfigError(f"{at}.name = {name!r}: unknown parameter; allowed: {allowed_names()}")
            if name in names:
                raise ConfigError(f"{at}.name = {name!r}: listed twice")
            r = e.get("why", "")
            if not isinstance(r, str):
                raise ConfigError(f"{at}.why: must be a string (a one-line reason)")
            field, part = leaf
            if field == BIAS:
                b_lo, b_hi, tnames, unit = parse_bias(e, at, name, targets)
                names.append(name), fields.append(field), parts.append(-1)
                lo.append(b_lo), hi.append(b_hi), reasons.append(r)
                btargets.append(tnames), bunits.append(unit)
                continue
            if field in GEOMETRY_FIELDS:
                if geometry is None:
                    raise ConfigError(f"{at}.name = {name!r}: geometry parameters need the tire's section")
                v0 = float(getattr(geometry, field))
            else:
                v0 = np.asarray(getattr(base, field), dtype=float)
                v0 = float(v0) if part < 0 else float(v0[part])
            linear = field in LINEAR_FIELDS
            if linear and "factor" in e:
                raise ConfigError(f"{at}.factor ({name}): searched linearly from a tire value that may be "
                                  "0; give bounds = [lo, hi] in the tire file's unit")
            if ("factor" in e) == ("bounds" in e):
                raise ConfigError(f"{at} ({name}): give exactly one of factor = [lo, hi] (times the "
                                  "tire's value) or bounds = [lo, hi] (the tire file's unit)")
            key = "factor" if "factor" in e else "bounds"
            b = e[key]
            if not (isinstance(b, list) and len(b) == 2 and all(is_num(x) for x in b)):
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must be two numbers [lo, hi]")
            if not (0 <= b[0] < b[1] if linear else 0 < b[0] < b[1]):
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must satisfy {'0 <=' if linear else '0 <'} "
                                  "lo < hi (an empty or inverted range cannot be searched)")
            factor, unit = _FILE_UNITS[field][1:]
            lo_si, hi_si = ((b[0] * v0, b[1] * v0) if key == "factor"
                            else (b[0] * factor, b[1] * factor))
            if not (v0 >= 0 if linear else v0 > 0):
                raise ConfigError(f"{at}.name = {name!r}: the tire's value is {v0:g}; a log-space "
                                  "parameter must start > 0")
            if not lo_si * (1 - 1e-12) <= v0 <= hi_si * (1 + 1e-12):
                raise ConfigError(f"{at}.{key} = {b!r} ({name}): must contain the tire's value "
                                  f"{v0 / factor:g}{' ' + unit if unit else ''}")
            if field in GEOMETRY_FIELDS:
                check_geometry_bounds(geometry, field, (lo_si, hi_si), f"{at}.{key} = {b!r} ({name})", factor)
            names.append(name), fields.append(field), parts.append(part)
            lo.append(lo_si if linear else math.log(lo_si)), hi.append(hi_si if linear else math.log(hi_si))
            reasons.append(r), btargets.append(()), bunits.append("")
        if all(f == BIAS for f in fields):
            raise ConfigError(f"{where}: only bias entries; free at least one tire parameter")
        space = cls(tuple(names), tuple(fields), tuple(parts), np.array(lo), np.array(hi),
                    np.zeros(len(names)), tuple(reasons), tuple(btargets), tuple(bunits), geometry)
        default = np.clip(space.from_params(base), space.lower, space.upper)
        return dataclasses.replace(space, default=default)
