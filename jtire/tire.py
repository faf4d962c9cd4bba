"""From a validated TireSpec to the objects a simulation needs: mesh, model and parameters."""

import dataclasses

import jax.numpy as jnp

from .config import TireSpec
from .materials import MaterialParams
from .mesh import PART_NAMES, Mesh, build_mesh
from .model import TireModel


@dataclasses.dataclass(frozen=True)
class Tire:
    """Everything a simulation of one tire needs, built by `make_tire` from a validated TireSpec.

    Attributes:
        spec: the validated tire file (SI).
        mesh: the swept mesh (static topology, reference geometry, lumped masses; numpy).
        model: the TireModel built on the mesh (the arrays and maps the force terms use). Mesh and
            model are cached: tires of the same geometry, masses and mesh settings share them.
        params: the MaterialParams of the spec (per-part moduli, thicknesses, losses, tread, friction).
    """

    spec: TireSpec
    mesh: Mesh
    model: TireModel
    params: MaterialParams


def params_from_spec(spec: TireSpec) -> MaterialParams:
    col = lambda key: jnp.array([spec.parts[p][key] for p in PART_NAMES])  # noqa: E731
    return MaterialParams(
        E_meridional=col("E_meridional"), E_circumferential=col("E_circumferential"), G_shear=col("G_shear"),
        E_bending=col("E_bending"), thickness=col("thickness"), loss=col("loss"),
        undertread_E=jnp.asarray(spec.undertread_E), undertread_thickness=jnp.asarray(spec.undertread_thickness),
        tread_E=jnp.asarray(spec.tread_E), tread_G=jnp.asarray(spec.tread_G), tread_loss=jnp.asarray(spec.tread_loss),
        friction=jnp.asarray(spec.friction), relaxation_times=tuple(spec.relaxation_times),
        nodal_damping=jnp.asarray(spec.nodal_damping, dtype=jnp.float64),
    )


_CACHE: dict = {}


def make_tire(spec: TireSpec) -> Tire:
    """Mesh + model + parameters. Models are cached per geometry and mesh size (building one
    traces a few functions), so repeated runs and sweeps reuse one model and one compilation."""
    key = (spec.geometry, spec.masses, spec.n_theta, spec.n_side, spec.n_crown, spec.contact_subpoints)
    if key not in _CACHE:
        if len(_CACHE) >= 16:  # a calibration with free geometry builds one model per point
            _CACHE.pop(next(iter(_CACHE)))
        mesh = build_mesh(spec.geometry, spec.masses, spec.n_theta, spec.n_side, spec.n_crown)
        _CACHE[key] = (mesh, TireModel.from_mesh(mesh, spec.contact_subpoints))
    mesh, model = _CACHE[key]
    return Tire(spec, mesh, model, params_from_spec(spec))
