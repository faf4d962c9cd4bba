"""Soil plate test: Bekker target, elastic rigid punch, invariants, config validation."""

import dataclasses
import math
import re
import tomllib
from pathlib import Path

import jax.numpy as jnp
import numpy as np
import pytest

from jtire.calibration.soil.block import (
    SoilSpec,
    bekker_sinkage,
    simulate_sinkage,
    sinkage_objective,
    suggested_bounds,
    _layout,
    _solver,
)
from jtire.calibration.soil.mesh import block_tridiagonal_solve
from jtire.errors import ConfigError, SimulationError

REFERENCE = Path(__file__).resolve().parents[1] / "configs" / "reference_xone_xda.toml"

# Elastic check: a block 40 plate radii wide and deep, plasticity switched off (huge cohesion).
ELASTIC = SoilSpec(block_radius_m=6.0, block_depth_m=6.0, n_r_plate=6, n_r_outer=18, n_z=22,
                   cohesion_Pa=1e11, n_load_steps=1)


@pytest.fixture(scope="module")
def spec():
    return SoilSpec()


def test_bekker_reproduces_study_table():
    bek = tomllib.loads(REFERENCE.read_text())["bekker"]
    z = bekker_sinkage(bek["pressure_kPa"] * 1e3, bek["plate_radius_m"],
                       bek["k_c_kN_per_m_n_plus_1"] * 1e3, bek["k_phi_kN_per_m_n_plus_2"] * 1e3,
                       bek["n"])
    # Table value has 4 decimals in mm: agreement to 1e-4 mm means the same inputs.
    assert abs(z * 1e3 - bek["sinkage_mm"]) < 1e-4
    assert abs(SoilSpec().target_sinkage_m * 1e3 - bek["sinkage_mm"]) < 1e-4
    # b is the plate radius: the diameter would give 25.18 mm, not the study's value.
    z_diam = bekker_sinkage(1e5, 0.30, 16.03e3, 1262.53e3, 0.7)
    assert abs(z_diam * 1e3 - bek["sinkage_mm"]) > 1.0


@pytest.mark.parametrize("nu", [0.2, 0.3, 0.45])
def test_elastic_rigid_punch_matches_boussinesq(nu):
    e_mod = 5e6
    res = simulate_sinkage(1600.0, e_mod, dataclasses.replace(ELASTIC, poisson_ratio=nu))
    exact = ELASTIC.pressure_Pa * math.pi * ELASTIC.plate_radius_m * (1 - nu**2) / (2 * e_mod)
    ratio = res.sinkage_m / exact
    # Both errors make the model stiffer than the half-space: the fixed base at 40 radii depth
    # (about 3 %) and the displacement-based mesh with 6 elements across the plate (2-3 %).
    # Measured 0.941 at nu = 0.3; 8 % allows both, and ratio <= 1 checks their sign.
    assert 0.92 < ratio <= 1.0, ratio
    # A linear problem: one Newton step solves it exactly.
    assert res.newton_iterations.tolist() == [1]


def test_elastic_sinkage_independent_of_density():
    # Without yielding, the pre-stress is in equilibrium with gravity and cannot move the plate.
    z1 = simulate_sinkage(1200.0, 5e6, ELASTIC).sinkage_m
    z2 = simulate_sinkage(2200.0, 5e6, ELASTIC).sinkage_m
    assert abs(z1 - z2) < 1e-9 * z1


def test_sinkage_decreases_with_E_exactly_as_one_over_E(spec):
    z1 = simulate_sinkage(1700.0, 1e6, spec).sinkage_m
    z2 = simulate_sinkage(1700.0, 2e6, spec).sinkage_m
    assert z2 < z1
    # Perfect plasticity with an E-independent pre-stress: displacements scale as 1/E; the
    # tolerance is the Newton tolerance (1e-8 of the plate force) with margin.
    assert abs(z1 / z2 - 2.0) < 1e-6


def test_density_changes_plastic_sinkage(spec):
    loose = simulate_sinkage(1200.0, 2e6, spec)
    dense = simulate_sinkage(2200.0, 2e6, spec)
    # More weight = more confinement = less yielding; measured 22.3 vs 19.1 mm (16 %).
    assert loose.sinkage_m > 1.10 * dense.sinkage_m
    # And plasticity is active: sinkage well above the elastic rigid punch on the same block.
    elastic = simulate_sinkage(1200.0, 2e6, dataclasses.replace(spec, cohesion_Pa=1e11))
    assert dense.sinkage_m > 1.5 * elastic.sinkage_m


def test_history_monotone(spec):
    res = simulate_sinkage(1500.0, 3e6, spec)
    assert res.converged
    n = spec.n_load_steps + 1
    assert res.pressure_history_Pa.shape == res.sinkage_history_m.shape == (n,)
    assert res.pressure_history_Pa[0] == 0.0 and res.sinkage_history_m[0] == 0.0
    assert res.pressure_history_Pa[-1] == spec.pressure_Pa
    assert res.sinkage_history_m[-1] == res.sinkage_m
    assert np.all(np.diff(res.pressure_history_Pa) > 0)
    assert np.all(np.diff(res.sinkage_history_m) > 0)
    # Yielding softens the plate: later increments of sinkage are larger (convex curve).
    assert np.diff(res.sinkage_history_m)[-1] > 2 * np.diff(res.sinkage_history_m)[0]


