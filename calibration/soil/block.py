"""Rigid circular plate pressed into an elastic-plastic soil block (study section 4.2).

The optimizer competition tunes the soil's density rho (kg/m^3) and Young's modulus E (Pa) so
that the simulated sinkage of a plate of radius 0.15 m under 100 kPa equals the sinkage that
Bekker's pressure-sinkage law p = (k_c / b + k_phi) z^n gives for the study's sandbox soil.

Model (SI, z up, axisymmetric finite elements from `calibration.soil.mesh`):
- Linear isotropic elasticity (E, nu) plus perfectly plastic Drucker-Prager
  f = sqrt(J2) + eta p - xi c <= 0 (p = mean stress, tension positive), cone matched to
  Mohr-Coulomb in triaxial compression; non-associated flow with dilatancy psi. Closed-form
  return to the cone; trial states beyond the apex go to the apex (a tension cut-off).
- Gravity pre-stress sigma_zz = -rho g d, sigma_rr = sigma_tt = K0 sigma_zz at depth d, in exact
  discrete equilibrium with its own nodal body force. The plate's settlement is measured from
  this state, so density acts only through the confinement that sets where the soil yields.
- The plate is rigid and smooth: its surface nodes share one vertical dof loaded by the force
  p pi a^2, raised in equal load steps, each solved by Newton with the consistent tangent
  (element-wise jax.jacfwd through the return mapping), assembled in block-tridiagonal form
  (one block per node row) and solved by block elimination, much cheaper than a dense LU
  (docs/design-notes.md).

A consequence worth knowing: with perfect plasticity and an E-independent pre-stress, every
displacement scales exactly as 1/E at fixed rho, so the error surface over (rho, E) has a valley
E*(rho) = S(rho) / z_target rather than a point minimum (the study saw the same trade-off).

The jitted solve is built once per mesh/load-step layout (`_solver`, cached) and takes every
material constant and the pressure as traced scalars: a competition of thousands of calls
compiles once.
"""

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from .mesh import block_tridiagonal_solve, build_mesh
from ...errors import ConfigError, SimulationError

# Suggested search box for the competition (see `suggested_bounds`): dry-to-saturated soil
# densities and E of a soft, deformable sandbox soil. With the default spec the zero-error valley
# lies inside this box, low in its E range (benchmarks/bench_soil.py --scan; docs/design-notes.md).
DENSITY_BOUNDS_KG_M3 = (1200.0, 2200.0)
YOUNGS_MODULUS_BOUNDS_PA = (0.5e6, 5.0e6)


