"""Benchmark: cost of one explicit time step, its fusion count, and the compile time of run_phase.

Per mesh (n_theta x n_side x n_crown), on a loaded tire (pressure ramp, rim free in z under a
vertical force, a flat road 5 mm into the tread, so the contact law is live):

  bare us/step   `jax.lax.fori_loop` of `vector_field.evaluate` + `TireState.advance`, jit,
                 model and params closure constants, drive and state arguments; N steps per call
  phase us/step  `solve.run_phase_jit` over the same N steps (diffrax loop, 201 saves of
                 `solve.observe`, the blow-up and settle events; settle_after = inf)
  fusions        `fusion(` calls in the compiled bare loop's while body (the step): every
                 instruction line of the while-body computation, and of the non-fused
                 computations it calls (call/conditional), whose opcode is `fusion`
  ops            all instruction lines of that body (fusions, copies, custom calls, ...)
  compile s      run_phase_jit: trace + lower + XLA compile (jax's in-memory caches cleared first;
                 the persistent compilation cache is off unless the environment turns it on)

Each time is the median of --repeat runs after a warm-up. Timing on this shared 2-core machine
varies by up to +-40 %: run it alone on the machine and compare medians.

    python benchmarks/bench_step.py                     # 64x5x6, 32x5x4, 96x10x8
    python benchmarks/bench_step.py --meshes 64x5x6 --repeat 5 --json out.json
To measure another checkout (e.g. the `before` column at commit 6f5538b), put it first on the path:
    git archive 6f5538b | tar -x -C /tmp/base
    PYTHONPATH=/tmp/base python benchmarks/bench_step.py --json before.json
"""

import argparse
import dataclasses
import json
import re
import statistics
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def loaded_case(mesh: str):
    """(model, params, drive, y0, dt) of the default tire on the given mesh, touching a flat road."""
    import jax.numpy as jnp

    import jtire
    from jtire import solve
    from jtire.config import load_tire
    from jtire.physics.contact import FlatRoad
    from jtire.state import Drive, TireState
    from jtire.tire import make_tire

    nt, ns, nc = (int(v) for v in mesh.split("x"))
    spec = dataclasses.replace(load_tire(REPO / "configs" / "tires" / "xone_xda.toml"), n_theta=nt, n_side=ns, n_crown=nc)
    tire = make_tire(spec)
    model, params = tire.model, tire.params
    p = 120 * 6894.757
    dt = solve.stable_step(model, params, p, 300.0)
    y0 = TireState.at_rest(model, len(params.relaxation_times))
    X = model.assemble(y0.x, y0.q)
    z_road = float(jnp.min(model.tread_points(X).z)) + 0.005
    f = lambda v: jnp.asarray(v, float)  # noqa: E731
    drive = Drive(pressure0=f(0.0), pressure1=f(p), force0=f(np.zeros(6)), force1=f([0, 0, 40e3, 0, 0, 0]),
                  t_ramp0=f(0.0), t_ramp1=f(0.02), rim_free=f([0, 0, 1, 0, 0, 0]), rim_velocity=f(np.zeros(6)),
                  surface=FlatRoad(height=f(z_road), velocity=f(np.zeros(3))), settle_damping=f(300.0),
                  damp_rim_frame=f(0.0), gravity=f(np.zeros(3)), dt=f(dt))
    return jtire, model, params, drive, y0, dt


def bare_loop(model, params, n_steps):
    import jax

    from jtire.physics.vector_field import evaluate

    def run(drive, y0):
        def body(i, y):
            upd, _ = evaluate(model, params, drive, i * drive.dt, y)
            return y.advance(upd, drive.dt, drive)

        return jax.lax.fori_loop(0, n_steps, body, y0)

    return jax.jit(run)


