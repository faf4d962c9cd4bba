"""Measured rolling resistance (study chapter 3): test-track and sandbox tables, averages, fits.

The tables live in configs/data/ (comment lines start with '#'; forces in lbf, pressures in psi).
They are converted to SI once, here, when loaded (1 lbf = 4.4482216152605 N,
1 psi = 6894.757293168361 Pa); everything downstream is N and Pa.

How the study averaged (checked against its printed track bobtail row, Fx 24.03552 lbf,
Fz 1160.946 lbf, RRC 0.018806): Fx and Fz are arithmetic means over the runs, and the RRC is the
arithmetic mean of the *tabulated per-run RRC column*. Neither ratio recomputed from the
tabulated forces reproduces it (mean(Fx)/mean(Fz) = 0.020703, mean(Fx/Fz) = 0.020834): on the
track each run's Fx and Fz are means of the left and right wheel transducers and its RRC was
formed before that averaging, so the column cannot be rebuilt from the forces (the bobtail runs
differ by ~9 %, the loaded runs by 0-4 %). On the sandbox the column equals Fx/Fz to 1e-9.
Both are therefore kept: `RunTable.rrc_table` (the study's RRC1) and `RunTable.rrc_ratio`
(Fx/Fz); the fits use the study's column unless asked otherwise (`rrc_source="ratio"`).

Data quirks kept as printed (reported, not repaired): the track trailer1 mean Fz is 2829.09 lbf
while its nominal load label reads 2819.09 (10.00 lbf apart, a one-digit slip in the study); in
the sandbox trailer1 runs 1 and 2 are identical on both axles (a duplicated table row).

`jtire data` prints the tables and writes them (CSV + JSON) under --out.
"""

import csv
import dataclasses
from pathlib import Path

import numpy as np

from .data_fits import compare_target, fit_linear, fit_power, load_targets
from .errors import ConfigError
from .resources import configs_dir

LBF_N = 4.4482216152605  # N per lbf (exact by definition of the pound-force)
PSI_PA = 6894.757293168361  # Pa per psi
DEFAULT_DATA_DIR = configs_dir() / "data"
TRACK_FILE = "track_rolling_resistance.csv"
SANDBOX_FILE = "sandbox_rolling_resistance.csv"
AXLE_NAMES = {"pusher": "pusher (track, left/right mean)", "LM": "pusher (left middle)",
              "LF": "steer (left front)"}
RRC_SOURCES = ("table", "ratio")


@dataclasses.dataclass(frozen=True)
class RunTable:
    """Per-run measurements of one table, SI. Every array has shape (n_runs,).

    source: "track" or "sandbox"; config: configuration number; label: configuration name;
    axle: "pusher" on the track, "LM"/"LF" on the sandbox; run: run id as printed;
    pressure_pa, nominal_load_n: the configuration's inflation (Pa) and nominal load (N);
    fx_n, fz_n: longitudinal and vertical force (N); rrc_table: the study's per-run RRC1.
    """

    source: str
    config: np.ndarray
    label: np.ndarray
    axle: np.ndarray
    run: np.ndarray
    pressure_pa: np.ndarray
    nominal_load_n: np.ndarray
    fx_n: np.ndarray
    fz_n: np.ndarray
    rrc_table: np.ndarray

    @property
    def rrc_ratio(self) -> np.ndarray:
        """RRC1 recomputed as Fx / Fz from the tabulated forces, shape (n_runs,)."""
        return self.fx_n / self.fz_n

    def rrc(self, source: str = "table") -> np.ndarray:
        if source not in RRC_SOURCES:
            raise ConfigError(f"rrc_source = {source!r}: must be one of {RRC_SOURCES}")
        return self.rrc_table if source == "table" else self.rrc_ratio

    def select(self, mask) -> "RunTable":
        mask = np.asarray(mask, dtype=bool)
        arrays = [f.name for f in dataclasses.fields(self) if f.name != "source"]
        return dataclasses.replace(self, **{k: getattr(self, k)[mask] for k in arrays})

    def mask(self, pressure_psi=None, axle=None) -> np.ndarray:
        """Boolean mask of runs at `pressure_psi` (matched to 1e-6 relative) and/or on `axle`."""
        m = np.ones(self.fx_n.shape, dtype=bool)
        if pressure_psi is not None:
            m &= np.isclose(self.pressure_pa, pressure_psi * PSI_PA, rtol=1e-6)
        if axle is not None:
            m &= self.axle == axle
        return m


