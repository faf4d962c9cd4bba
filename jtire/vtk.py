"""ParaView export: the frames of a run (`frames.npz`, see `jtire.frames`) as .vtu files + a .pvd.

One unstructured grid per frame: the shell mid-surface as quads (T * (S-1) cells over T * S points;
point index t * S + i for section node i of meridian t), with
    point data  displacement_m (3), from the reference shape; contact_pressure_Pa
    cell data   energy_density_J_per_m2 (elastic strain energy per unit reference area)
and a `<name>.pvd` collection listing every frame with its time, which ParaView opens as a time
series. Written with meshio (binary, zlib-compressed .vtu).
"""

from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .errors import ConfigError
from .io import atomic_write_text

REQUIRED = ("t", "nodes", "nodes_ref")


def load_frames(path) -> dict:
    """Read and check a frames.npz (a file, or a run folder holding one). ConfigError if it is
    missing or its arrays do not fit together."""
    path = Path(path)
    if path.is_dir():
        path = path / "frames.npz"
    if not path.is_file():
        raise ConfigError(f"{path}: no such frames file (write one with `jtire run --frames N`)")
    try:
        with np.load(path) as z:
            fr = {k: z[k] for k in z.files}
    except (OSError, ValueError) as e:
        raise ConfigError(f"{path}: not a readable .npz file ({e})") from None
    missing = [k for k in REQUIRED if k not in fr]
    if missing:
        raise ConfigError(f"{path}: missing arrays {', '.join(missing)} (has {', '.join(sorted(fr))})")
    n = fr["t"].shape[0]
    T, S = fr["nodes_ref"].shape[:2]
    want = {"nodes": (n, T, S, 3), "contact_pressure_Pa": (n, T, S), "energy_density_J_per_m2": (n, T, S - 1)}
    for k, shape in want.items():
        if k in fr and fr[k].shape != shape:
            raise ConfigError(f"{path}: {k} has shape {fr[k].shape}, expected {shape} (n={n} frames, T={T}, S={S})")
    return fr


def quad_cells(T: int, S: int) -> np.ndarray:
    """(T * (S-1), 4) point indices of the mid-surface quads, ordered (segment t, element i)."""
    t, i = np.meshgrid(np.arange(T), np.arange(S - 1), indexing="ij")
    t1 = (t + 1) % T
    return np.stack([t * S + i, t * S + i + 1, t1 * S + i + 1, t1 * S + i], axis=-1).reshape(-1, 4)


def frame_mesh(frames: dict, k: int):
    """The meshio.Mesh of frame k."""
    import meshio

    ref = np.asarray(frames["nodes_ref"], float)
    T, S = ref.shape[:2]
    nodes = np.asarray(frames["nodes"][k], float)
    point_data = {"displacement_m": (nodes - ref).reshape(-1, 3)}
    if "contact_pressure_Pa" in frames:
        point_data["contact_pressure_Pa"] = np.asarray(frames["contact_pressure_Pa"][k], float).reshape(-1)
    cell_data = {}
    if "energy_density_J_per_m2" in frames:
        cell_data["energy_density_J_per_m2"] = [np.asarray(frames["energy_density_J_per_m2"][k], float).reshape(-1)]
    return meshio.Mesh(nodes.reshape(-1, 3), [("quad", quad_cells(T, S))], point_data=point_data,
                       cell_data=cell_data)


def pvd_text(entries) -> str:
    """A ParaView collection: entries is [(time s, file name relative to the .pvd)]."""
    rows = "\n".join(f'    <DataSet timestep="{t!r}" part="0" file={quoteattr(str(f))}/>' for t, f in entries)
    return ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
            f"  <Collection>\n{rows}\n  </Collection>\n</VTKFile>\n")


def write_series(frames: dict, out_dir, name: str = "tire") -> Path:
    """Write `<name>_<k>.vtu` for every frame and `<name>.pvd` in out_dir. Returns the .pvd path."""
    import meshio

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    times = np.asarray(frames["t"], float).reshape(-1)
    width = max(4, len(str(len(times) - 1)))
    entries = []
    for k, t in enumerate(times):
        fname = f"{name}_{k:0{width}d}.vtu"
        tmp = out / f".{fname}.tmp.vtu"
        meshio.write(tmp, frame_mesh(frames, k), file_format="vtu")
        tmp.replace(out / fname)
        entries.append((float(t), fname))
    return atomic_write_text(out / f"{name}.pvd", pvd_text(entries))
