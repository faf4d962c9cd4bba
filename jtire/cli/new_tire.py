"""`jtire new-tire SIZE [--out DIR] [--load-index N] [--pressure-kPa P] [--rim-width-in W] [--measured CSV]`: a
tire file for another size, with a run config (E01, E02, E09, E12 at its rated condition), a characterization
config and, from the user's measurements, a calibration config beside it (the work is `jtire.new_tire`)."""

from pathlib import Path


def add_arguments(p):
    p.add_argument("size", help="metric radial size designation, e.g. 295/75R22.5, 315/80R22.5 or 205/55R16")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for tire.toml, run.toml and characterize.toml (default: tires/<size>, e.g. "
                        "tires/295_75R22.5)")
    p.add_argument("--load-index", type=int, default=None, metavar="N",
                   help="load index from the sidewall (single fitment); needed for sizes outside the built-in table")
    p.add_argument("--pressure-kPa", type=float, default=None, metavar="P",
                   help="reference (rated) pressure; default: the table's for known sizes, else 250 kPa passenger, "
                        "830 kPa truck")
    p.add_argument("--rim-width-in", type=float, default=None, metavar="W",
                   help="rim width in inches (default: the size's measuring rim)")
    p.add_argument("--measured", default=None, metavar="CSV",
                   help="your measurements (columns quantity, value, unit, load_kg, pressure_kPa[, speed_kmh]; quantity "
                        "one of k_sv, k_l, footprint_length, footprint_width, rolling_resistance): also write "
                        "calibrate.toml with one target per row")
    p.add_argument("--force", action="store_true", help="replace the files in an existing --out folder")


def run_cli(args, say) -> int:
    from .. import new_tire, sizes
    from ..errors import ConfigError
    from ..io import atomic_write_text

    size, rated, files = new_tire.files_for(args.size, args.rim_width_in, args.load_index, args.pressure_kPa,
                                             args.measured)
    out = Path(args.out) if args.out else Path("tires") / size.text.replace("/", "_")
    clash = [name for name in files if (out / name).exists()]
    if clash and not args.force:
        raise ConfigError(f"--out {out}: already holds {', '.join(clash)} (--force replaces them)")
    out.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        atomic_write_text(out / name, text)
    k = sizes.rhyne_stiffness(size, rated.pressure_kPa * 1e3)
    say(f"{size.text} ({size.kind}): outer diameter {size.outer_diameter * 1e3:.1f} mm, section "
        f"{size.section_width * 1e3:.0f} x {size.section_height * 1e3:.1f} mm, rated {rated.load_kg:g} kg (load index "
        f"{rated.load_index}) at {rated.pressure_kPa:g} kPa")
    say(f"  Rhyne's vertical stiffness estimate at {rated.pressure_kPa:g} kPa: {k / 1e3:.0f} kN/m (compare E02's "
        "k_sv_secant)")
    say(f"  wrote {', '.join(str(out / name) for name in files)}; next:")
    say(f"    jtire run {out}/run.toml")
    tire = ""
    if "calibrate.toml" in files:
        say(f"    jtire calibrate {out}/calibrate.toml --out runs/calibrate_{out.name}")
        tire = f" --tire runs/calibrate_{out.name}/calibrated_tire.toml"
    say(f"    jtire characterize {out}/characterize.toml{tire} --out runs/characterize_{out.name}")
    return 0