@dataclasses.dataclass(frozen=True)
class SoilSpec:
    """Geometry, soil constants, loading, solver settings and Bekker target (all SI).

    Defaults are the study's plate test (a = 0.15 m, 100 kPa, Bekker constants of its Table)
    with a loose, slightly cohesive sand (c = 2 kPa, phi = 30 deg, close to Wong's sandy loam);
    the block is 10 plate radii wide and deep.
    """

    plate_radius_m: float = 0.15
    block_radius_m: float = 1.5
    block_depth_m: float = 1.5
    n_r_plate: int = 6  # elements across the plate radius
    n_r_outer: int = 10  # graded elements from the plate edge to the outer wall
    n_z: int = 14  # graded elements from the surface to the bottom
    pressure_Pa: float = 1.0e5
    n_load_steps: int = 10
    poisson_ratio: float = 0.3
    friction_angle_rad: float = math.radians(30.0)
    cohesion_Pa: float = 2.0e3
    dilatancy_angle_rad: float = 0.0
    k0: float = 0.5  # lateral earth pressure at rest; Jaky's 1 - sin(30 deg)
    gravity_m_s2: float = 9.81
    newton_rtol: float = 1e-8  # residual norm / plate force
    max_newton_iterations: int = 30
    bekker_k_c: float = 16.03e3  # N/m^(n+1)
    bekker_k_phi: float = 1262.53e3  # N/m^(n+2)
    bekker_n: float = 0.7
    bekker_b_m: float = 0.15  # the study's b is the plate RADIUS (gives its 23.7896 mm)

    def __post_init__(self):
        checks = [
            ("plate_radius_m", 0.01, 1.0),
            ("block_radius_m", 2.0 * self.plate_radius_m, 100.0),
            ("block_depth_m", self.plate_radius_m, 100.0),
            ("n_r_plate", 1, 50),
            ("n_r_outer", 1, 200),
            ("n_z", 2, 200),
            ("pressure_Pa", 1.0, 1.0e7),
            ("n_load_steps", 1, 1000),
            ("poisson_ratio", 0.0, 0.49),
            ("friction_angle_rad", math.radians(5.0), math.radians(50.0)),
            ("cohesion_Pa", 1.0, 1.0e12),
            ("dilatancy_angle_rad", 0.0, self.friction_angle_rad),
            ("gravity_m_s2", 0.0, 100.0),
            ("newton_rtol", 1e-14, 1e-2),
            ("max_newton_iterations", 1, 500),
            ("bekker_k_c", 0.0, 1e9),
            ("bekker_k_phi", 0.0, 1e10),
            ("bekker_n", 0.1, 2.0),
            ("bekker_b_m", 1e-3, 10.0),
        ]
        types = {f.name: f.type for f in dataclasses.fields(self)}
        for name, lo, hi in checks:
            v = getattr(self, name)
            kind = (int,) if types[name] is int else (int, float)
            if not (isinstance(v, kind) and not isinstance(v, bool)) or not lo <= v <= hi:
                what = "an integer" if types[name] is int else "a number"
                raise ConfigError(f"soil.{name} = {v!r}: must be {what} in [{lo:g}, {hi:g}]")
        k_lo, k_hi = _k0_range(self.friction_angle_rad)
        if not k_lo <= self.k0 <= k_hi:
            raise ConfigError(
                f"soil.k0 = {self.k0!r}: must be in [{k_lo:.4g}, {k_hi:.4g}] "
                "(gravity pre-stress inside the yield cone at this friction angle)"
            )

    @classmethod
    def from_config(cls, table: dict) -> "SoilSpec":
        """Build from a TOML [soil] table: keys are the field names (SI), except angles, which
        are given as `friction_angle_deg` / `dilatancy_angle_deg` and converted here once."""
        kw = dict(table)
        for ang, lo in (("friction_angle", 5.0), ("dilatancy_angle", 0.0)):
            if f"{ang}_deg" in kw:
                v = kw.pop(f"{ang}_deg")
                if not isinstance(v, (int, float)) or isinstance(v, bool) or not lo <= v <= 50.0:
                    raise ConfigError(
                        f"soil.{ang}_deg = {v!r}: must be a number in [{lo:g}, 50] deg"
                    )
                kw[f"{ang}_rad"] = math.radians(v)
        names = {f.name for f in dataclasses.fields(cls)}
        for key in kw:
            if key not in names:
                raise ConfigError(f"soil.{key}: unknown field; allowed: {', '.join(sorted(names))}")
        for f in dataclasses.fields(cls):
            if f.name not in kw:
                continue
            v = kw[f.name]
            if f.type is int and not (isinstance(v, int) and not isinstance(v, bool)):
                raise ConfigError(f"soil.{f.name} = {v!r}: must be an integer")
            if f.type is float and isinstance(v, int) and not isinstance(v, bool):
                kw[f.name] = float(v)  # TOML writes 100000 as an integer
        return cls(**kw)

    @property
    def target_sinkage_m(self) -> float:
        """Bekker sinkage at the plate pressure (m): the competition's target."""
        return bekker_sinkage(self.pressure_Pa, self.bekker_b_m, self.bekker_k_c,
                              self.bekker_k_phi, self.bekker_n)


@dataclasses.dataclass(frozen=True)
class SoilResult:
    """Outcome of one plate test.

    Attributes:
        sinkage_m: plate settlement at the full pressure (m, positive down).
        pressure_history_Pa: (n_load_steps + 1,) plate pressure, starting at 0 (Pa).
        sinkage_history_m: (n_load_steps + 1,) settlement at those pressures (m).
        converged: every load step met the Newton tolerance (always True on return, since a
            failed step raises SimulationError; kept for callers that log results).
        newton_iterations: (n_load_steps,) Newton iterations (linear solves) per step.
    """

    sinkage_m: float
    pressure_history_Pa: np.ndarray
    sinkage_history_m: np.ndarray
    converged: bool
    newton_iterations: np.ndarray