def _read_table(path: Path, columns: tuple) -> list:
    """Rows of a measurement CSV as dicts (column -> text), each with its file line number under
    the key "_line". Comment lines ('#') and blank lines are skipped. Every problem is one
    ConfigError naming the file (and the line): missing, a folder, not UTF-8, no header, a
    duplicated or missing column, a row with another number of fields than the header, no rows.
    """
    from .config import read_text

    if not path.exists():
        raise ConfigError(f"data file {path}: not found (pass --data-dir to point elsewhere)")
    text = read_text(path, "data file")
    numbered = [(i + 1, line) for i, line in enumerate(text.splitlines())
                if line.strip() and not line.lstrip().startswith("#")]
    if not numbered:
        raise ConfigError(f"data file {path}: empty (no header line, no data rows)")
    parsed = []
    for line_no, line in numbered:  # one record per line (so every error can name its line)
        try:
            parsed.append(next(csv.reader([line], strict=True)))
        except csv.Error as e:
            raise ConfigError(f"data file {path} line {line_no}: not valid CSV ({e})") from None
    header = [h.strip() for h in parsed[0]]
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise ConfigError(f"data file {path} line {numbered[0][0]}: column(s) {dup} appear more than once")
    missing = [c for c in columns if c not in header]
    if missing:
        raise ConfigError(f"data file {path}: missing column(s) {missing}; need {list(columns)}")
    rows = []
    for (line_no, _), fields in zip(numbered[1:], parsed[1:]):
        if len(fields) != len(header):
            raise ConfigError(f"data file {path} line {line_no}: {len(fields)} fields, the header has "
                              f"{len(header)}")
        rows.append(dict(zip(header, (f.strip() for f in fields))) | {"_line": line_no})
    if not rows:
        raise ConfigError(f"data file {path}: no data rows (only the header)")
    return rows


def _column(rows, name, path, positive=False) -> np.ndarray:
    """Column `name` as floats (n,); a non-number, NaN or inf (or <= 0 with positive) names the
    file and the line."""
    out = []
    for r in rows:
        try:
            v = float(r[name])
        except ValueError:
            raise ConfigError(f"data file {path} line {r['_line']}: {name} = {r[name]!r}: must be a "
                              "number") from None
        if not np.isfinite(v) or (positive and v <= 0.0):
            raise ConfigError(f"data file {path} line {r['_line']}: {name} = {r[name]}: must be finite"
                              + (" and > 0" if positive else ""))
        out.append(v)
    return np.array(out, dtype=float)


def _check_configurations(table, path) -> None:
    """Runs of one configuration (and axle) must share its label, pressure and nominal load: the
    averages take them from the first run, so a mismatch would be reported under a wrong name."""
    for cfg, axle in dict.fromkeys(zip(table.config.tolist(), table.axle.tolist())):
        m = (table.config == cfg) & (table.axle == axle)
        for what, col in (("label", table.label), ("pressure_psi", table.pressure_pa),
                          ("nominal_load_lbs", table.nominal_load_n)):
            if len(set(col[m].tolist())) > 1:
                raise ConfigError(f"data file {path}: configuration {cfg}"
                                  + (f" axle {axle}" if table.source != "track" else "")
                                  + f" has runs with different {what}")


