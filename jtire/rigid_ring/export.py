"""From a characterization to the files a vehicle-dynamics engineer uses: the two rigid-ring tables,
the trend verdicts, the Magic Formula fit and an MF 6.1/6.2 `.tir` (shared by `jtire export-tir` and
`jtire characterize`). Returns the written paths and the report lines; never prints."""

from pathlib import Path

from ..io import atomic_write_text
from . import magic_formula as mf
from . import mf_longitudinal as mfx
from . import mf_rolling
from . import report, tir, trends


def export(char, out_dir, tir_name: str = "rigid_ring.tir", longvl: float = 6.7056, fittyp: int = 61,
           all_pressures: bool = False, source: str = "characterization"):
    """Write the .tir, in_plane/out_of_plane tables and trends.md into out_dir. Returns (paths, lines)."""
    out_dir = Path(out_dir)
    out = out_dir / tir_name
    rated = char.rated_row()
    nom = mf.Nominal(rated.load_N, rated.pressure_Pa, char.tire.unloaded_radius_m)
    curves = mf.curves_from_characterization(char, None if all_pressures else [rated.pressure_Pa])
    fit = mf.fit_pure_lateral(curves, nom) if curves else None
    slip_curves = mfx.curves_from_characterization(char, None if all_pressures else [rated.pressure_Pa])
    fit_x = mfx.fit_pure_longitudinal(slip_curves, nom) if slip_curves else None
    sections, notes = tir.build(char, fit=fit, longvl=longvl, fittyp=fittyp, rated=rated, fit_x=fit_x)
    written = [tir.write(out, sections, [f"rigid ring + MF {fittyp} from {source} (jtire)"])]
    written += report.write_tables(char, out_dir)
    vs = trends.verdicts(char)
    written.append(atomic_write_text(out_dir / "trends.md", trends.markdown(vs)))
    lines = [report.markdown(char, "in"), report.markdown(char, "out"), "### Trends\n", trends.markdown(vs)]
    if fit is not None:
        lines.append(f"MF fit ({'all pressures' if all_pressures else 'nominal pressure'}): "
                     f"max |F_y,MF - F_y| over {fit.range_text()} = {100 * fit.max_fy_error:.2f} % of peak"
                     + ("" if fit.max_mz_error is None else f", M_z {100 * fit.max_mz_error:.2f} %")
                     + ("" if fit.success else f" (optimizer: {fit.message})"))
        for fz, p, efy, emz in fit.errors:
            lines.append(f"  {fz:9.0f} N {p / 1e3:6.0f} kPa: F_y {100 * efy:.2f} %"
                         + ("" if emz is None else f", M_z {100 * emz:.2f} %"))
    else:
        lines.append("MF fit: no E10 curves in the characterization (not fitted)")
    if fit_x is not None:
        lines.append(f"MF F_x fit ({'all pressures' if all_pressures else 'nominal pressure'}, free-rolling F_x "
                     f"removed): max |F_x,MF - F_x| over "
                     f"0-{100 * fit_x.err_range:g} % slip = {100 * fit_x.max_error:.2f} % of peak"
                     + ("" if fit_x.success else f" (optimizer: {fit_x.message})"))
        for fz, p, e in fit_x.errors:
            lines.append(f"  {fz:9.0f} N {p / 1e3:6.0f} kPa: F_x {100 * e:.2f} %")
    else:
        lines.append("MF F_x fit: no E06 curves in the characterization (only PKX1, PKX2, PPX1 from k_k)")
    rf = mf_rolling.rolling_fit(char, {k: (v, c) for rows in sections.values() for k, v, c in rows}, rated)
    if rf is not None:
        lines.append(f"MF rolling resistance (QSY1, QSY7, QSY8 from E12's drag): max drag error {100 * rf.max_error:.2f} %")
        for fz, p, d, d_mf, e in rf.errors:
            lines.append(f"  {fz:9.0f} N {p / 1e3:6.0f} kPa: E12 {d:.4g} N, |M_y|/R_l {d_mf:.4g} N ({100 * e:+.2f} %)")
    else:
        lines.append("MF rolling resistance: no E12 drag in the characterization (QSY1, QSY7 defaults)")
    lines += [f"note: {n}" for n in notes]
    return [Path(p) for p in written if p is not None], lines
