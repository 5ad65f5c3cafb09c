"""Frames: the rotation of a body (a sensor chip, a magnet, a soft part) and the maps of
vectors into and out of its own frame.

An orientation is three angles (alpha, beta, gamma) (rad); a vector v given in the scene
(world) frame reads, in the body's own frame,

    v_body = Rx(alpha) Ry(beta) Rz(gamma) v = M v

with the right-handed rotation matrices of the spin-valve paper's Eq. 4, and back,
v = M^T v_body. For a chip the body frame is (a, b, c), ``a`` its sensitive in-plane axis
and ``c`` its normal; for a magnet it is the frame of :func:`magdesign.fields.cylinder`
(centre at the origin, axis z).
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float


def rotation_matrix(
    alpha: Float[ArrayLike, "..."], beta: Float[ArrayLike, "..."], gamma: Float[ArrayLike, "..."]
) -> Float[Array, "... 3 3"]:
    """Rx(alpha) Ry(beta) Rz(gamma) (the spin-valve paper's Eq. 4), angles in rad, broadcast together."""
    alpha, beta, gamma = jnp.broadcast_arrays(*(jnp.asarray(a, dtype=float) for a in (alpha, beta, gamma)))
    one, zero = jnp.ones_like(alpha), jnp.zeros_like(alpha)

    def matrix(rows):
        return jnp.stack([jnp.stack(row, axis=-1) for row in rows], axis=-2)

    ca, sa = jnp.cos(alpha), jnp.sin(alpha)
    cb, sb = jnp.cos(beta), jnp.sin(beta)
    cg, sg = jnp.cos(gamma), jnp.sin(gamma)
    rx = matrix([[one, zero, zero], [zero, ca, -sa], [zero, sa, ca]])
    ry = matrix([[cb, zero, sb], [zero, one, zero], [-sb, zero, cb]])
    rz = matrix([[cg, -sg, zero], [sg, cg, zero], [zero, zero, one]])
    return rx @ ry @ rz


def rotation(angles: Float[ArrayLike, "... 3"]) -> Float[Array, "... 3 3"]:
    """Rx(alpha) Ry(beta) Rz(gamma) for ``angles = (alpha, beta, gamma)`` (rad), (..., 3, 3)."""
    angles = jnp.asarray(angles, dtype=float)
    return rotation_matrix(angles[..., 0], angles[..., 1], angles[..., 2])


def to_body(rotations: Float[ArrayLike, "... 3 3"], field: Float[ArrayLike, "... 3"]) -> Float[Array, "... 3"]:
    """The vector ``field`` (any unit) expressed in each body's (chip's) frame:
    ``rotations @ field``, the rotations (..., 3, 3) broadcast against the field (..., 3)
    (one per chip: (S, 3, 3) against (n, S, 3))."""
    return jnp.einsum("...ij,...j->...i", rotations, field)


def from_body(matrix: Float[ArrayLike, "3 3"], field: Float[ArrayLike, "... 3"]) -> Float[Array, "... 3"]:
    """The vectors ``field`` (any unit, (..., 3)) given in the frame of one body whose
    rotation is ``matrix`` (3, 3), expressed in the scene frame: M^T v."""
    return jnp.einsum("ji,...j->...i", matrix, field)