def _load(source: str, filename: str, data_dir, axle_column) -> RunTable:
    path = Path(data_dir if data_dir is not None else DEFAULT_DATA_DIR) / filename
    cols = ("config", "label", "pressure_psi", "nominal_load_lbs", "run", "fx_lbs", "fz_lbs", "rrc")
    rows = _read_table(path, cols + ((axle_column,) if axle_column else ()))
    n = len(rows)
    axle = np.array([r[axle_column] for r in rows]) if axle_column else np.full(n, "pusher")
    config = _column(rows, "config", path)
    bad = [r for r, c in zip(rows, config) if c != int(c)]
    if bad:
        raise ConfigError(f"data file {path} line {bad[0]['_line']}: config = {bad[0]['config']!r}: "
                          "must be an integer")
    # The single unit conversion of the measured data: lbf -> N, psi -> Pa.
    table = RunTable(
        source=source,
        config=config.astype(int),
        label=np.array([r["label"] for r in rows]),
        axle=axle,
        run=np.array([r["run"] for r in rows]),
        pressure_pa=_column(rows, "pressure_psi", path, positive=True) * PSI_PA,
        nominal_load_n=_column(rows, "nominal_load_lbs", path, positive=True) * LBF_N,
        fx_n=_column(rows, "fx_lbs", path) * LBF_N,
        fz_n=_column(rows, "fz_lbs", path, positive=True) * LBF_N,
        rrc_table=_column(rows, "rrc", path),
    )
    _check_configurations(table, path)
    return table


def load_track(data_dir=None) -> RunTable:
    """Rigid test-track runs (pusher axle, 15 mph), from `data_dir` or configs/data/."""
    return _load("track", TRACK_FILE, data_dir, None)


def load_sandbox(data_dir=None) -> RunTable:
    """Loose dry-sand runs (left pusher LM and left steer LF, 5 mph), from `data_dir`."""
    return _load("sandbox", SANDBOX_FILE, data_dir, "axle")


@dataclasses.dataclass(frozen=True)
class ConfigAverage:
    """Per-configuration (and per-axle) averages, SI.

    fx_n, fz_n: means over runs (N); rrc_study: mean of the tabulated per-run RRC (the study's
    printed average); rrc_mean_of_ratios: mean of Fx/Fz; rrc_ratio_of_means: mean Fx / mean Fz;
    rrc_std, rrc_sem: sample standard deviation and standard error of the tabulated RRC.
    """

    source: str
    config: int
    label: str
    axle: str
    pressure_pa: float
    nominal_load_n: float
    n_runs: int
    fx_n: float
    fz_n: float
    rrc_study: float
    rrc_mean_of_ratios: float
    rrc_ratio_of_means: float
    rrc_std: float
    rrc_sem: float


def config_averages(table: RunTable) -> list:
    """One ConfigAverage per (config, axle), in the order the table lists them."""
    keys = list(dict.fromkeys(zip(table.config.tolist(), table.axle.tolist())))
    out = []
    for cfg, axle in keys:
        t = table.select((table.config == cfg) & (table.axle == axle))
        n = t.fx_n.size
        std = float(np.std(t.rrc_table, ddof=1)) if n > 1 else float("nan")
        out.append(ConfigAverage(
            source=table.source, config=int(cfg), label=str(t.label[0]), axle=str(axle),
            pressure_pa=float(t.pressure_pa[0]), nominal_load_n=float(t.nominal_load_n[0]),
            n_runs=n, fx_n=float(np.mean(t.fx_n)), fz_n=float(np.mean(t.fz_n)),
            rrc_study=float(np.mean(t.rrc_table)),
            rrc_mean_of_ratios=float(np.mean(t.rrc_ratio)),
            rrc_ratio_of_means=float(np.mean(t.fx_n) / np.mean(t.fz_n)),
            rrc_std=std, rrc_sem=std / np.sqrt(n)))
    return out


@dataclasses.dataclass(frozen=True)
class TrendFits:
    """Linear and power-law fits of RRC on F_z for one selection of runs (arrays shape (n,))."""

    name: str
    description: str
    fz_n: np.ndarray
    rrc: np.ndarray
    linear: object  # jtire.data_fits.LinearFit
    power: object  # jtire.data_fits.PowerFit


def trend_fits(table: RunTable, name: str, pressure_psi=None, axle=None,
               rrc_source: str = "table", confidence: float = 0.95) -> TrendFits:
    """Fit both trends to the runs of `table` at `pressure_psi` and on `axle` (None: all)."""
    t = table.select(table.mask(pressure_psi, axle))
    desc = f"{table.source}" + (f", {AXLE_NAMES.get(axle, axle)}" if axle else "") + \
        (f", {pressure_psi:g} psi" if pressure_psi is not None else "") + f", RRC from {rrc_source}"
    return points_trend_fits(name, desc + ", every run", t.fz_n, t.rrc(rrc_source), confidence)


