"""Rotations of sensor chips: the chip frame of seed 002, Eqs. 3-4.

A chip's orientation is three angles (alpha, beta, gamma) (rad); a field H given in
the scene (world) frame reads, in the chip frame (a, b, c),

    H_chip = Rx(alpha) Ry(beta) Rz(gamma) H

with ``a`` the chip's sensitive in-plane axis and ``c`` its normal
(:func:`magdesign.transducers.rotation_matrix`).
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign.transducers import rotation_matrix


def rotation(angles: Float[ArrayLike, "... 3"]) -> Float[Array, "... 3 3"]:
    """Rx(alpha) Ry(beta) Rz(gamma) for ``angles = (alpha, beta, gamma)`` (rad), (..., 3, 3)."""
    angles = jnp.asarray(angles, dtype=float)
    return rotation_matrix(angles[..., 0], angles[..., 1], angles[..., 2])


def to_chip(rotations: Float[ArrayLike, "s 3 3"], field: Float[ArrayLike, "*n s 3"]) -> Float[Array, "*n s 3"]:
    """The field (T) expressed in each chip's frame: ``rotations @ field`` per chip."""
    return jnp.einsum("...ij,...j->...i", rotations, field)