def bekker_sinkage(pressure_Pa: float, b_m: float, k_c: float, k_phi: float, n: float) -> float:
    """Sinkage z (m) from Bekker's law p = (k_c / b + k_phi) z^n.

    k_c in N/m^(n+1), k_phi in N/m^(n+2), b in m (plate radius for a circular plate, as in the
    study), pressure in Pa.
    """
    modulus = k_c / b_m + k_phi  # N/m^(n+2)
    if not (pressure_Pa >= 0.0 and modulus > 0.0 and n > 0.0):
        raise ConfigError(f"bekker: pressure {pressure_Pa!r} Pa must be >= 0, k_c/b + k_phi "
                          f"{modulus!r} and n {n!r} must be > 0")
    return float((pressure_Pa / modulus) ** (1.0 / n))


def _dp_constants(phi, psi):
    """Drucker-Prager eta, xi (friction, cohesion) and eta_bar (flow) from Mohr-Coulomb
    angles, outer cone (triaxial compression, the state under a loaded plate)."""
    s, sp = jnp.sin(phi), jnp.sin(psi)
    root3 = math.sqrt(3.0)
    eta = 6 * s / (root3 * (3 - s))
    xi = 6 * jnp.cos(phi) / (root3 * (3 - s))
    return eta, xi, 6 * sp / (root3 * (3 - sp))


def _k0_range(phi: float) -> tuple:
    """K0 interval for which sigma_h = K0 sigma_v is inside the cone at every depth (c >= 0)."""
    eta = float(_dp_constants(phi, 0.0)[0])
    t = eta / math.sqrt(3.0)
    return (1 - t) / (1 + 2 * t), (1 + t) / (1 - 2 * t) if 2 * t < 1 else math.inf


def _return_map(eps, eps_p_old, sig0, mat):
    """Stress and plastic strain at one Gauss point (closed-form Drucker-Prager return).

    eps, eps_p_old: (4,) engineering strains [rr, zz, tt, gamma_rz] (1); sig0: (4,) pre-stress
    (Pa); mat: (G, K, eta, xi, eta_bar, c). Returns sigma (4,) Pa and eps_p (4,).
    """
    g, k, eta, xi, eta_b, c = mat
    ee = eps - eps_p_old
    tr = ee[0] + ee[1] + ee[2]
    dev = jnp.array([ee[0] - tr / 3, ee[1] - tr / 3, ee[2] - tr / 3, ee[3] / 2])
    sig_tr = sig0 + jnp.concatenate([k * tr + 2 * g * dev[:3], 2 * g * dev[3:]])
    p_tr = (sig_tr[0] + sig_tr[1] + sig_tr[2]) / 3
    s_tr = sig_tr - p_tr * jnp.array([1.0, 1.0, 1.0, 0.0])
    j2 = 0.5 * (s_tr[0] ** 2 + s_tr[1] ** 2 + s_tr[2] ** 2) + s_tr[3] ** 2
    # Double-where keeps the derivative of sqrt finite at a purely hydrostatic state.
    q = jnp.where(j2 > 0, jnp.sqrt(jnp.where(j2 > 0, j2, 1.0)), 0.0)
    f_tr = q + eta * p_tr - xi * c
    dgam = f_tr / (g + k * eta * eta_b)
    on_cone = q - g * dgam >= 0
    scale = jnp.where(on_cone, 1 - g * dgam / jnp.where(q > 0, q, 1.0), 0.0)
    p_new = jnp.where(on_cone, p_tr - k * eta_b * dgam, xi * c / eta)
    sig_pl = s_tr * scale + p_new * jnp.array([1.0, 1.0, 1.0, 0.0])
    sig = jnp.where(f_tr > 0, sig_pl, sig_tr)
    # Plastic strain = total minus elastic strain of the stress change from the pre-stress.
    ds = sig - sig0
    pm = (ds[0] + ds[1] + ds[2]) / 3
    e_el = jnp.array([pm / (3 * k) + (ds[0] - pm) / (2 * g), pm / (3 * k) + (ds[1] - pm) / (2 * g),
                      pm / (3 * k) + (ds[2] - pm) / (2 * g), ds[3] / g])
    return sig, eps - e_el


