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
                        help="fit the MF to the curves at every pressure (PPY1..4, PPZ1); default: nominal only")


def run_cli(args, say) -> int:
    from ..rigid_ring import magic_formula as mf
    from ..rigid_ring import report, tir, trends
    from ..rigid_ring.table import read_characterization

    src = Path(args.characterization)
    char = read_characterization(src)
    base = src if src.is_dir() else src.parent
    out = Path(args.out) if args.out else base / "rigid_ring.tir"
    rated = char.rated_row()
    nom = mf.Nominal(rated.load_N, rated.pressure_Pa, char.tire.unloaded_radius_m)
    curves = mf.curves_from_characterization(char, None if args.all_pressures else [rated.pressure_Pa])
    fit = mf.fit_pure_lateral(curves, nom) if curves else None
    sections, notes = tir.build(char, fit=fit, longvl=args.longvl, fittyp=args.fittyp, rated=rated)
    tir.write(out, sections, [f"rigid ring + MF {args.fittyp} from {src.name} (jtire export-tir)"])
    written = report.write_tables(char, out.parent)
    vs = trends.verdicts(char)
    from ..io import atomic_write_text
    written.append(atomic_write_text(out.parent / "trends.md", trends.markdown(vs)))

    say(report.markdown(char, "in"))
    say(report.markdown(char, "out"))
    say("### Trends\n")
    say(trends.markdown(vs))
    if fit is not None:
        say(f"MF fit ({'all pressures' if args.all_pressures else 'nominal pressure'}): "
            f"max |F_y,MF - F_y| over 0-{fit.err_range_deg:g} deg = {100 * fit.max_fy_error:.2f} % of peak"
            + ("" if fit.max_mz_error is None else f", M_z {100 * fit.max_mz_error:.2f} %")
            + ("" if fit.success else f" (optimizer: {fit.message})"))
        for fz, p, efy, emz in fit.errors:
            say(f"  {fz:9.0f} N {p / 1e3:6.0f} kPa: F_y {100 * efy:.2f} %"
                + ("" if emz is None else f", M_z {100 * emz:.2f} %"))
    for n in notes:
        say(f"note: {n}")
    say(f"wrote {out} and {', '.join(p.name for p in written)} in {out.parent}")
    return 0
