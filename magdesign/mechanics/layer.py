"""Elastomer layer of thickness h under a flat contact of area S.

The layer sits between the contact (or a magnet film) and the substrate. Its normal
stiffness k_n = E_eff S / h and shear stiffness k_s = G S / h (N/m) come at two
fidelity levels:

- ``"hooke"``: E_eff = E, Young's modulus; Yan et al.'s (2021) dP = E dz / h and
  Fx = S G dx / h. Exact for a layer free to slide on both faces.
- ``"bonded"``: a layer bonded on both faces cannot bulge freely and is stiffer in
  compression. For a disc of radius a (S = pi a^2), the shape factor is
  S_f = loaded area / free lateral area = a / (2 h), and

      E_c = E (1 + 2 S_f^2)                     (Gent & Lindley, Proc. Inst. Mech.
                                                 Eng. 173, 111 (1959))
      1 / E_eff = 1 / E_c + 1 / K               (bulk compressibility, Gent,
                                                 "Engineering with Rubber", 3rd ed.
                                                 (Hanser, 2012))

  so E_eff runs from E K / (E + K) (thick layer: E less the bulk compliance, which
  E already contains, a relative undershoot E / K, 0.3 % for K = 1000 mu) to the bulk
  modulus K (thin layer). Bonding does
  not change the simple-shear stiffness to this order, so k_s is G S / h at both levels
  (the bending correction of a tall block, h comparable to a, is not included).

Against the bonded level, ``"hooke"`` underestimates k_n by the factor
(1 + 2 S_f^2) (for K >> E_c): 1.5 % at S_f = 0.087 (a / h = 0.17), 3x at S_f = 1.
"""

from typing import NamedTuple

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._validation import check_positive
from magdesign.mechanics.materials import AbstractMaterial

FIDELITIES = ("hooke", "bonded")


class LayerStiffness(NamedTuple):
    """Stiffness (N/m) of a layer: force per displacement of its top face."""

    normal: Float[Array, "..."]
    shear: Float[Array, "..."]


def shape_factor(*, thickness: Float[ArrayLike, "..."], area: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """S_f = loaded area / free lateral area (-) of a bonded disc: a / (2 h).

    ``area`` pi a^2 (m^2) and ``thickness`` h (m), both > 0, broadcast together.
    """
    check_positive(thickness=thickness, unit="m")
    check_positive(area=area, unit="m^2")
    radius = jnp.sqrt(jnp.asarray(area) / jnp.pi)
    return radius / (2.0 * jnp.asarray(thickness))


def compression_modulus(
    *,
    thickness: Float[ArrayLike, "..."],
    area: Float[ArrayLike, "..."],
    material: AbstractMaterial,
    fidelity: str = "hooke",
) -> Float[Array, "..."]:
    """Effective modulus E_eff (Pa) in dP = E_eff dz / h; see the module docstring."""
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    check_positive(thickness=thickness, unit="m")
    check_positive(area=area, unit="m^2")
    youngs = material.youngs_modulus
    if fidelity == "hooke":
        return jnp.broadcast_to(youngs, jnp.broadcast_shapes(jnp.shape(thickness), jnp.shape(area)))
    bonded = youngs * (1.0 + 2.0 * shape_factor(thickness=thickness, area=area) ** 2)
    bulk = material.bulk_modulus
    # Written as K E_c / (K + E_c) rather than 1 / (1/E_c + 1/K): the same value, and a
    # very thin layer (E_c -> inf) gives K without an inf in between.
    return bulk / (1.0 + bulk / bonded)


def layer_stiffness(
    *,
    thickness: Float[ArrayLike, "..."],
    area: Float[ArrayLike, "..."],
    material: AbstractMaterial,
    fidelity: str = "hooke",
) -> LayerStiffness:
    """Normal and shear stiffness (N/m) of a layer of ``thickness`` h (m) under a flat
    contact of ``area`` S (m^2) of ``material``; k_n = E_eff S / h, k_s = G S / h.

    ``fidelity`` is "hooke" or "bonded" (module docstring). ``thickness`` and ``area``
    broadcast together; both must be > 0.
    """
    modulus = compression_modulus(thickness=thickness, area=area, material=material, fidelity=fidelity)
    per_height = jnp.asarray(area) / jnp.asarray(thickness)
    return LayerStiffness(normal=modulus * per_height, shear=material.shear_modulus * per_height)
