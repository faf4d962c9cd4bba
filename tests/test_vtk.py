"""Frames (jtire.frames) and the ParaView export (jtire.vtk, `jtire export-vtk`) on the coarse ring.

States with known answers: the tire at rest (no displacement, no strain energy), the same tire
moved rigidly (displacement = the move at every node, beads included; still no strain energy:
the strains are invariant), and a state with random nodal perturbations (the per-quad energies
are non-negative and sum to the model's strain energy). The .vtu files must round-trip through
meshio and the .pvd must list every frame with its time.
"""

import xml.etree.ElementTree as ET

import equinox as eqx
import jax
import jax.numpy as jnp
import meshio
import numpy as np
import pytest

from jtire import frames as F
from jtire import vtk
from jtire.cli import main as cli_main
from jtire.physics.geometry_ops import V
from jtire.state import TireState

SHIFT = np.array([0.01, -0.02, 0.03])  # m, the rigid move
REL = 1e-12  # float64 round-off
ZERO_ENERGY = 1e-12  # J/m^2: the strains of a rigid move differ from the reference by round-off only


@pytest.fixture(scope="module")
def states(coarse_tire):
    model, params = coarse_tire.model, coarse_tire.params
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    moved = eqx.tree_at(lambda s: (s.x, s.q), y0, (y0.x + V(*SHIFT), y0.q.at[:3].set(jnp.asarray(SHIFT))))
    key = jax.random.PRNGKey(0)
    noise = jax.random.normal(key, (3,) + y0.x.x.shape) * 1e-3
    bumped = eqx.tree_at(lambda s: s.x, y0, y0.x + V(*noise))
    return model, params, [y0, moved, bumped]


@pytest.fixture(scope="module")
def frames(states):
    model, params, ys = states
    z_road = float(np.min(np.asarray(model.x_ref.z))) - 0.05  # well below: no contact
    return F.frames_from_states(model, params, ys, [0.0, 0.01, 0.02], z_road=z_road)


def test_frame_arrays(states, frames):
    model, params, ys = states
    T, S = model.n_theta, model.n_s
    shapes = {"t": (3,), "x": (3, T, S - 2, 3), "q": (3, 6), "nodes": (3, T, S, 3), "nodes_ref": (T, S, 3),
              "contact_pressure_Pa": (3, T, S), "energy_density_J_per_m2": (3, T, S - 1), "z_road": (3,)}
    assert {k: v.shape for k, v in frames.items()} == shapes
    disp = frames["nodes"] - frames["nodes_ref"][None]
    assert np.max(np.abs(disp[0])) == 0.0
    assert np.allclose(disp[1], SHIFT, rtol=0, atol=1e-15)  # beads ride on the rim: the same move
    assert np.max(np.abs(frames["energy_density_J_per_m2"][:2])) < ZERO_ENERGY
    assert np.all(frames["contact_pressure_Pa"] == 0.0)
    assert np.allclose(frames["nodes"][:, :, 1:-1], frames["x"], rtol=0, atol=0)  # free nodes are x


def test_element_energy_sums_to_the_strain_energy(states, frames):
    model, params, ys = states
    y = ys[2]
    e = np.asarray(F.element_energy(model, params, y.x, y.q))
    total = float(model.strain_energy(params, model.assemble(y.x, y.q)))
    assert total > 0 and np.all(e >= 0)
    assert e.sum() == pytest.approx(total, rel=REL)
    assert np.allclose(frames["energy_density_J_per_m2"][2], e / np.asarray(model.quad_area), rtol=REL)


def test_energy_stays_near_a_moved_node(states):
    """Moving one free node strains only the edges, shear and hinges that touch it or its neighbours:
    the energy must land within two segments and two elements of the node."""
    model, params, ys = states
    y0 = ys[0]
    t0, j0 = 5, model.n_s // 2 - 1  # free column j0 is real node j0 + 1
    x = y0.x + V(*(jnp.zeros_like(y0.x.x).at[t0, j0].set(d) for d in (0.0, 0.0, 2e-3)))
    e = np.asarray(F.element_energy(model, params, x, y0.q))
    T = model.n_theta
    dt = np.minimum((np.arange(T) - t0) % T, (t0 - np.arange(T)) % T)
    i = np.arange(model.n_s - 1)
    far = (dt[:, None] > 2) | (np.abs(i[None, :] - (j0 + 1)) > 2)
    assert e.sum() > 0 and np.all(e[far] == 0.0)


def test_vtu_round_trip_and_pvd(tmp_path, states, frames):
    model, _, _ = states
    T, S = model.n_theta, model.n_s
    pvd = vtk.write_series(frames, tmp_path / "vtk")
    root = ET.parse(pvd).getroot()
    sets = root.find("Collection").findall("DataSet")
    assert [float(d.get("timestep")) for d in sets] == [0.0, 0.01, 0.02]
    for k, d in enumerate(sets):
        m = meshio.read(tmp_path / "vtk" / d.get("file"))
        assert m.points.shape == (T * S, 3)
        assert len(m.cells) == 1 and m.cells[0].type == "quad" and m.cells[0].data.shape == (T * (S - 1), 4)
        assert np.allclose(m.points, frames["nodes"][k].reshape(-1, 3), rtol=0, atol=1e-15)
        assert np.allclose(m.point_data["displacement_m"], (frames["nodes"][k] - frames["nodes_ref"]).reshape(-1, 3),
                           rtol=0, atol=1e-15)
        assert np.array_equal(m.point_data["contact_pressure_Pa"], frames["contact_pressure_Pa"][k].reshape(-1))
        assert np.allclose(m.cell_data["energy_density_J_per_m2"][0],
                           frames["energy_density_J_per_m2"][k].reshape(-1), rtol=0, atol=0)
    # quad (t, i) joins nodes i, i+1 of meridians t and t+1, wrapping around
    cells = vtk.quad_cells(T, S)
    assert cells[(T - 1) * (S - 1)].tolist() == [(T - 1) * S, (T - 1) * S + 1, 1, 0]


def test_export_vtk_command(tmp_path, frames, capsys):
    run = tmp_path / "run"
    F.save_frames(run / "frames.npz", frames)
    assert cli_main(["--no-cache", "export-vtk", str(run)]) == 0
    assert (run / "vtk" / "tire.pvd").is_file() and len(list((run / "vtk").glob("tire_*.vtu"))) == 3
    assert "wrote 3 frames" in capsys.readouterr().out
    assert cli_main(["--no-cache", "export-vtk", str(tmp_path / "nothing")]) == 2
    assert "no such frames file" in capsys.readouterr().err
