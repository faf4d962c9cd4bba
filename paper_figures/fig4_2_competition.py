"""Study Figure 4-2: progression of ARSM, GA and Monte Carlo on the soil-block calibration.

Best sinkage error so far against the number of function calls, median and quartiles over the
seeds of each method, with the study's single runs (Table 4-3) as stars. Histories are kept in
--runs, so a long run that is stopped resumes where it left off.

    python paper_figures/fig4_2_competition.py --out runs/figures/fig4_2_competition.png
    python paper_figures/fig4_2_competition.py --quick --out /tmp/fig4_2.png

--quick runs the same soil finite-element model with 3 seeds x 20 calls (about 10 s) and says
so in the title. The full figure is 3000 FE calls (about 30 ms each after a ~2 s compile: ~100 s
on a quiet 2-core machine); it shares nothing with `jtire compete` unless --runs points at the
same folder (e.g. --runs runs/compete, where `jtire compete` keeps its soil/ histories).
"""

import argparse
import shutil
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from jtire.calibration.soil.competition import (  # noqa: E402
    QUICK_BUDGET,
    QUICK_SEEDS,
    CompetitionSpec,
    fingerprint,
    load_config,
    run_competition,
    soil_objective,
)
from jtire.calibration.soil.report import plot_progression  # noqa: E402

CONFIG = Path(__file__).resolve().parents[1] / "configs" / "calibration" / "soil_competition.toml"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs/figures/fig4_2_competition.png")
    ap.add_argument("--quick", action="store_true",
                    help=f"{QUICK_SEEDS} seeds x {QUICK_BUDGET} calls (same FE model)")
    ap.add_argument("--config", default=str(CONFIG))
    ap.add_argument("--runs", default=None,
                    help="folder for the run histories (default runs/fig4_2; --quick: a temp dir)")
    args = ap.parse_args(argv)

    cfg = load_config(args.config)
    comp = dict(cfg.get("competition", {}))
    if args.quick:
        comp.update(seeds=QUICK_SEEDS, budget=QUICK_BUDGET)
    spec = CompetitionSpec.from_config({**cfg, "competition": comp})
    name = "soil"
    objective = soil_objective(cfg)
    tmp = tempfile.mkdtemp(prefix="fig4_2_") if args.quick and args.runs is None else None
    runs = Path(tmp or args.runs or "runs/fig4_2") / name
    try:
        results = run_competition(objective, spec, runs, fingerprint=fingerprint(cfg, name))
    finally:
        if tmp:
            shutil.rmtree(tmp, ignore_errors=True)
    what = ("QUICK CHECK, " if args.quick else "") + "soil plate test (axisymmetric FE, Drucker-Prager)"
    title = (f"Figure 4-2: sinkage error vs calls, {what}\n{spec.seeds} seeds x {spec.budget} "
             "calls per method; line: median, band: quartiles; stars: the study's single runs")
    plot_progression(results, spec, args.out, title)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