def points_trend_fits(name: str, description: str, fz_n, rrc,
                      confidence: float = 0.95) -> TrendFits:
    """Fit both trends to given points, fz_n (N) and rrc of shape (n,). A fit that cannot be
    made (too few points, an exact fit, RRC <= 0 for the power law) is one ConfigError naming
    the fit and its points (e.g. ``fit track_120psi (track, 120 psi, ...): ...``)."""
    fz_n, rrc = np.asarray(fz_n, dtype=float), np.asarray(rrc, dtype=float)
    try:
        fits = TrendFits(name, description, fz_n, rrc, fit_linear(fz_n, rrc, confidence),
                         fit_power(fz_n, rrc, confidence))
    except ConfigError as e:
        raise ConfigError(f"fit {name} ({description}): {e}") from None
    # Measured runs never lie on a trend to round-off; if these do (synthetic data, or an RRC
    # column computed from the fit), the residual sd is 0, the intervals have zero width and every
    # z-score is infinite: a certainty no measurement has. Refuse, naming the fit, rather than
    # print those numbers.
    for model, line in (("linear", fits.linear.line), ("power-law", fits.power.log_line)):
        if line.exact:
            raise ConfigError(f"fit {name} ({description}): the {line.n} points lie exactly on the "
                              f"{model} trend (residual sd 0 to round-off): no confidence interval "
                              "can be estimated; measured runs scatter, check the data")
    return fits


@dataclasses.dataclass(frozen=True)
class DataSummary:
    """Everything `jtire data` reports: tables, averages, fits, and targets against track fits."""

    track: RunTable
    sandbox: RunTable
    track_averages: list
    sandbox_averages: list
    fits: dict  # name -> TrendFits
    targets: list  # jtire.data_fits.Target
    comparisons: list  # jtire.data_fits.TargetComparison (track fits only)


def analyze(data_dir=None, reference=None, rrc_source: str = "table",
            confidence: float = 0.95) -> DataSummary:
    """Load both tables, average them, fit the 120 psi trends, compare the study's targets.

    Fits: track_120psi (every track run at 120 psi), track_120psi_means (its 4 configuration
    means), sandbox_LM_120psi and sandbox_LF_120psi (every run of that axle at 120 psi). The 80 psi
    configuration is averaged but left out of the fits (a different inflation).
    """
    track, sandbox = load_track(data_dir), load_sandbox(data_dir)
    fits = {
        "track_120psi": trend_fits(track, "track_120psi", 120.0, None, rrc_source, confidence),
        "sandbox_LM_120psi": trend_fits(sandbox, "sandbox_LM_120psi", 120.0, "LM", rrc_source,
                                        confidence),
        "sandbox_LF_120psi": trend_fits(sandbox, "sandbox_LF_120psi", 120.0, "LF", rrc_source,
                                        confidence),
    }
    track_avg = config_averages(track)
    # The per-run fit treats the 24 runs as independent although they cluster in 4 loads, and
    # the configurations scatter about any smooth trend by more than their runs do (trailer2 and
    # trailer3, 7 % apart in load, differ by 50 % in RRC). The fit through the 4 configuration
    # means (2 degrees of freedom) carries that scatter into its intervals: a robustness check.
    means = [a for a in track_avg if np.isclose(a.pressure_pa, 120.0 * PSI_PA, rtol=1e-6)]
    rrc_means = [a.rrc_study if rrc_source == "table" else a.rrc_mean_of_ratios for a in means]
    fits["track_120psi_means"] = points_trend_fits(
        "track_120psi_means", f"track, 120 psi, configuration means of RRC from {rrc_source}",
        [a.fz_n for a in means], rrc_means, confidence)
    targets = load_targets(reference)
    comparisons = [compare_target(fit, tg, name) for name in ("track_120psi", "track_120psi_means")
                   for tg in targets for fit in (fits[name].linear, fits[name].power)]
    return DataSummary(track, sandbox, track_avg, config_averages(sandbox), fits, targets,
                       comparisons)
