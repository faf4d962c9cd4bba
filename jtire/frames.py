"""Frames of a simulation for visualisation: deformed mid-surface, contact pressure, strain energy.

`frames_from_states(model, params, states, times, z_road)` turns recorded TireStates into a dict of
plain arrays, saved as `frames.npz` (`save_frames`) and turned into ParaView files by `jtire.vtk`.
The file is self-contained: the exporter needs no config, mesh or model. Its arrays (FRAME_KEYS):

    t                        (n,)             s, time of each frame
    x                        (n, T, S-2, 3)   m, free-node positions (TireState.x)
    q                        (n, 6)           rim coordinates (x, y, z m; rx, ry, rz rad)
    nodes                    (n, T, S, 3)     m, every real mid-surface node (beads placed by the rim)
    nodes_ref                (T, S, 3)        m, the same nodes on the reference (mould) shape, rim at 0
    contact_pressure_Pa      (n, T, S)        Pa, nodal contact pressure (`contact_pressure.nodal_pressure`)
    energy_density_J_per_m2  (n, T, S-1)      J/m^2, elastic strain energy of each quad over its area
    z_road                   (n,)             m, road height (NaN: no flat road)

T = n_theta, S = real nodes per meridian. Quad (t, i) spans meridians t, t+1 (mod T) and section
nodes i, i+1. The strain energy is the long-term elastic one, 0.5 K (s - s0)^2 per generalized
strain (`TireModel.strain_energy`; the Maxwell branches' stored energy is not included), each
strain's energy shared equally among the quads it belongs to: an edge between its two quads, a
hinge at a node among the quads around the node, shear to its own quad. The shares sum to the
model's strain energy exactly.
"""

import jax
import jax.numpy as jnp
import numpy as np

from .contact_pressure import flat_road, nodal_pressure

FRAME_KEYS = ("t", "x", "q", "nodes", "nodes_ref", "contact_pressure_Pa", "energy_density_J_per_m2", "z_road")


def real_nodes(model, x, q):
    """(T, S, 3) m: the mid-surface's real nodes (beads from the rim pose q, free nodes x)."""
    X = model.assemble(x, q)[:, 1:-1]
    return jnp.stack([X.x, X.y, X.z], axis=-1)


def _around(e):
    """(T, k) values at meridians -> segments: meridian t is shared by segments t-1 and t."""
    return 0.5 * (e + jnp.roll(e, -1, axis=0))


def _along(e):
    """(T, S) values at real nodes -> (T, S-1) section elements: node i is shared by elements i-1
    and i; a bead node (one element) gives its element everything."""
    out = 0.5 * (e[:, :-1] + e[:, 1:])
    return out.at[:, 0].add(0.5 * e[:, 0]).at[:, -1].add(0.5 * e[:, -1])


def element_energy(model, params, x, q):
    """(T, S-1) J: elastic strain energy of each quad (sums to `model.strain_energy`). Traceable."""
    T, S = model.n_theta, model.n_s
    X = model.assemble(x, q)
    d = model.strains(X) - model.s0
    e = 0.5 * model.stiffness(params) * d * d
    sizes = [T * (S - 1), T * (S - 2), T * (S - 1), T * S, T * (S - 2)]  # the order of `model.strains`
    e_mer, e_circ, e_shear, e_mh, e_ch = (a.reshape(T, -1) for a in jnp.split(e, np.cumsum(sizes)[:-1]))
    pad = lambda a: jnp.pad(a, ((0, 0), (1, 1)))  # noqa: E731  free columns -> real columns (beads carry none)
    return _around(e_mer) + _along(pad(e_circ)) + e_shear + _around(_along(e_mh)) + _around(_along(pad(e_ch)))


def frame_fields(model, params, y, z_road, t=0.0, surface=None):
    """One frame (traceable): (nodes (T, S, 3), contact pressure (T, S), energy density (T, S-1)).
    The contact surface is `surface` if given, else the flat road at z_road (NaN: no road)."""
    nodes = real_nodes(model, y.x, y.q)
    energy = element_energy(model, params, y.x, y.q) / model.quad_area
    if surface is None:
        has_road = jnp.isfinite(z_road)
        p = nodal_pressure(model, params, y, flat_road(jnp.where(has_road, z_road, -1e3)), t)
        p = jnp.where(has_road, p, 0.0)
    else:
        p = nodal_pressure(model, params, y, surface, t)
    return nodes, p, energy