@functools.lru_cache(maxsize=8)
def _solver(layout: tuple):
    """Jitted plate test for one mesh/load-step layout (built once, reused for every call).

    The returned function maps theta = (rho, E, nu, phi, c, psi, K0, g, p, rtol), shape (10,),
    to (settlement per step (n_steps,) m, converged (n_steps,), iterations (n_steps,),
    residual norms (n_steps,) N).
    """
    a, big_r, big_h, nrp, nro, nz, n_steps, max_it = layout
    mesh = build_mesh(a, big_r, big_h, nrp, nro, nz)
    b = jnp.asarray(mesh.b_bar)
    w = jnp.asarray(mesh.weight)
    depth = jnp.asarray(mesh.gp_depth)
    edofs = jnp.asarray(mesh.element_dofs)
    n = mesh.n_free
    plate_force_dir = jnp.zeros(n).at[mesh.plate_dof].set(-math.pi * a**2)  # per Pa, downward

    nb, m = mesh.n_blocks, mesh.block_size
    ke_index = jnp.asarray(mesh.ke_index)
    pad_eye = jnp.asarray(mesh.pad_mask[:, :, None] * np.eye(m))  # identity on padding slots

    def assemble_vec(fe):
        return jnp.zeros(n + 1).at[edofs].add(fe)[:n]

    def assemble_blocks(ke):
        kb = jnp.zeros(nb * 3 * m * m + 1).at[ke_index].add(ke)[:-1].reshape(nb, 3, m, m)
        return kb.at[:, 1].add(pad_eye)

    def solve(kb, r):
        return block_tridiagonal_solve(kb, r.reshape(nb, m)).reshape(n)

    def element_force(ue, b_e, w_e, eps_p_e, sig0_e, mat):
        eps = jnp.einsum("gij,j->gi", b_e, ue)
        sig, eps_p = jax.vmap(_return_map, (0, 0, 0, None))(eps, eps_p_e, sig0_e, mat)
        fe = jnp.einsum("gij,gi,g->j", b_e, sig, w_e)
        return fe, (fe, eps_p)

    element_tangent = jax.vmap(jax.jacfwd(element_force, has_aux=True), (0, 0, 0, 0, 0, None))

    def run(theta):
        rho, e_mod, nu, phi, c, psi, k0, grav, pressure, rtol = theta
        g_mod = e_mod / (2 * (1 + nu))
        k_mod = e_mod / (3 * (1 - 2 * nu))
        eta, xi, eta_b = _dp_constants(phi, psi)
        mat = (g_mod, k_mod, eta, xi, eta_b, c)
        sv = -rho * grav * depth  # (n_elem, 4) vertical pre-stress, Pa
        sig0 = jnp.stack([k0 * sv, sv, k0 * sv, jnp.zeros_like(sv)], axis=-1)
        # Nodal body force that the pre-stress balances exactly (discrete K0 procedure).
        f_grav = assemble_vec(jnp.einsum("egij,egi,eg->ej", b, sig0, w))
        tol = rtol * pressure * math.pi * a**2

        def evaluate(u, eps_p):
            ue = jnp.concatenate([u, jnp.zeros(1)])[edofs]
            ke, (fe, eps_p_new) = element_tangent(ue, b, w, eps_p, sig0, mat)
            return assemble_vec(fe), assemble_blocks(ke), eps_p_new

        def load_step(carry, lam):
            u, eps_p = carry
            f_ext = f_grav + lam * pressure * plate_force_dir

            def cond(s):
                _, it, res, _, _ = s
                rn = jnp.linalg.norm(res)
                return (rn > tol) & (it < max_it) & jnp.isfinite(rn)

            def body(s):
                u_i, it, res, kmat, _ = s
                u_i = u_i - solve(kmat, res)
                fint, kmat, epn = evaluate(u_i, eps_p)
                return u_i, it + 1, fint - f_ext, kmat, epn

            fint, kmat, epn = evaluate(u, eps_p)
            u, it, res, _, epn = jax.lax.while_loop(cond, body, (u, 0, fint - f_ext, kmat, epn))
            rn = jnp.linalg.norm(res)
            return (u, epn), (-u[mesh.plate_dof], rn <= tol, it, rn)

        lams = jnp.arange(1, n_steps + 1) / n_steps
        init = (jnp.zeros(n), jnp.zeros(b.shape[:3]))
        _, out = jax.lax.scan(load_step, init, lams)
        return out

    return jax.jit(run), mesh


