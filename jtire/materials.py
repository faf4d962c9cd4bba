"""Material parameters: per-part membrane, shear and bending moduli, thicknesses and losses.

Every quantity a calibration may tune is a `jax.Array` leaf (house rule 4): per-part parameters
are short arrays indexed by the static part index of `jtire.mesh`, so a calibration
differentiates a vector of a few dozen numbers, not a field over elements.

Viscoelasticity: each generalized stress has a long-term elastic stiffness K and B Maxwell
branches of stiffness c_b * loss * K and relaxation time tau_b (a generalized Prony series). The
weights c_b are fixed so that the loss tangent averaged over the rolling band equals the part's
`loss`: the parameter means what an engineer reads off a DMA sweep, and the dissipation is the
model's own, with no prescribed rolling-resistance coefficient anywhere.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .mesh import N_PARTS, PART_NAMES

# Moduli a calibration may tune, with the parts they exist for (name -> field).
MODULUS_FIELDS = ("E_meridional", "E_circumferential", "G_shear", "E_bending")


def prony_weights(relaxation_times, band_hz=(1.0, 100.0)) -> np.ndarray:
    """Branch weights c_b (B,) giving a mean loss tangent of 1 over `band_hz` per unit `loss`.

    Loss tangent of the series for loss = 1 (small-loss approximation, storage ~ K):
        tan_delta(w) = sum_b c_b * w tau_b / (1 + (w tau_b)^2)
    Equal weights, scaled so the log-frequency average over the band is one.
    """
    tau = np.asarray(relaxation_times, float)
    w = 2 * np.pi * np.logspace(np.log10(band_hz[0]), np.log10(band_hz[1]), 200)
    shape = (w[:, None] * tau[None, :] / (1 + (w[:, None] * tau[None, :]) ** 2)).sum(axis=1)
    return np.full(tau.shape, 1.0 / shape.mean())


def dynamic_modulus(loss, relaxation_times, f_hz) -> tuple:
    """(tan delta, E'/K) of a part with loss parameter `loss` at frequency f_hz: what its Prony series
    (weights `prony_weights`) gives exactly, E* / K = 1 + sum_b c_b loss i w tau_b / (1 + i w tau_b).
    `loss` is the band-averaged small-loss tan delta; at one frequency the true one differs."""
    tau = np.asarray(relaxation_times, float)
    c = prony_weights(tau)
    wt = 2 * np.pi * np.asarray(f_hz, float)[..., None] * tau
    k = np.asarray(loss, float)[..., None] * c
    storage = 1.0 + np.sum(k * wt**2 / (1 + wt**2), axis=-1)
    lossmod = np.sum(k * wt / (1 + wt**2), axis=-1)
    return lossmod / storage, storage


class MaterialParams(eqx.Module):
    """Per-part (P = 6 parts, `jtire.mesh.PART_NAMES`) and tread parameters, SI.

    E_meridional:      (P,) Pa, membrane modulus along the meridian (carcass cords)
    E_circumferential: (P,) Pa, membrane modulus around the tire (belt cords in the crown)
    G_shear:           (P,) Pa, in-plane shear modulus
    E_bending:         (P,) Pa, modulus for shell bending, D = E_bending t^3 / 12
    thickness:         (P,) m
    loss:              (P,) loss tangent of the part's rubber over the rolling band
    undertread_E, undertread_thickness: the undertread membrane under the tread (crown only,
                       isotropic rubber layer in parallel with the belt), Pa and m
    tread_E, tread_G:  tread rubber compression and shear moduli, Pa (contact stiffness)
    tread_loss:        loss tangent of the tread rubber
    friction:          Coulomb friction coefficient tread-road
    relaxation_times:  (B,) s, Maxwell branch relaxation times (static: they fix the branch layout)
    nodal_damping:     1/s, mass-proportional damping on every tire node's road-frame velocity: the
                       study's explicit-code model form, not tire physics; 0 (off) by default
    """

    E_meridional: Float[Array, " P"]
    E_circumferential: Float[Array, " P"]
    G_shear: Float[Array, " P"]
    E_bending: Float[Array, " P"]
    thickness: Float[Array, " P"]
    loss: Float[Array, " P"]
    undertread_E: Float[Array, ""]
    undertread_thickness: Float[Array, ""]
    tread_E: Float[Array, ""]
    tread_G: Float[Array, ""]
    tread_loss: Float[Array, ""]
    friction: Float[Array, ""]
    relaxation_times: tuple = eqx.field(static=True)
    nodal_damping: Float[Array, ""] = eqx.field(default_factory=lambda: jnp.zeros(()))

    def __check_init__(self):
        for name in ("E_meridional", "E_circumferential", "G_shear", "E_bending", "thickness", "loss"):
            shape = jnp.shape(getattr(self, name))
            if shape != (N_PARTS,):
                raise ValueError(f"MaterialParams.{name}: shape {shape}, expected ({N_PARTS},) = one per part {PART_NAMES}")

    @property
    def prony_weights(self) -> np.ndarray:
        """Maxwell branch weights c_b, shape (B,), of these relaxation times: `prony_weights` over the
        default rolling band (1-100 Hz), so a part's mean loss tangent over the band equals its `loss`."""
        return prony_weights(np.asarray(self.relaxation_times))

    def part_table(self) -> dict:
        """The per-part parameters as a {part: {field: value}} dict (for reports)."""
        out = {}
        for p, name in enumerate(PART_NAMES):
            out[name] = {f: float(np.asarray(getattr(self, f))[p]) for f in
                         ("E_meridional", "E_circumferential", "G_shear", "E_bending", "thickness", "loss")}
        return out

    def without_damping(self) -> "MaterialParams":
        """The same material with every loss set to zero (for energy-conservation checks)."""
        return eqx.tree_at(lambda m: (m.loss, m.tread_loss, m.nodal_damping), self,
                           (jnp.zeros_like(self.loss), jnp.zeros_like(self.tread_loss),
                            jnp.zeros_like(self.nodal_damping)))
