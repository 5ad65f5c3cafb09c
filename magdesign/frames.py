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

# Below this angle (rad) rotate_by_vector takes sin(a) / a and (1 - cos a) / a^2 from their
# series (error below a^4 / 120), where the closed forms lose digits to cancellation.
ROTATION_SERIES_ANGLE = 1e-4


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


def rotate_by_vector(
    vector: Float[ArrayLike, "... 3"], rotation_vector: Float[ArrayLike, "... 3"]
) -> Float[Array, "... 3"]:
    """``vector`` (any unit, (..., 3)) turned by the angle |w| (rad) about the axis of the
    rotation vector w (rad, (..., 3)), right-handed (Rodrigues' formula); smooth, with finite
    derivatives, at w = 0."""
    v, w = jnp.broadcast_arrays(jnp.asarray(vector, dtype=float), jnp.asarray(rotation_vector, dtype=float))
    squared = jnp.sum(w * w, axis=-1, keepdims=True)
    series = squared < ROTATION_SERIES_ANGLE**2
    safe = jnp.where(series, 1.0, squared)  # the double where: no 0/0 in the unused branch's gradient
    angle = jnp.sqrt(safe)
    sine = jnp.where(series, 1.0 - squared / 6.0, jnp.sin(angle) / angle)
    versine = jnp.where(series, 0.5 - squared / 24.0, (1.0 - jnp.cos(angle)) / safe)
    cross = jnp.cross(w, v)
    return v + sine * cross + versine * jnp.cross(w, cross)
