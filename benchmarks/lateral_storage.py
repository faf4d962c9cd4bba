"""The rigid ring's lateral mode on the rubber's storage moduli: for each validation condition of a
characterization, E09, E07 and E08 pushed statically on the long-term moduli and on every part's and the
tread's storage modulus at the shell's lateral release frequency (`validate.storage_tire`), and the ring
variant's linear lateral mode with its springs from the static pushes, with all three scaled by E09's
ratio (`rigid_ring.params.derive(..., lateral_springs="storage")` on the ratio `jtire characterize` measures),
and with each spring from its own push (k_cy rederived).

    python benchmarks/lateral_storage.py runs/characterize            # its validation conditions
    python benchmarks/lateral_storage.py runs/characterize --condition 4625 120

Prints one markdown table and writes OUT/lateral_storage.json. Default mesh: about 1 min per condition on
2 cores after compiling (six static pushes).
"""

import argparse
import dataclasses
import sys
import time
from pathlib import Path

# experiment -> the ring's spring it measures (the table's column, SI)
PUSHES = (("lateral_stiffness", "k_l_N_per_m"), ("sidewall_translation", "k_by_N_per_m"),
          ("sidewall_camber", "k_bgamma_Nm_per_rad"))


def parse(argv, description, out, add=None):
    """The storage benchmarks' command line: a characterization folder, conditions, an output folder;
    add(parser) adds a script's own options."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("char_dir", help="a finished characterization folder (jtire characterize --out DIR)")
    ap.add_argument("--condition", nargs=2, type=float, action="append", metavar=("KG", "PSI"),
                    help="a grid condition (default: the validation's three)")
    ap.add_argument("--out", default=out)
    if add is not None:
        add(ap)
    return ap.parse_args(argv)


def setup(a):
    """(plan, solver protocol, characterization, [(kg, psi, SI condition)]) for the parsed arguments."""
    from jtire import cache
    from jtire import units as U
    from jtire.characterize import load_plan
    from jtire.experiments.phases import Protocol
    from jtire.resources import config_path
    from jtire.rigid_ring.table import read_characterization
    from jtire.validate import DEFAULT_CONDITIONS

    cache.enable()
    plan = load_plan(config_path("characterize.toml"))
    conds = [(kg, psi, {"load_N": kg * U.G0, "pressure_Pa": psi * U.PSI})
             for kg, psi in a.condition or DEFAULT_CONDITIONS]
    return plan, Protocol.from_dict(plan.solver), read_characterization(a.char_dir), conds


_LONG_TERM = {}  # (experiment, quantity, condition) -> its push on the long-term moduli


def storage_ratio(plan, proto, name, key, cond, f_hz, where):
    """Experiment `name`'s static push on the storage moduli at f_hz over its push on the long-term
    moduli: quantity `key`'s ratio (its shortest decay when it has one: only the push is read)."""
    from jtire import batch
    from jtire.config import validate_table
    from jtire.experiments import REGISTRY
    from jtire.tire import make_tire
    from jtire.validate import storage_tire

    schema = REGISTRY[name].schema
    table = dict(plan.tables.get(name) or validate_table({}, schema, name))
    if "decay_s" in schema:
        fld = schema["decay_s"]
        table["decay_s"] = fld.lo * fld.factor
    def push(spec):
        r = batch.run(REGISTRY[name].from_table(table, proto, spec), make_tire(spec), [cond])[0]
        if isinstance(r, batch.CaseFailure):
            raise SystemExit(f"{name} at {where}: {r.error}")
        return r.quantities[key]

    # the long-term push depends on the condition only: road-free tests at one pressure run it once
    static = (name, key, tuple(sorted(cond.items())))
    if static not in _LONG_TERM:
        _LONG_TERM[static] = push(plan.tire)
    return push(storage_tire(plan.tire, f_hz)) / _LONG_TERM[static]


def save(a, name, rows):
    """rows with the characterization they came from, as JSON in the output folder (atomically)."""
    from jtire.io import atomic_write_json

    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    return atomic_write_json(out / name, {"char_dir": str(a.char_dir), "rows": rows})


def main(argv=None):
    a = parse(argv, __doc__.splitlines()[0], "runs/lateral_storage")
    from jtire.rigid_ring.modes import lateral_modes
    from jtire.rigid_ring.params import derive
    from jtire.validate import shell_metrics

    plan, proto, char, conds = setup(a)
    rows = []
    for kg, psi, c in conds:
        f = shell_metrics(a.char_dir, c["load_N"], c["pressure_Pa"])[0].get("lateral.f_Hz")
        row = char.row(c["load_N"], c["pressure_Pa"])
        if f is None or row is None:
            print(f"{kg:g} kg, {psi:g} psi: no lateral release or no table row in {a.char_dir}", file=sys.stderr)
            continue
        t0, ratio = time.perf_counter(), {}
        for name, key in PUSHES:
            cond = c if name == "lateral_stiffness" else {"pressure_Pa": c["pressure_Pa"]}
            ratio[key] = storage_ratio(plan, proto, name, key, cond, f, f"{kg:g} kg, {psi:g} psi")
        d = derive(row, char.tire, lateral_springs="static")  # the static pushes' springs
        r_l = ratio["k_l_N_per_m"]
        f_static = lateral_modes(d, "ring")[0][0]
        f_scaled = lateral_modes(dataclasses.replace(d, k_l=d.k_l * r_l, k_by=d.k_by * r_l,
                                                     k_bgamma=d.k_bgamma * r_l, k_cy=d.k_cy * r_l), "ring")[0][0]
        d2 = derive(dataclasses.replace(row, q=row.q | {k: row.q[k] * ratio[k] for _, k in PUSHES}), char.tire,
                     lateral_springs="static")
        f_own = lateral_modes(d2, "ring")[0][0]
        rows.append({"load_kg": kg, "pressure_psi": psi, "f_shell_Hz": f, "ratios": ratio,
                     "f_ring_static_Hz": f_static, "f_ring_scaled_Hz": f_scaled, "f_ring_own_Hz": f_own,
                     "k_cy_ratio": d2.k_cy / d.k_cy, "wall_s": time.perf_counter() - t0})
        print(f"{kg:g} kg, {psi:g} psi: {time.perf_counter() - t0:.1f} s", file=sys.stderr, flush=True)

    def fp(x, ref):
        return f"{x:.2f} Hz ({100 * (x / ref - 1):+.1f} %)"

    print("| condition | shell f | k_l, k_by, k_bgamma on the storage moduli | ring f, static springs | "
          "all x E09's ratio | each its own push (k_cy) |\n|---|---|---|---|---|---|")
    for r in rows:
        ks = ", ".join(f"x {r['ratios'][k]:.3f}" for _, k in PUSHES)
        print(f"| {r['load_kg']:g} kg, {r['pressure_psi']:g} psi | {r['f_shell_Hz']:.2f} Hz | {ks} | "
              f"{fp(r['f_ring_static_Hz'], r['f_shell_Hz'])} | {fp(r['f_ring_scaled_Hz'], r['f_shell_Hz'])} | "
              f"{fp(r['f_ring_own_Hz'], r['f_shell_Hz'])} (x {r['k_cy_ratio']:.3f}) |")
    print("wrote", save(a, "lateral_storage.json", rows))


if __name__ == "__main__":
    main()
