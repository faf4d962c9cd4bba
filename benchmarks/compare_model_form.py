"""The study's model form against the physical tire: what nodal damping alpha does to the tire a
vehicle model receives.

Two tire files (typically `jtire calibrate configs/calibration/study.toml`'s calibrated_tire.toml,
the physical tire + bias, and `study_replication.toml`'s, where alpha carries the drag) are run
through
- E12 (steady) at 7.5, 15 and 30 mph at one load: the drag, and how much of it is the nodal damping's
  (its power over the speed), the Maxwell branches' and the sliding's;
- `jtire characterize` at the rated condition only (no validation): the damping constants of the
  rigid ring, C_tot, C_btheta, C_by, C_bgamma, C_l (and C_bx),
and printed side by side (markdown), written to OUT/model_form.json and OUT/model_form.md.

    python benchmarks/compare_model_form.py --physical runs/calibrate/study/calibrated_tire.toml \\
        --replication runs/calibrate/study_replication/calibrated_tire.toml --out runs/model_form

Default mesh: ~2 min of E12 and ~5 min of characterization per tire on 2 cores (warm compile cache).
"""

import argparse
import json
import sys
import time
from pathlib import Path

DAMPERS = ("C_tot_Ns_per_m", "C_btheta_Nms_per_rad", "C_by_Ns_per_m", "C_bgamma_Nms_per_rad",
           "C_l_Ns_per_m", "C_bx_Ns_per_m")


def drag_at_speeds(tire_path, speeds_mph, load_kn, overrides):
    from jtire import batch
    from jtire import units as U
    from jtire.config import parse_solver, read_tire_file, validate_table
    from jtire.experiments import REGISTRY, Protocol
    from jtire.tire import make_tire

    _, spec = read_tire_file(tire_path, overrides)
    tire = make_tire(spec)
    proto = Protocol.from_dict(parse_solver({}))
    cls = REGISTRY["rolling_resistance"]
    rows = []
    for v in speeds_mph:
        exp = cls.from_table(validate_table({"speed_mph": v}, cls.schema, "rolling_resistance"), proto, spec)
        (r,) = batch.run(exp, tire, [{"load_N": load_kn * 1e3, "pressure_Pa": 120.0 * U.PSI}])
        if isinstance(r, batch.CaseFailure):
            raise SystemExit(f"{tire_path}: E12 at {v} mph failed: {r.error}")
        q = r.quantities
        speed = q["speed_m_per_s"]
        rows.append({"speed_mph": v, "drag_N": q["rolling_resistance_N"], "rrc": q["rrc"],
                     "nodal_N": q["nodal_damping_power_W"] / speed,
                     "maxwell_N": q["viscoelastic_power_W"] / speed,
                     "tread_damping_N": q["tread_damping_power_W"] / speed,
                     "friction_N": q["friction_power_W"] / speed})
    return spec.nodal_damping, rows


def dampers(tire_path, out, overrides):
    from jtire.cli import main

    args = ["characterize", "--tire", str(tire_path), "--out", str(out), "--no-validate",
            "--set", "grid.loads_kg=[4625.0]", "--set", "grid.pressures_psi=[120.0]"]
    for o in overrides:
        args += ["--set", f"tire.{o}"]
    if main(args) != 0:
        raise SystemExit(f"{tire_path}: characterize failed")
    row = json.loads((Path(out) / "characterization.json").read_text())["rows"][0]
    return {k: row.get(k) for k in DAMPERS}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--physical", required=True, help="tire TOML of the physical calibration")
    ap.add_argument("--replication", required=True, help="tire TOML of the study's model form")
    ap.add_argument("--out", default="runs/model_form")
    ap.add_argument("--speeds", type=float, nargs="+", default=[7.5, 15.0, 30.0], help="mph")
    ap.add_argument("--load-kN", type=float, default=38.7)
    ap.add_argument("--set", action="append", default=[], help="tire override, e.g. mesh.n_theta=32")
    ap.add_argument("--no-characterize", action="store_true", help="the drag table only")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    result = {}
    for label, path in (("physical", a.physical), ("replication", a.replication)):
        t0 = time.perf_counter()
        alpha, rows = drag_at_speeds(path, a.speeds, a.load_kN, a.set)
        result[label] = {"tire": str(path), "alpha_per_s": alpha, "drag": rows}
        if not a.no_characterize:
            result[label]["dampers"] = dampers(path, out / f"char_{label}", a.set)
        result[label]["wall_s"] = time.perf_counter() - t0
    lines = [f"E12 at {a.load_kN:g} kN, 120 psi (steady); N", "",
             "| tire | alpha 1/s | " + " | ".join(f"{v:g} mph drag (nodal part)" for v in a.speeds)
             + f" | {a.speeds[-1]:g} / {a.speeds[0]:g} mph drag ratio |", "|---|---|" + "---|" * len(a.speeds) + "---|"]
    for label, r in result.items():
        d = r["drag"]
        lines.append(f"| {label} | {r['alpha_per_s']:.4g} | " + " | ".join(
            f"{x['drag_N']:.0f} ({x['nodal_N']:.0f})" for x in d) + f" | {d[-1]['drag_N'] / d[0]['drag_N']:.2f} |")
    if not a.no_characterize:
        lines += ["", "Rigid-ring dampers at the rated condition (jtire characterize, two-peak values)", "",
                  "| tire | " + " | ".join(DAMPERS) + " |", "|---|" + "---|" * len(DAMPERS)]
        for label, r in result.items():
            lines.append(f"| {label} | " + " | ".join(
                "" if r["dampers"][k] is None else f"{r['dampers'][k]:.4g}" for k in DAMPERS) + " |")
    text = "\n".join(lines) + "\n"
    (out / "model_form.md").write_text(text)
    (out / "model_form.json").write_text(json.dumps(result, indent=1))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
