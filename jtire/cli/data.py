"""`jtire data`: the measured test-track and sandbox tables, their RRC fits, and how the study's
rolling-resistance targets compare with them (the work is `jtire.data.analyze`)."""

import dataclasses
from pathlib import Path

from ..data import LBF_N, PSI_PA, RRC_SOURCES, SANDBOX_FILE, TRACK_FILE, analyze
from ..errors import ConfigError


def add_arguments(parser) -> None:
    parser.add_argument("--out", default="runs/data", help="output folder (default runs/data)")
    parser.add_argument("--data-dir", default=None,
                        help=f"folder holding {TRACK_FILE} and {SANDBOX_FILE} "
                             "(default: the package's configs/data)")
    parser.add_argument("--reference", default=None,
                        help="TOML with [calibration.targets.rolling_resistance_*] "
                             "(default configs/reference_xone_xda.toml)")
    parser.add_argument("--rrc", choices=RRC_SOURCES, default="table",
                        help="per-run RRC for the fits: the study's column (table) "
                             "or Fx/Fz (ratio)")
    parser.add_argument("--confidence", type=float, default=0.95,
                        help="two-sided confidence level of every interval (default 0.95)")


def _average_rows(avgs) -> list:
    return [[a.source, a.config, a.label, a.axle, a.pressure_pa / PSI_PA, a.n_runs,
             a.fx_n / LBF_N, a.fz_n / LBF_N, a.fx_n, a.fz_n, a.rrc_study, a.rrc_mean_of_ratios,
             a.rrc_ratio_of_means, a.rrc_std, a.rrc_sem] for a in avgs]


AVERAGE_HEADER = ["source", "config", "label", "axle", "pressure_psi", "n_runs", "fx_lbf",
                  "fz_lbf", "fx_N", "fz_N", "rrc_study", "rrc_mean_of_ratios",
                  "rrc_ratio_of_means", "rrc_std", "rrc_sem"]


def _fit_rows(fits) -> list:
    rows = []
    for f in fits.values():
        lin, pw = f.linear, f.power
        n, conf = lin.line.n, lin.line.confidence
        rows += [[f.name, "linear", "a", lin.a, *lin.a_ci, lin.line.stderr[0], n, conf],
                 [f.name, "linear", "b_per_N", lin.b, *lin.b_ci, lin.line.stderr[1], n, conf],
                 [f.name, "power", "c", pw.c, *pw.c_ci, float("nan"), n, conf],
                 [f.name, "power", "d", pw.d, *pw.d_ci, pw.log_line.stderr[1], n, conf]]
    return rows


def _print_averages(say, title, avgs) -> None:
    say(f"\n{title}")
    say(f"{'cfg':>3} {'label':<22} {'axle':<6} {'psi':>4} {'n':>2} {'Fx lbf':>10} "
          f"{'Fz lbf':>10} {'Fx N':>10} {'Fz N':>10} {'RRC study':>10} {'mean Fx/Fz':>10} "
          f"{'mFx/mFz':>9} {'sem':>8}")
    for r in _average_rows(avgs):
        say(f"{r[1]:>3} {r[2]:<22} {r[3]:<6} {r[4]:>4.0f} {r[5]:>2} {r[6]:>10.5f} {r[7]:>10.3f} "
              f"{r[8]:>10.3f} {r[9]:>10.1f} {r[10]:>10.6f} {r[11]:>10.6f} {r[12]:>9.6f} "
              f"{r[14]:>8.6f}")


def _interval(lo, hi) -> str:
    return f"{f'[{lo:.5f},{hi:.5f}]':>19}"


def run_cli(args, say) -> int:
    from ..io import atomic_write_csv, atomic_write_json, check_writable

    if not 0.0 < args.confidence < 1.0:  # NaN and inf fail too
        raise ConfigError(f"--confidence {args.confidence:g}: must be in (0, 1), e.g. 0.95")
    out = Path(args.out)
    check_writable(out)
    s = analyze(args.data_dir, args.reference, args.rrc, args.confidence)
    pct = f"{100 * args.confidence:g}%"

    _print_averages(say, "Track (rigid oval, 15 mph), per-configuration averages", s.track_averages)
    _print_averages(say, "Sandbox (loose dry sand, 5 mph), per-configuration averages",
                    s.sandbox_averages)

    say(f"\nFits of RRC on Fz (runs at 120 psi, RRC from '{args.rrc}', {pct} CIs, Fz in N)")
    say(f"{'dataset':<18} {'model':<7} {'param':<8} {'value':>12} {'ci low':>12} "
          f"{'ci high':>12} {'n':>3}")
    fit_rows = _fit_rows(s.fits)
    for r in fit_rows:
        say(f"{r[0]:<18} {r[1]:<7} {r[2]:<8} {r[3]:>12.5g} {r[4]:>12.5g} {r[5]:>12.5g} {r[7]:>3}")

    say(f"\nStudy rolling-resistance targets against the track 120 psi fits ({pct} bands)")
    say(f"{'fit':<19} {'target':<21} {'Fz kN':>5} {'RRC tgt':>8} {'model':<7} {'trend':>8} "
          f"{'CI of trend':>19} {'new-point band':>19} {'z trend':>7} {'z pt':>5} {'% off':>7}")
    cmp_rows = []
    for c in s.comparisons:
        cmp_rows.append([c.dataset, c.target, c.load_n, c.target_rrc, c.model, c.pred, c.lower,
                         c.upper, c.obs_lower, c.obs_upper, c.z_mean, c.z_obs, c.percent,
                         c.inside_ci])
        say(f"{c.dataset:<19} {c.target:<21} {c.load_n / 1e3:>5.1f} {c.target_rrc:>8.5f} "
              f"{c.model:<7} {c.pred:>8.5f} {_interval(c.lower, c.upper)} "
              f"{_interval(c.obs_lower, c.obs_upper)} {c.z_mean:>7.1f} {c.z_obs:>5.1f} "
              f"{c.percent:>+7.1f}")
    say("z trend: target - trend in standard errors of the trend; z pt: in standard errors of "
          "one new fitted point (a run, or a configuration mean); power law in ln RRC; "
          "% off: target / trend - 1")

    atomic_write_csv(out / "track_averages.csv", AVERAGE_HEADER, _average_rows(s.track_averages))
    atomic_write_csv(out / "sandbox_averages.csv", AVERAGE_HEADER,
                     _average_rows(s.sandbox_averages))
    atomic_write_csv(out / "fits.csv", ["dataset", "model", "param", "value", "ci_low", "ci_high",
                                        "stderr", "n", "confidence"], fit_rows)
    atomic_write_csv(out / "target_comparison.csv",
                     ["dataset", "target", "load_N", "target_rrc", "model", "fit_rrc", "ci_low",
                      "ci_high", "point_band_low", "point_band_high", "z_mean", "z_point",
                      "percent", "inside_ci"],
                     cmp_rows)
    atomic_write_json(out / "fits.json", {
        "rrc_source": args.rrc, "confidence": args.confidence, "units": "Fz in N, RRC = Fx/Fz",
        "fits": {k: {"description": f.description, "linear": f.linear.as_dict(),
                     "power": f.power.as_dict()} for k, f in s.fits.items()},
        "targets": [dataclasses.asdict(t) | {"rrc": t.rrc} for t in s.targets],
        "comparisons": [dataclasses.asdict(c) | {"inside_ci": c.inside_ci}
                        for c in s.comparisons]})
    say(f"\nwrote {out}/track_averages.csv, sandbox_averages.csv, fits.csv, "
          "target_comparison.csv, fits.json")
    return 0
