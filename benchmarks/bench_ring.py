"""Wall time of the rigid ring's validation scenarios (drop, drum-cleat, lateral release, slip steps at
5 and 15 m/s) with each tread contact: the string (the default) and the first-order lag (the model
before it), per condition after a first, compiling, pass.

    python benchmarks/bench_ring.py                      # the synthetic characterization's rated row
    python benchmarks/bench_ring.py --char runs/characterize   # the validation's three conditions

Prints one row per (condition, contact): the compiling pass, the median of --repeat timed passes,
and the string's time over the lag's.
"""

import argparse
import statistics
import time

from jtire import units as U
from jtire.rigid_ring import synthetic
from jtire.rigid_ring.table import read_characterization
from jtire.validate import DEFAULT_CONDITIONS, ring_results


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--char", help="a characterization folder (default: the synthetic characterization)")
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args(argv)
    if a.char:
        ch = read_characterization(a.char)
        rows = [ch.row(kg * U.G0, psi * U.PSI) for kg, psi in DEFAULT_CONDITIONS]
        rows = [r for r in rows if r is not None]
    else:
        ch = synthetic.characterization()
        rows = [ch.rated_row()]
    print(f"{'condition':>22} {'contact':>7} {'first pass':>11} {'timed (median)':>15} {'string / lag':>13}")
    for row in rows:
        times = {}
        for contact in ("lag", "string"):
            t0 = time.perf_counter()
            ring_results(row, ch.tire, contact=contact)  # the validation's own scenarios
            first = time.perf_counter() - t0
            reps = []
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                ring_results(row, ch.tire, contact=contact)
                reps.append(time.perf_counter() - t0)
            times[contact] = statistics.median(reps)
            ratio = f"{times['string'] / times['lag']:.2f}" if contact == "string" else ""
            name = f"{row.load_N / U.G0:g} kg {row.pressure_Pa / U.PSI:g} psi"
            print(f"{name:>22} {contact:>7} {first:>10.1f}s {times[contact]:>14.1f}s {ratio:>13}", flush=True)


if __name__ == "__main__":
    main()
