"""A closed-form STAND-IN simulator for tests and dry runs. NOT PHYSICS.

It answers the calibration targets in milliseconds with the structure of the real responses,
so that every piece of the calibration and posterior machinery can be exercised without the
shell model:

- static vertical deflection  DZ = F / k_v,  k_v = series(k_p + k_carcass, k_tread):
  k_p an inflation term, k_carcass a sum of power laws of the sidewall parts' meridional,
  bending, circumferential and shear stiffnesses (E t, E t^3), k_tread from tread E and the
  undertread modulus. Smooth, monotone, saturating (the series spring) in every modulus.
- static lateral deflection  DY = F_y / k_lat,  k_lat = series(sidewall lateral, tread shear G
  growing with load^0.5).
- footprint: half the chord of the free radius cut at DZ's deflection, a width growing with it.
- rolling-resistance force  FX = RRC(F_z) F_z with RRC = sidewall and shoulder loss x deflection
  (so FX grows like F_z^1.x and softer sidewalls lose more) + tread loss x F_z^0.2 + crown loss.

- geometry (when free): the carcass term of k_v grows like crown_radius^0.3 (a flatter crown
  spreads the load over more of the belt) and the sidewall's lateral term like
  (widest_point_ratio / 0.5)^-0.5; both 1 at the shipped section.

Its constants put the xone_xda defaults at DZ ~ 44 mm at 50 kN, DY ~ 12 mm at 5 kN and RRC
~ 0.02 (the test-track trend), so the study's targets are reachable inside the default bounds
but not at the defaults. Everything is jax: the Jacobian is exact (autodiff through
`ParamSpace.to_params`), which is what the gradient route and its finite-difference check use.
"""

import time

import jax
import jax.numpy as jnp
import numpy as np

from .simulator import Simulator
from ...errors import ConfigError

__all__ = ["StandinSimulator", "REFERENCE"]

# The shipped xone_xda values (SI): the stand-in's responses are functions of value / reference,
# fixed here so that the stand-in does not move when the base tire changes.
REFERENCE = {
    "E_meridional": np.array([700.0, 1000.0, 1300.0, 1100.0, 600.0, 300.0]) * 1e6,
    "E_circumferential": np.array([12.0, 6.0, 5.0, 5.0, 8.0, 10000.0]) * 1e6,
    "G_shear": np.array([3.0, 2.0, 1.7, 1.7, 2.7, 130.0]) * 1e6,
    "E_bending": np.array([60.0, 25.0, 20.0, 20.0, 40.0, 600.0]) * 1e6,
    "thickness": np.array([25.0, 18.0, 14.0, 16.0, 30.0, 15.0]) * 1e-3,
    "loss": np.array([0.10, 0.10, 0.10, 0.10, 0.12, 0.12]),
    "undertread_E": 5e6, "tread_E": 15e6, "tread_G": 1.5e6, "tread_loss": 0.15,
}
_SIDEWALL_W = jnp.array([0.0, 0.3, 0.4, 0.3, 0.0, 0.0])  # lower, mid, upper sidewall
_BEND_W = jnp.array([0.2, 0.2, 0.2, 0.2, 0.2, 0.0])  # bead .. shoulder
_DELTA_REF = 0.045  # m, the deflection the loss terms are scaled to


def _x(params, field):
    return getattr(params, field) / REFERENCE[field]


def stiffnesses(params, load_n, geo=None):
    """(k_v, k_lat) in N/m of the stand-in at vertical load load_n (N); geo: {Geometry field: SI
    value} (`ParamSpace.geometry_values`; absent fields at the shipped section)."""
    geo = geo or {}
    crown = geo.get("crown_radius", 2.0) / 2.0
    widest = geo.get("widest_point_ratio", 0.5) / 0.5
    t = _x(params, "thickness")
    m = jnp.sum(_SIDEWALL_W * _x(params, "E_meridional") * t)
    b = jnp.sum(_BEND_W * _x(params, "E_bending") * t**3)
    c = jnp.sum(_SIDEWALL_W * _x(params, "E_circumferential") * t)
    s = jnp.sum(_SIDEWALL_W * _x(params, "G_shear") * t)
    k_p = 500e3
    k_carc = (300e3 * m**0.3 + 200e3 * b**0.7 + 100e3 * c**0.5 + 50e3 * s**0.5) * crown**0.3
    k_tread = 8e6 * _x(params, "tread_E") ** 0.8 * _x(params, "undertread_E") ** 0.2
    k_v = 1.0 / (1.0 / (k_p + k_carc) + 1.0 / k_tread)
    k_sw_lat = (250e3 * c**0.4 * b**0.3 + 150e3 * s**0.5) * widest**-0.5 + 0.15 * k_p
    k_tr_lat = 3e6 * _x(params, "tread_G") * (load_n / 45.4e3) ** 0.5
    k_lat = 1.0 / (1.0 / k_sw_lat + 1.0 / k_tr_lat)
    return k_v, k_lat


def rolling_resistance(params, load_n, geo=None):
    """Stand-in drag force (N) at vertical load load_n (N)."""
    k_v, _ = stiffnesses(params, load_n, geo)
    delta = load_n / k_v / _DELTA_REF
    loss = params.loss
    l_sw = jnp.sum(_SIDEWALL_W * loss) + 0.3 * loss[4]
    rrc = (0.08 * l_sw * delta + 0.05 * params.tread_loss * (load_n / 40e3) ** 0.2
           + 0.03 * loss[5] * delta**0.5)
    return rrc * load_n