def _layout(spec: SoilSpec) -> tuple:
    return (spec.plate_radius_m, spec.block_radius_m, spec.block_depth_m, spec.n_r_plate,
            spec.n_r_outer, spec.n_z, spec.n_load_steps, spec.max_newton_iterations)


def _theta(density, youngs, spec: SoilSpec) -> jnp.ndarray:
    return jnp.array([density, youngs, spec.poisson_ratio, spec.friction_angle_rad,
                      spec.cohesion_Pa, spec.dilatancy_angle_rad, spec.k0, spec.gravity_m_s2,
                      spec.pressure_Pa, spec.newton_rtol], dtype=jnp.float64)


def simulate_sinkage(density_kg_m3: float, youngs_modulus_Pa: float, spec: SoilSpec) -> SoilResult:
    """Push the plate to spec.pressure_Pa on a block of this density and Young's modulus.

    Raises ConfigError for a non-finite or non-positive parameter and SimulationError naming the
    first load step whose Newton iteration did not reach the tolerance.
    """
    for name, v in (("density_kg_m3", density_kg_m3), ("youngs_modulus_Pa", youngs_modulus_Pa)):
        if not (np.isfinite(v) and v > 0):
            raise ConfigError(f"soil {name} = {v!r}: must be a finite number > 0")
    run, _ = _solver(_layout(spec))
    out = run(_theta(density_kg_m3, youngs_modulus_Pa, spec))
    sink, ok, its, res = (np.asarray(x) for x in out)
    if not ok.all():
        k = int(np.argmin(ok))
        raise SimulationError(
            f"soil plate test (rho={density_kg_m3:g} kg/m^3, E={youngs_modulus_Pa:g} Pa): Newton "
            f"did not converge at load step {k + 1}/{spec.n_load_steps} "
            f"(p = {spec.pressure_Pa * (k + 1) / spec.n_load_steps:g} Pa, residual {res[k]:.3g} N "
            f"after {int(its[k])} iterations)"
        )
    steps = np.arange(spec.n_load_steps + 1) / spec.n_load_steps
    return SoilResult(
        sinkage_m=float(sink[-1]),
        pressure_history_Pa=steps * spec.pressure_Pa,
        sinkage_history_m=np.concatenate([[0.0], sink]),
        converged=True,
        newton_iterations=its.astype(int),
    )


def sinkage_objective(spec: SoilSpec):
    """f(x) = |simulated - Bekker target| / target * 100 (percent), x = [rho kg/m^3, E Pa]."""
    target = spec.target_sinkage_m

    def objective(x) -> float:
        x = np.asarray(x, dtype=float)
        if x.shape != (2,):
            raise ConfigError(f"soil objective x has shape {x.shape}: must be (2,) = [density, E]")
        z = simulate_sinkage(float(x[0]), float(x[1]), spec).sinkage_m
        return abs(z - target) / target * 100.0

    return objective


def suggested_bounds() -> np.ndarray:
    """(2, 2) search box [[rho_lo, rho_hi], [E_lo, E_hi]] in kg/m^3 and Pa."""
    return np.array([DENSITY_BOUNDS_KG_M3, YOUNGS_MODULUS_BOUNDS_PA])
