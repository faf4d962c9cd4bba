"""Profile: where one explicit step's time goes, piece by piece, and what one XLA kernel costs.

The step (`vector_field.evaluate` + `TireState.advance`) is cut into nested pieces; each runs alone as a
jitted `fori_loop` of N iterations on the loaded tire of `bench_step.py` (the model and parameters as
closure constants, as in the solver), its outputs folded back into the loop state (1e-30 x their sum:
a few small reductions, counted in every row but `step`) so nothing is hoisted out of the loop:

  kinematics        assemble the net, strains, cavity volume, tread points (forward only)
  + rates           jax.linearize of that map and its jvp (strain rates, tread-point velocities)
  + contact         the contact law at the tread points (bristles, normal and friction forces)
  evaluate          the whole force evaluation: + Maxwell branches, the transposed linearization
                    (nodal forces), damping, rim
  step              evaluate + advance (the bare step of bench_step.py)

For each: microseconds per iteration, the fusions (kernels) XLA made of the loop body, and the
microseconds per fusion. A step whose time is the fusion count times a near-constant cost per
kernel, nearly independent of the mesh size, is bound by kernel dispatch, not arithmetic.

    python benchmarks/profile_step.py                         # the default mesh and two others
    python benchmarks/profile_step.py --meshes 64x5x6 --steps 2000 --repeat 5
Run it alone on the machine (timings here vary by up to +-40 % under load).
"""

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_step import count_body_fusions, loaded_case, timed  # noqa: E402


def pieces(model, params, drive):
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from jtire.physics.contact import OMEGA_REF, contact_forces
    from jtire.physics.vector_field import evaluate

    def kin(Y):
        X = model.assemble(*Y)
        return model.strains(X), model.volume(X), model.tread_points(X)

    def _nudge(y, tot):
        return eqx.tree_at(lambda s: s.x.x, y, y.x.x + 1e-30 * tot)

    def total(tree):
        return sum(jnp.sum(leaf) for leaf in jax.tree_util.tree_leaves(tree))

    def p_kin(i, y):
        return _nudge(y, total(kin((y.x, y.q))))

    def p_rates(i, y):
        (s, vol, P), lin = jax.linearize(kin, (y.x, y.q))
        sdot, _, Pdot = lin((y.v, y.qd))
        return _nudge(y, total((s, vol, P, sdot, Pdot)))

    def p_contact(i, y):
        (s, vol, P), lin = jax.linearize(kin, (y.x, y.q))
        sdot, _, Pdot = lin((y.v, y.qd))
        k_n, k_t, _ = model.contact_stiffness(params)
        c_n = params.tread_loss * k_n / OMEGA_REF
        F, bristle, F_n, gap, p_tread, p_slide = contact_forces(drive.surface, P, Pdot, i * drive.dt, y.bristle, k_n,
                                                                k_t, c_n, params.friction, drive.dt)
        return _nudge(y, total((s, vol, sdot, F, bristle, p_tread)))

    def p_eval(i, y):
        upd, _ = evaluate(model, params, drive, i * drive.dt, y)
        return _nudge(y, total(upd))

    def p_step(i, y):
        upd, _ = evaluate(model, params, drive, i * drive.dt, y)
        return y.advance(upd, drive.dt, drive)

    return {"kinematics": p_kin, "+ rates": p_rates, "+ contact": p_contact, "evaluate": p_eval, "step": p_step}


def profile_mesh(mesh, n_steps, repeat):
    import jax

    _, model, params, drive, y0, dt = loaded_case(mesh)
    dof = 3 * model.x_ref.x.size + 6
    rows = []
    for name, body in pieces(model, params, drive).items():
        loop = jax.jit(lambda d, y, body=body: jax.lax.fori_loop(0, n_steps, body, y))
        compiled = loop.lower(drive, y0).compile()
        fus, _ = count_body_fusions(compiled.as_text())
        t, _ = timed(lambda: compiled(drive, y0), repeat)
        us = 1e6 * t / n_steps
        rows.append((mesh, dof, name, us, fus, us / max(fus, 1)))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["64x5x6", "32x5x4", "96x10x8"], help="n_theta x n_side x n_crown")
    ap.add_argument("--steps", type=int, default=2000, help="iterations per timed call")
    ap.add_argument("--repeat", type=int, default=3, help="timed calls per figure (median)")
    args = ap.parse_args(argv)
    print("| mesh | DOF | piece | us / iteration | fusions | us / fusion |")
    print("|---|---|---|---|---|---|")
    for m in args.meshes:
        for mesh, dof, name, us, fus, per in profile_mesh(m, args.steps, args.repeat):
            print(f"| {mesh} | {dof} | {name} | {us:.0f} | {fus} | {per:.2f} |", flush=True)


if __name__ == "__main__":
    main()