def _stack_states(states):
    if isinstance(states, (list, tuple)):
        return jax.tree_util.tree_map(lambda *a: jnp.stack(a), *states)
    return states


def frames_from_states(model, params, states, times, z_road=None, surface=None) -> dict:
    """TireStates -> the frames dict (FRAME_KEYS, numpy arrays; see the module docstring).

    states: a list of TireState, or one TireState whose leaves carry a leading frame axis (n).
    times: (n,) s. z_road: None (no road: zero contact pressure), a height (m) or (n,) heights of
    the flat road. surface: any other rigid surface (a drum, a cleat), used instead of z_road and
    queried at each frame's time."""
    ys = _stack_states(states)
    t = jnp.asarray(times, dtype=jnp.float64).reshape(-1)
    n = t.shape[0]
    if ys.q.shape[0] != n:
        raise ValueError(f"{ys.q.shape[0]} states for {n} times")
    z = jnp.full(n, jnp.nan) if z_road is None else jnp.broadcast_to(jnp.asarray(z_road, dtype=jnp.float64), (n,))
    fields = jax.jit(jax.vmap(lambda y, zi, ti: frame_fields(model, params, y, zi, ti, surface)))
    nodes, p, energy = jax.device_get(fields(ys, z, t))
    x = np.stack([np.asarray(ys.x.x), np.asarray(ys.x.y), np.asarray(ys.x.z)], axis=-1)
    ref = np.asarray(real_nodes(model, model.x_ref, jnp.zeros(6)))
    return {"t": np.asarray(t), "x": x, "q": np.asarray(ys.q), "nodes": np.asarray(nodes), "nodes_ref": ref,
            "contact_pressure_Pa": np.asarray(p), "energy_density_J_per_m2": np.asarray(energy),
            "z_road": np.asarray(z) if surface is None else np.full(n, np.nan)}


def save_frames(path, frames: dict):
    """Write the frames dict as an .npz file (atomically). Returns the path."""
    import io

    from .io import atomic_write_bytes

    buf = io.BytesIO()
    np.savez_compressed(buf, **{k: np.asarray(frames[k]) for k in FRAME_KEYS})
    return atomic_write_bytes(path, buf.getvalue())


def frames_from_outputs(model, outputs) -> dict:
    """The frames recorded by a run under `experiments.program.recording_frames` -> the frames dict.

    outputs: one case's simulate outputs (a dict holding stacked `PhaseOut`s, e.g. "phases"), or a
    list of them (only the first case is taken: one experiment run = one animation). Frames of
    every phase are joined in time order; the samples a phase did not reach (it settled early:
    times inf) are dropped. Contact pressure is on each phase's own surface (road, drum, cleat), so
    z_road is NaN. ValueError when nothing was recorded."""
    if isinstance(outputs, (list, tuple)):
        outputs = outputs[0]
    # the stacked PhaseOut values (`experiments.program`) that carry frames
    found = [v.frames for v in outputs.values() if getattr(v, "frames", None) is not None]
    if not found:
        raise ValueError("no frames were recorded (run the experiment under recording_frames)")
    keys = ("t", "x", "q", "nodes", "contact_pressure_Pa", "energy_density_J_per_m2")
    # each: (phases, n_frames, ...) -> (phases * n_frames, ...)
    cat = {k: np.concatenate([np.asarray(f[k]).reshape((-1,) + np.asarray(f[k]).shape[2:]) for f in found])
           for k in keys}
    ok = np.isfinite(cat["t"])
    order = np.argsort(cat["t"][ok], kind="stable")
    fr = {k: v[ok][order] for k, v in cat.items()}
    # a phase's end and the next one's start are the same instant: keep one frame per time
    keep = np.concatenate([np.diff(fr["t"]) > 0, [True]])
    fr = {k: v[keep] for k, v in fr.items()}
    fr["nodes_ref"] = np.asarray(real_nodes(model, model.x_ref, jnp.zeros(6)))
    fr["z_road"] = np.full(len(fr["t"]), np.nan)
    return fr
