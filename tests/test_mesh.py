"""The mesh reproduces the tire's data and is mirror symmetric."""

import dataclasses

import numpy as np
import pytest

from jtire.mesh import N_PARTS, PART_NAMES, build_mesh, section_profile


def test_masses_match_the_data(spec):
    m = build_mesh(spec.geometry, spec.masses, spec.n_theta, spec.n_side, spec.n_crown).masses()
    # by construction (areal densities from the data): to rounding
    assert m["tire_kg"] == pytest.approx(80.08, rel=1e-12)
    assert m["belt_kg"] == pytest.approx(70.75, rel=1e-12)
    assert m["rim_kg"] == pytest.approx(31.17, rel=1e-12)
    # inertias are a result, not an input: within 20 % of the study's (mass at the mid-surface,
    # not spread through the tread, makes them low; reported beside 17.40 and 10.49)
    assert m["belt_Iy_kgm2"] == pytest.approx(17.4026, rel=0.2)
    assert m["belt_Ix_kgm2"] == pytest.approx(10.491, rel=0.2)


def test_non_belt_inertia_is_the_rest_of_the_tire(spec):
    mesh = build_mesh(spec.geometry, spec.masses, spec.n_theta, spec.n_side, spec.n_crown)
    m = mesh.masses()
    x, z = mesh.nodes[..., 0], mesh.nodes[..., 2]
    # a partition of the tire's nodes: belt + rest = the whole tire's spin inertia, to rounding
    assert m["belt_Iy_kgm2"] + m["nonbelt_Iy_kgm2"] == pytest.approx(float((mesh.node_mass * (x**2 + z**2)).sum()),
                                                                        rel=1e-12)
    # the rest (9.33 kg of sidewalls and beads) lies between the rim and the tread: m r_rim^2 <= I <= m R0^2
    rest = m["tire_kg"] - m["belt_kg"]
    g = spec.geometry
    assert rest * g.rim_radius**2 < m["nonbelt_Iy_kgm2"] < rest * g.outer_radius**2


def test_section_is_symmetric_and_has_every_part(spec):
    y, r, part = section_profile(spec.geometry, spec.n_side, spec.n_crown)
    np.testing.assert_allclose(y, -y[::-1], atol=1e-12)
    np.testing.assert_allclose(r, r[::-1], atol=1e-12)
    assert set(part.tolist()) == set(range(N_PARTS))
    assert r.max() == pytest.approx(spec.geometry.outer_radius - spec.geometry.tread_depth, abs=1e-9)
    assert np.abs(y).max() == pytest.approx(spec.geometry.section_width / 2, abs=2e-3)


def test_refined_mesh_keeps_masses(spec):
    fine = dataclasses.replace(spec, n_theta=96, n_side=10, n_crown=8)
    m = build_mesh(fine.geometry, fine.masses, fine.n_theta, fine.n_side, fine.n_crown).masses()
    assert m["belt_kg"] == pytest.approx(70.75, rel=1e-12)


@pytest.mark.parametrize("kw", [dict(n_side=3), dict(n_side=7), dict(n_crown=5), dict(n_crown=2)])
def test_bad_mesh_sizes_are_refused(spec, kw):
    args = dict(n_side=spec.n_side, n_crown=spec.n_crown) | kw
    with pytest.raises(ValueError, match="mesh.n_"):
        section_profile(spec.geometry, **args)


def test_part_names():
    assert PART_NAMES[-1] == "crown" and len(PART_NAMES) == 6
