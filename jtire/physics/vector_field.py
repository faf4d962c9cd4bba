"""Assembles every force term into the accelerations of one step (the model's vector field).

One linearization of the strain map gives both the strain rates (for the Maxwell branches) and
the internal forces (its transpose applied to the stresses); pressure is p * grad V; the contact
forces act at the tread points and come back to nodes and rim through the transposed
linearization of the tread-point map. Nothing here loops over nodes, elements or time.
"""

import jax
import jax.numpy as jnp

from ..materials import prony_weights
from ..state import Update
from . import rim
from .geometry_ops import V, cross, dot
from .rigid_belt import belt_load_forces, rigid_belt_accelerations
from .contact import OMEGA_REF, contact_forces
from .drum import FreeDrum


def evaluate(model, params, drive, t, y):
    """Forces on the state `y` at time t. Returns (Update, diagnostics dict).

    One linearization of the kinematic map Y -> (strains, cavity volume, tread points) gives all
    rates (its jvp) and all nodal forces (its transpose applied to (-stress, pressure, contact
    force)): a single forward and a single backward pass per step.
    """
    Y, Yd = (y.x, y.q), (y.v, y.qd)

    def kinematics(Y_):
        X = model.assemble(*Y_)
        return model.strains(X), model.volume(X), model.tread_points(X)

    (s, vol, P), lin = jax.linearize(kinematics, Y)
    sdot, _, Pdot = lin(Yd)
    K = model.stiffness(params)
    # Maxwell branches, integrated exactly for a constant strain rate over the step. They are
    # advanced with the strain rate that brought the net to its current shape (v of this state
    # is the velocity of the last position update) before their stress is used, as the bristles
    # are: updating them after would apply a one-step-old stress, which destabilizes the scheme.
    tau = jnp.asarray(params.relaxation_times)
    cb = jnp.asarray(prony_weights(params.relaxation_times))
    Kb = cb[:, None] * (model.strain_loss(params) * K)[None, :]
    decay = jnp.exp(-drive.dt / tau)[:, None]
    maxwell = y.maxwell * decay + Kb * sdot[None, :] * tau[:, None] * (1 - decay)
    safe_Kb = jnp.where(Kb > 0, Kb, 1.0)
    p_visc = jnp.sum(jnp.where(Kb > 0, maxwell**2 / (safe_Kb * tau[:, None]), 0.0))
    sigma = K * (s - model.s0) + jnp.sum(maxwell, axis=0)

    p = drive.pressure(t)
    k_n, k_t, _ = model.contact_stiffness(params)
    c_n = params.tread_loss * k_n / OMEGA_REF
    surface = drive.surface
    free_drum = isinstance(surface, FreeDrum)
    if free_drum:  # a drum with its own inertia: its spin is the state's
        surface = surface.spinning(y.drum[1])
    F, bristle, F_n, gap, p_tread, p_slide = contact_forces(surface, P, Pdot, t, y.bristle, k_n, k_t,
                                                            c_n, params.friction, drive.dt)
    drum_acc = surface.acceleration(P, F) if free_drum else jnp.zeros(())
    ((fx, fq),) = jax.linear_transpose(lin, Y)((-sigma, p, F))

    # dynamic-relaxation damping on velocities relative to the rim frame (alpha = 1: the rim
    # takes the reaction; needed whenever the rim moves or spins) or to the ground (alpha = 0:
    # a slowly loaded, non-rolling tire, where damping relative to a descending rim would
    # resist the deflection itself and bias a quasi-static load-deflection curve)
    m = model.node_mass
    alpha = drive.damp_rim_frame
    v_rel = y.v - rim.frame_velocity(y.q, y.qd, y.x) * alpha
    f_d = v_rel * (-drive.settle_damping * m)
    r = y.x - V(y.q[0], y.q[1], y.q[2])
    fdf = f_d * alpha
    fq = fq - jnp.concatenate([fdf.sum().array(), cross(r, fdf).sum().array()])
    fx = fx + f_d
    p_settle = -jnp.sum(dot(f_d, v_rel))
    # the study's explicit-FE model form (params.nodal_damping, 0 = off): mass-proportional damping on
    # every tire node's velocity relative to the road's frame; its loss counts as dissipated
    v_road = surface.frame_velocity()
    zero = jnp.zeros_like(m)
    v_g = y.v - V(zero + v_road[0], zero + v_road[1], zero + v_road[2])
    f_nodal = v_g * (-params.nodal_damping * m)
    fx = fx + f_nodal
    p_nodal = -jnp.sum(dot(f_nodal, v_g))

    if drive.belt_loaded:
        fx = fx + belt_load_forces(y.x, m, model.belt_mask, drive.belt_load(t))
    M_rim = jnp.concatenate([jnp.full(3, model.rim_mass), model.rim_inertia])
    g6 = jnp.concatenate([drive.gravity * model.rim_mass, jnp.zeros(3)])
    g = drive.gravity
    if drive.rigid_belt:
        ax = rigid_belt_accelerations(y.x, y.v, fx, m, model.belt_mask) + V(g[0], g[1], g[2])
    else:
        ax = fx / m + V(g[0], g[1], g[2])
    aq = (fq + drive.rim_force(t) + g6) / M_rim

    upd = Update(ax, aq, maxwell, bristle, p_visc + p_tread + p_nodal, p_settle, p_slide, drum_acc)
    d = s - model.s0
    # fq: generalized force (N, N m about the rim centre) of the tire on the rim: beads, the
    # pressure on the rim closure and the reaction of rim-frame damping. It is what a hub
    # dynamometer reads, whatever the rim's own mass and drive.
    diag = dict(P=P, F=F, F_n=F_n, gap=gap, pressure=p, volume=vol, strain_energy=0.5 * jnp.sum(K * d * d),
                tire_on_rim=fq)
    return upd, diag
