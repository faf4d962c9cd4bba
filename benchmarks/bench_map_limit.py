"""Memory maps held by compiled CPU programs, and what happens at the kernel's cap (vm.max_map_count).

    python benchmarks/bench_map_limit.py --programs 20            # maps per program, and a clear
    python benchmarks/bench_map_limit.py --programs 400 --guard   # past the cap's share: cleared, lives
    python benchmarks/bench_map_limit.py --programs 400           # no guard: dies near the cap (SIGSEGV)

Each program is a chain of `--ops` cumsum kernels (kept alive, as long jobs keep their jitted
functions). Prints, per program, the process's memory maps and whether
`jtire.cache.release_programs_if_crowded` cleared. Without `--guard` the process crosses the cap and
XLA's loader fails ("LLVM compilation error: Cannot allocate memory") and then segfaults (measured here:
65,416 maps at program 207 of 100 kernels each, exit 139). Runs without the persistent cache.
Take it alone on the machine: a program compiles in ~1-2 s.
"""

import argparse
import os
import time

os.environ.setdefault("JTIRE_CACHE_DIR", "off")

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
from jax import lax  # noqa: E402

from jtire import cache  # noqa: E402


def program(k: int, ops: int):
    def f(x):
        for i in range(ops):
            x = lax.optimization_barrier(jnp.cumsum(jnp.sin(x * (i + k)))[::-1] * 1e-2)
        return x

    return jax.jit(f)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--programs", type=int, default=20)
    ap.add_argument("--ops", type=int, default=100)
    ap.add_argument("--guard", action="store_true", help="call release_programs_if_crowded before each compile")
    args = ap.parse_args(argv)
    x = jnp.ones(64)
    keep = []
    n0, cap = cache.map_count(), cache.map_limit()
    print(f"maps at start {n0}, cap (vm.max_map_count) {cap}, threshold {cache.CROWDED_FRACTION:g} of it")
    print("| program | maps | cleared | s |")
    print("|---|---|---|---|")
    t0, counts = time.perf_counter(), [n0]
    for k in range(args.programs):
        cleared = cache.release_programs_if_crowded() if args.guard else False
        f = program(k, args.ops)
        f(x).block_until_ready()
        keep.append(f)
        counts.append(cache.map_count())
        print(f"| {k} | {cache.map_count()} | {'yes' if cleared else ''} | {time.perf_counter() - t0:.1f} |", flush=True)
    steps = sorted(b - a for a, b in zip(counts, counts[1:]) if b > a)  # a clear's drop left out
    per = steps[len(steps) // 2] if steps else 0
    jax.clear_caches()
    print(f"maps per program (median) {per}; after jax.clear_caches(): {cache.map_count()} "
          f"(the functions still held: {len(keep)}); clears by the guard: {cache.clears()}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