def footprint(params, load_n, geo=None):
    """Stand-in footprint (length, width), m, at vertical load load_n (N): half the chord of a 0.51 m
    circle cut at the stand-in's deflection (the tread and belt spread a deflection, so the shell model's
    E01 patch is shorter than its geometric chord: docs/design-notes.md), and a width that grows from
    0.30 m with it."""
    delta = load_n / stiffnesses(params, load_n, geo)[0]
    return jnp.sqrt(2.0 * 0.5095 * delta - delta**2), 0.30 + 2.0 * delta


STANDIN_RESPONSES = (("footprint", "contact_length_m"), ("footprint", "contact_width_m"),
                     ("vertical_stiffness", "deflection_m"), ("lateral_stiffness", "lateral_deflection_m"),
                     ("rolling_resistance", "rolling_resistance_N"))


def _response(params, target, geo=None):
    exp, q, cond, table = target.experiment, target.quantity, target.condition, target.table
    if exp == "footprint" and q in ("contact_length_m", "contact_width_m"):
        return footprint(params, cond["load_N"], geo)[q == "contact_width_m"]
    if exp == "vertical_stiffness" and q == "deflection_m":
        force = table.get("stated_load_kN") or cond["load_N"]
        return force / stiffnesses(params, force, geo)[0]
    if exp == "lateral_stiffness" and q == "lateral_deflection_m":
        return table["force_kN"] / stiffnesses(params, cond["load_N"], geo)[1]
    if exp == "rolling_resistance" and q == "rolling_resistance_N":
        return rolling_resistance(params, cond["load_N"], geo)
    raise ValueError(f"stand-in simulator: no stand-in for {exp}.{q} (target {target.name})")


class StandinSimulator(Simulator):
    """The stand-in (module docstring) for a ParamSpace, a base MaterialParams and targets.

    fail: optional callable theta (d,) -> bool; such points return a nan row (a failed run).
    jacobian_cost: forward-run equivalents charged per jacobian call (reporting only; the default
    says d, one forward run per parameter; what a jvp costs on the shell model: docs/design-notes.md).
    Counters: n_points (points evaluated), batches (list of batch sizes), n_jacobians.
    """

    def __init__(self, space, base_params, targets, fail=None, jacobian_cost=None):
        self.space, self.base, self.targets = space, base_params, tuple(targets)
        for t in self.targets:  # refuse a target it has no formula for before anything runs
            if (t.experiment, t.quantity) not in STANDIN_RESPONSES:
                raise ConfigError(f"targets.{t.name}: the stand-in has no {t.experiment}.{t.quantity} (it has "
                                  f"{', '.join('.'.join(r) for r in STANDIN_RESPONSES)}); drop --standin")
        self.response_names = tuple(t.name for t in self.targets)
        self.fail = fail
        self.cost_forward_equivalents = {
            "evaluate": 1.0, "jacobian": float(space.d if jacobian_cost is None else jacobian_cost)}
        self.n_points, self.batches, self.n_jacobians = 0, [], 0
        extra = {"k_v_N_per_m": lambda p, g: stiffnesses(p, 45.4e3, g)[0],
                 "k_lat_N_per_m": lambda p, g: stiffnesses(p, 45.4e3, g)[1]}
        self._quantities = {t.name: (lambda p, g, t=t: _response(p, t, g)) for t in self.targets}
        self._quantities.update(extra)
        self.quantity_names = tuple(self._quantities)
        base = self.base
        def f(th):  # the parameters and the section once per point, then every target
            p, g = space.to_params(th, base), space.geometry_values(th)
            return jnp.stack([_response(p, t, g) for t in self.targets])

        self._batch = jax.jit(jax.vmap(f))
        self._jac = {}

    def evaluate(self, thetas) -> np.ndarray:
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        t0 = time.perf_counter()
        out = self.space.add_bias(thetas, np.array(self._batch(jnp.asarray(thetas))), self.response_names)
        self.last_failures = {}
        if self.fail is not None:
            bad = [bool(self.fail(th)) for th in thetas]
            out[bad] = np.nan
            self.last_failures = {k: {n: "stand-in: a failed point (test)" for n in self.response_names}
                                  for k, b in enumerate(bad) if b}
        self.n_points += thetas.shape[0]
        self.batches.append(thetas.shape[0])
        self.last_wall_s = time.perf_counter() - t0
        return out

    def jacobian(self, theta, quantities=None):
        names = self.response_names if quantities is None else tuple(quantities)
        unknown = [q for q in names if q not in self._quantities]
        if unknown:
            raise KeyError(f"stand-in simulator: unknown quantities {unknown}; known: "
                           f"{list(self.quantity_names)}")
        if names not in self._jac:
            base, space = self.base, self.space
            def f(th):
                p, g = space.to_params(th, base), space.geometry_values(th)
                return jnp.stack([self._quantities[q](p, g) for q in names])

            self._jac[names] = jax.jit(lambda th: (f(th), jax.jacfwd(f)(th)))
        th = jnp.asarray(np.asarray(theta, dtype=float))
        self.n_jacobians += 1
        vals, jac = self._jac[names](th)
        vals, jac = np.array(vals), np.array(jac)
        if quantities is None:  # the targets measure tire + bias
            vals, jac = self.space.add_bias_jacobian(theta, vals, jac, self.response_names)
        return vals, jac

    def fingerprint(self) -> dict:
        return {"simulator": "standin", "note": "closed-form stand-in, not physics"}

    def for_targets(self, targets):
        return StandinSimulator(self.space, self.base, targets)
