"""What the section's geometry moves: a calibration config's targets and checks for the tire as
shipped and for each geometry change, one at a time (the transverse crown radius, the height of
the sidewall's widest point, the mid-surface at the carcass instead of the outer section width).

    python benchmarks/geometry_effects.py                       # study.toml, default mesh
    python benchmarks/geometry_effects.py --config configs/calibration/track.toml --set tire.mesh.n_theta=32

Prints one markdown table (each response, and its change from the shipped tire in %) and writes
OUT/geometry_effects.json. Default mesh: ~25 s per variant on 2 cores after compiling (~1 min).
"""

import argparse
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VARIANTS = [
    ("as shipped", []),
    ("mid_surface = carcass", ['tire.tire.mid_surface="carcass"']),
    ("crown_radius 1000 mm", ["tire.tire.crown_radius_mm=1000"]),
    ("crown_radius 4000 mm", ["tire.tire.crown_radius_mm=4000"]),
    ("widest_point_ratio 0.40", ["tire.tire.widest_point_ratio=0.40"]),
    ("widest_point_ratio 0.60", ["tire.tire.widest_point_ratio=0.60"]),
]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "calibration" / "study.toml"))
    ap.add_argument("--set", action="append", default=[], help="override for every variant (tire.mesh.n_theta=32)")
    ap.add_argument("--out", default="runs/geometry_effects")
    a = ap.parse_args(argv)
    from jtire import cache

    cache.enable()
    import dataclasses

    from jtire.calibration.tire.shell import ShellSimulator
    from jtire.calibration.tire.spec import load_calibration

    rows = []
    for label, sets in VARIANTS:
        spec = load_calibration(a.config, a.set + sets)
        targets = tuple(spec.targets) + tuple(spec.checks)
        spec = dataclasses.replace(spec, targets=targets, weights=(1.0,) * len(targets))
        sim = ShellSimulator(spec, spec.tire)
        t0 = time.perf_counter()
        # the tire alone (every bias at 0: its lower bound is 0 in the shipped configs)
        y = sim.evaluate(spec.space.default[None])[0]
        rows.append({"variant": label, "wall_s": time.perf_counter() - t0,
                     "responses": {t.name: float(v) for t, v in zip(targets, y)},
                     "measured": {t.name: t.measured for t in targets}})
        print(f"{label}: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)
    names = list(rows[0]["responses"])
    base = rows[0]["responses"]
    lines = ["| variant | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|",
             "| measured | " + " | ".join(f"{rows[0]['measured'][n]:.5g}" for n in names) + " |"]
    for r in rows:
        cells = [f"{r['responses'][n]:.5g}" + ("" if r is rows[0] else
                                                 f" ({100 * (r['responses'][n] / base[n] - 1):+.1f} %)")
                 for n in names]
        lines.append(f"| {r['variant']} | " + " | ".join(cells) + " |")
    print("\n".join(lines))
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "geometry_effects.json").write_text(json.dumps({"config": a.config, "set": a.set, "rows": rows}, indent=1))


if __name__ == "__main__":
    main()
