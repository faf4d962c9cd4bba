"""Cross-field checks of the tire section (jtire.config.tire_from_dict): what the mesh cannot build,
or would build as something else than the file says, is refused with one line naming the field
and its allowed range; what is accepted up to those limits builds a mesh whose belt carries tread
everywhere (the contact goes through the tread)."""

import copy
import tomllib

import numpy as np
import pytest

from jtire.config import tire_from_dict
from jtire.errors import ConfigError
from jtire.mesh import build_mesh

from .conftest import TIRE_TOML


@pytest.fixture(scope="module")
def raw():
    return tomllib.loads(TIRE_TOML.read_text())


def _with(raw, **tire):
    r = copy.deepcopy(raw)
    r["tire"].update(tire)
    return r


def _limits(t):
    """The allowed ranges, derived here from the mesh's rules (docstring of _check_geometry), mm."""
    room = (t["outer_diameter_mm"] - t["rim_diameter_mm"]) / 2 - 0.75 * t["section_height_mm"]
    hb = t["belt_width_mm"] / 2
    return room, max(hb, hb**2 / (2 * (room - t["tread_depth_mm"])))


BAD = [  # (field, value, words in the message[, other fields set with it])
    ("tread_width_mm", 1000.0, "tire.tread_width_mm = 1000: must be in [tire.belt_width_mm = 360, "
                               "tire.section_width_mm = 445]"),
    ("tread_width_mm", 300.0, "tire.tread_width_mm = 300: must be in [tire.belt_width_mm = 360"),
    ("crown_radius_mm", 50.0, "tire.crown_radius_mm = 50: must be above 523.6 mm"),
    ("crown_radius_mm", 500.0, "tire.crown_radius_mm = 500: must be above 523.6 mm"),
    ("tread_depth_mm", 60.0, "tire.tread_depth_mm = 60: must be below 55.94 mm"),
    ("flange_height_mm", 99.0, "tire.flange_height_mm = 99: must be below the widest point, 75 mm above the rim",
     dict(outer_diameter_mm=871.5, section_height_mm=150.0)),
    ("widest_point_ratio", 0.3, "tire.flange_height_mm = 99: must be below the widest point, 45 mm above the rim",
     dict(outer_diameter_mm=871.5, section_height_mm=150.0, flange_height_mm=99.0)),
    ("widest_point_ratio", 0.85, "tire.widest_point_ratio = 0.85: must be in [0.2, 0.8]"),
    ("widest_point_ratio", 0.79, "tire.widest_point_ratio = 0.79: must be below 0.7676", dict(crown_radius_mm=600.0)),
    ("rim_width_mm", 900.0, "tire.rim_width_mm = 900: must be below tire.section_width_mm = 445"),
    ("belt_width_mm", 300.0, "tire.belt_width_mm = 300: must lie between tire.rim_width_mm = 355.6"),
    ("section_height_mm", 300.0, "tire.section_height_mm = 300: must equal (outer_diameter_mm - rim_diameter_mm)"),
]


@pytest.mark.parametrize("bad", BAD, ids=[f"{b[0]}={b[1]:g}" for b in BAD])
def test_bad_geometry_is_one_line_naming_the_field(raw, bad):
    field, value, words, *other = bad
    with pytest.raises(ConfigError) as e:
        tire_from_dict(_with(raw, **{field: value}, **(other[0] if other else {})))
    msg = str(e.value)
    assert words in msg and "\n" not in msg


def test_the_crown_and_tread_limits_are_the_meshs(raw):
    t = raw["tire"]
    room, r_min = _limits(t)
    assert room == pytest.approx(55.9375) and r_min == pytest.approx(180**2 / (2 * (room - 25.0)))
    for field, inside, outside in [("crown_radius_mm", r_min * 1.001, r_min * 0.999),
                                   ("tread_depth_mm", None, room * 1.0001)]:
        with pytest.raises(ConfigError, match=field):
            tire_from_dict(_with(raw, **{field: outside}))
        if inside is not None:
            tire_from_dict(_with(raw, **{field: inside}))
    # a crown arc must be wider in radius than the belt's half-width even with room to spare
    narrow = dict(belt_width_mm=358.0, tread_depth_mm=1.0)
    _, r_min_n = _limits(t | narrow)
    assert r_min_n > 179.0  # half-width 179 mm: the arc rule is the binding one only if room is big
    with pytest.raises(ConfigError, match="crown_radius_mm = 170"):
        tire_from_dict(_with(raw, crown_radius_mm=170.0, **narrow))


@pytest.mark.parametrize("tire", [
    {},  # the shipped tire
    {"crown_radius_mm": 530.0},  # just above the limit: the belt edge just inside the tread zone
    {"tread_depth_mm": 40.0, "crown_radius_mm": 1100.0},
    {"tread_width_mm": 360.0},  # tread = belt
    {"tread_width_mm": 445.0},  # tread = section
    {"flange_height_mm": 99.0},
])
def test_accepted_geometry_builds_a_mesh_with_tread_over_the_whole_belt(raw, tire):
    spec = tire_from_dict(_with(raw, **tire))
    m = build_mesh(spec.geometry, spec.masses, spec.n_theta, spec.n_side, spec.n_crown)
    belt = np.flatnonzero(m.belt_mask)
    assert belt.size == spec.n_crown + 1
    # every belt node carries the full tread depth: the file's tread is what the mesh built
    np.testing.assert_allclose(m.tread_depth[belt], spec.geometry.tread_depth, rtol=1e-12)
