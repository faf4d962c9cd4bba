"""`jtire export-vtk RUN_DIR [--out DIR]`: a run's recorded frames (RUN_DIR/frames.npz, written by
`jtire run --frames N`) as ParaView files: one .vtu per frame (the deformed mid-surface with its
displacement, contact pressure and strain-energy density) and a .pvd time series (`jtire.vtk`)."""

from pathlib import Path


def add_arguments(parser) -> None:
    parser.add_argument("run_dir", help="run folder holding frames.npz (or the .npz file itself)")
    parser.add_argument("--out", default=None, help="output folder (default: RUN_DIR/vtk)")
    parser.add_argument("--name", default="tire", help="file stem of the .vtu frames and the .pvd (default tire)")


def run_cli(args, say) -> int:
    from ..vtk import load_frames, write_series

    src = Path(args.run_dir)
    # a run of several experiments keeps one frames.npz per experiment folder
    sources = [src] if not src.is_dir() or (src / "frames.npz").is_file() else sorted(
        p.parent for p in src.glob("*/frames.npz"))
    if not sources:
        sources = [src]  # load_frames names the missing file
    for one in sources:
        frames = load_frames(one)
        base = one if one.is_dir() else one.parent
        out = Path(args.out) / base.name if args.out and len(sources) > 1 else (
            Path(args.out) if args.out else base / "vtk")
        pvd = write_series(frames, out, args.name)
        n = len(frames["t"])
        T, S = frames["nodes_ref"].shape[:2]
        say(f"wrote {n} frames ({T * S} points, {T * (S - 1)} quads each) and {pvd}")
    return 0
