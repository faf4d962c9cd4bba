"""`jtire export-tir CHAR_DIR_OR_JSON [--out FILE.tir]`: the rigid-ring tables, trend verdicts, the
Magic Formula fit and an MF 6.1 `.tir` from a characterization (the work is `jtire.rigid_ring`)."""

from pathlib import Path


def add_arguments(parser) -> None:
    parser.add_argument("characterization", help="characterization.json, or the folder holding it")
    parser.add_argument("--out", default=None, help="output .tir file (default: rigid_ring.tir beside the input)")
    parser.add_argument("--longvl", type=float, default=6.7056,
                        help="LONGVL: speed of the E10 runs, m/s (default 6.7056 = 15 mph)")
    parser.add_argument("--fittyp", type=int, choices=(61, 62), default=61, help="FITTYP written (default 61)")
    parser.add_argument("--all-pressures", action="store_true",
                        help="fit the MF to the curves at every pressure (PPY1..4, PPZ1, PPX1..4); default: nominal only")


def run_cli(args, say) -> int:
    import math

    from ..errors import ConfigError
    from ..io import check_writable
    from ..rigid_ring.export import export
    from ..rigid_ring.table import read_characterization

    if not (math.isfinite(args.longvl) and 0.0 < args.longvl <= 100.0):
        raise ConfigError(f"--longvl {args.longvl:g}: must be a speed in (0, 100] m/s")
    src = Path(args.characterization)
    char = read_characterization(src)
    base = src if src.is_dir() else src.parent
    out = Path(args.out) if args.out else base / "rigid_ring.tir"
    if out.is_dir():
        raise ConfigError(f"--out {out}: is a folder; give the .tir file to write")
    check_writable(out.parent)
    written, lines = export(char, out.parent, tir_name=out.name, longvl=args.longvl, fittyp=args.fittyp,
                            all_pressures=args.all_pressures, source=src.name)
    for line in lines:
        say(line)
    say(f"wrote {', '.join(p.name for p in written)} in {out.parent}")
    return 0