def count_body_fusions(hlo: str):
    """(fusions, instructions) in the while body of a compiled loop (see the module docstring)."""
    comps, name = {}, None
    for line in hlo.splitlines():
        m = re.match(r"^(ENTRY )?%?([\w.\-]+) .*\{\s*$", line)
        if m:
            name = m.group(2)
            comps[name] = []
        elif line.strip() == "}":
            name = None
        elif name is not None and "=" in line:
            comps[name].append(line)
    bodies = [re.search(r"body=%?([\w.\-]+)", ln).group(1) for c in comps.values() for ln in c if " while(" in ln]
    # the outermost while: the one whose body is largest
    body = max(bodies, key=lambda b: len(comps.get(b, ())))
    seen, todo, fus, ops = set(), [body], 0, 0
    while todo:
        c = todo.pop()
        if c in seen or c not in comps:
            continue
        seen.add(c)
        for ln in comps[c]:
            if re.search(r"\s(parameter|constant|get-tuple-element|tuple|bitcast)\(", ln):
                continue
            ops += 1
            if re.search(r"\sfusion\(", ln):
                fus += 1
            else:
                todo += re.findall(r"(?:to_apply|calls|branch_computations|body|condition)=\{?%?([\w.\-]+)", ln)
    return fus, ops


def timed(f, repeat):
    import jax

    jax.block_until_ready(f())  # warm-up
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(f())
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts), ts


def bench_mesh(mesh, n_steps, repeat, hlo_out=None):
    import jax
    import jax.numpy as jnp

    jtire, model, params, drive, y0, dt = loaded_case(mesh)
    from jtire import solve

    loop = bare_loop(model, params, n_steps)
    compiled = loop.lower(drive, y0).compile()
    hlo = compiled.as_text()
    if hlo_out:
        Path(hlo_out).write_text(hlo)
    fus, ops = count_body_fusions(hlo)
    t_bare, bare_all = timed(lambda: compiled(drive, y0), repeat)
    y_end = compiled(drive, y0)
    ok = bool(jnp.all(jnp.isfinite(y_end.x.x)))

    t1 = n_steps * dt
    args = (model, params, drive, y0, jnp.asarray(0.0), jnp.asarray(t1 * (1 + 1e-9)), jnp.linspace(0.0, t1, solve.N_SAVE),
            jnp.asarray(jnp.inf), jnp.asarray(1e-3), solve.MAX_STEPS)
    jax.clear_caches()
    t0 = time.perf_counter()
    res = jax.block_until_ready(solve.run_phase_jit(*args))
    t_first = time.perf_counter() - t0
    t_phase, phase_all = timed(lambda: solve.run_phase_jit(*args), repeat)
    steps = int(res.n_steps)
    dof = 3 * model.x_ref.x.size + 6
    return dict(mesh=mesh, dof=dof, dt=dt, n_steps=n_steps, phase_steps=steps, finite=ok,
                bare_us=1e6 * t_bare / n_steps, bare_us_all=[1e6 * t / n_steps for t in bare_all],
                phase_us=1e6 * t_phase / steps, phase_us_all=[1e6 * t / steps for t in phase_all],
                fusions=fus, ops=ops, compile_s=t_first - t_phase, jtire=str(Path(jtire.__file__).parent))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["64x5x6", "32x5x4", "96x10x8"], help="n_theta x n_side x n_crown")
    ap.add_argument("--steps", type=int, default=2000, help="steps per timed call")
    ap.add_argument("--repeat", type=int, default=3, help="timed calls per figure (median)")
    ap.add_argument("--json", help="write the rows here")
    ap.add_argument("--before", help="a --json file of the same script on the old code: shown beside")
    ap.add_argument("--hlo", help="write the compiled bare loop's HLO text of the first mesh here")
    args = ap.parse_args(argv)

    before = {r["mesh"]: r for r in json.loads(Path(args.before).read_text())} if args.before else {}
    cols = ("mesh", "DOF", "bare us/step", "phase us/step", "fusions", "ops", "compile s")
    print(" | ".join(f"{c:>14}" for c in cols), flush=True)
    rows = []
    for i, m in enumerate(args.meshes):
        r = bench_mesh(m, args.steps, args.repeat, args.hlo if i == 0 else None)
        rows.append(r)
        b = before.get(m)
        fmt = lambda k, f: (f"{r[k]:{f}}" + (f" ({b[k]:{f}})" if b else "")).rjust(14)  # noqa: E731
        print(" | ".join([m.rjust(14), f"{r['dof']:>14d}", fmt("bare_us", ".0f"), fmt("phase_us", ".0f"),
                          fmt("fusions", "d"), fmt("ops", "d"), fmt("compile_s", ".1f")]), flush=True)
        if not r["finite"] or r["phase_steps"] != args.steps:
            print(f"   warning: finite={r['finite']}, run_phase took {r['phase_steps']} steps", flush=True)
    if before:
        print("(in brackets: --before)")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