def test_objective_zero_on_valley_and_compiles_once(spec):
    f = sinkage_objective(spec)
    target = spec.target_sinkage_m
    e0 = 2e6
    for rho in (1300.0, 2000.0):
        e_star = simulate_sinkage(rho, e0, spec).sinkage_m * e0 / target  # uses 1/E scaling
        assert f(np.array([rho, e_star])) < 1e-5  # percent; Newton tolerance level
        assert f(np.array([rho, 2 * e_star])) == pytest.approx(50.0, rel=1e-6)
    run, _ = _solver(_layout(spec))
    assert run._cache_size() == 1  # traced parameters: no re-jit per call


def test_bounds_contain_target(spec):
    (rho_lo, rho_hi), (e_lo, e_hi) = suggested_bounds()
    target = spec.target_sinkage_m
    # Softest corner sinks more than the target, stiffest corner less: the valley crosses the box.
    assert simulate_sinkage(rho_lo, e_lo, spec).sinkage_m > target
    assert simulate_sinkage(rho_hi, e_hi, spec).sinkage_m < target


def test_collapse_raises_with_load_step(spec):
    weak = dataclasses.replace(spec, cohesion_Pa=1e3, friction_angle_rad=math.radians(25.0),
                               k0=1 - math.sin(math.radians(25.0)))
    with pytest.raises(SimulationError, match=r"load step \d+/10"):
        simulate_sinkage(1200.0, 2e6, weak)


@pytest.mark.parametrize(
    "table, field",
    [
        ({"poisson_ratio": 0.6}, "soil.poisson_ratio"),
        ({"pressure_Pa": -5.0}, "soil.pressure_Pa"),
        ({"n_z": 3.5}, "soil.n_z"),
        ({"friction_angle_deg": 70.0}, "soil.friction_angle_deg"),
        ({"friction_angle_rad": 1.2}, "soil.friction_angle_rad"),
        ({"k0": 0.05}, "soil.k0"),
        ({"plate_radius": 0.15}, "soil.plate_radius"),
    ],
)
def test_bad_config_rejected_with_one_line(table, field):
    with pytest.raises(ConfigError) as err:
        SoilSpec.from_config(table)
    msg = str(err.value)
    assert msg.startswith(field) and "\n" not in msg
    assert re.search(r"must|allowed", msg)


def test_from_config_converts_units():
    spec = SoilSpec.from_config({"friction_angle_deg": 30, "pressure_Pa": 100000, "n_z": 14})
    assert spec == SoilSpec()


def test_block_tridiagonal_solve_matches_dense():
    rng = np.random.default_rng(0)
    nb, m = 5, 4
    kb = rng.normal(size=(nb, 3, m, m))
    kb[:, 1] += 8 * np.eye(m)  # well conditioned, like a stiffness below collapse
    kb[0, 0] = 0.0  # no block above the first row
    kb[-1, 2] = 0.0  # nor below the last
    dense = np.zeros((nb * m, nb * m))
    for j in range(nb):
        dense[j * m:(j + 1) * m, j * m:(j + 1) * m] = kb[j, 1]
        if j > 0:
            dense[j * m:(j + 1) * m, (j - 1) * m:j * m] = kb[j, 0]
        if j < nb - 1:
            dense[j * m:(j + 1) * m, (j + 1) * m:(j + 2) * m] = kb[j, 2]
    rhs = rng.normal(size=(nb, m))
    x = np.asarray(block_tridiagonal_solve(jnp.asarray(kb), jnp.asarray(rhs)))
    # Same linear system, exact algebra: only rounding differs (condition number ~ 10).
    expected = np.linalg.solve(dense, rhs.ravel())
    np.testing.assert_allclose(x.ravel(), expected, rtol=1e-10, atol=1e-12)


@pytest.mark.slow
def test_elastic_punch_converges_with_block_and_mesh():
    # Larger blocks and finer meshes remove the two (stiffening) errors: the ratio rises toward 1.
    layouts = [(1.5, 6, 10, 14), (3.0, 6, 14, 18), (6.0, 6, 18, 22), (9.0, 8, 26, 30)]
    ratios = []
    for size, nrp, nro, nz in layouts:
        spec = dataclasses.replace(ELASTIC, block_radius_m=size, block_depth_m=size,
                                   n_r_plate=nrp, n_r_outer=nro, n_z=nz)
        exact = spec.pressure_Pa * math.pi * spec.plate_radius_m * (1 - 0.3**2) / (2 * 5e6)
        ratios.append(simulate_sinkage(1600.0, 5e6, spec).sinkage_m / exact)
    assert np.all(np.diff(ratios) > 0) and ratios[-1] <= 1.0, ratios
    assert ratios[-1] > 0.95, ratios  # measured 0.959 at 60 radii and 8 elements per radius
