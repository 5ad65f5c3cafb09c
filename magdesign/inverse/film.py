"""Yan et al.'s (2021) closed-form force read-out (Eq. 3) for the film scene.

    Fz = c1 S E / (k h) ln(|B|(z1) / |B|(z0)) + b1
    Fx = c2 S G / (k h) (phi0 - phi1) + b2

|B| and the field angle phi of one taxel at rest (index 0) and loaded (1);
k = 2 pi / T. Readings are in the scene frame (z up, towards the film); the angle is
the film frame's, phi = atan2(Bx, -Bz) = kx below an infinite film
(:class:`magdesign.scene.FilmScene`), so a shear u moves it by -k u. The paper writes arctan(R_B) with R_B = Bx / Bz; the
angle difference is the same for |kx| < pi/2 and stays exact beyond (atan2, not
arctan of a ratio). S E / h and S G / h are the layer's stiffnesses k_n and k_s
(:func:`magdesign.mechanics.layer_stiffness`; E is the effective compression modulus
at the "bonded" fidelity). c1 = c2 = 1, b1 = b2 = 0 is the ideal model; the paper fits
all four.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign.fields import film_angle
from magdesign.scene.film_scene import FilmScene


def film_forces(
    scene: FilmScene,
    rest: Float[ArrayLike, "... 3"],
    loaded: Float[ArrayLike, "... 3"],
    *,
    c1: float = 1.0,
    c2: float = 1.0,
    b1: float = 0.0,
    b2: float = 0.0,
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(Fz, Fx) (N) from a taxel's readings (Bx, By, Bz) (T) at rest and loaded."""
    rest, loaded = jnp.asarray(rest), jnp.asarray(loaded)
    k = 2.0 * jnp.pi / scene.period
    stiffness = scene.layer.stiffness
    magnitude_ratio = jnp.linalg.norm(loaded, axis=-1) / jnp.linalg.norm(rest, axis=-1)
    fz = c1 * stiffness.normal / k * jnp.log(magnitude_ratio) + b1
    turn = film_angle(rest[..., 0], -rest[..., 2]) - film_angle(loaded[..., 0], -loaded[..., 2])
    fx = c2 * stiffness.shear / k * turn + b2
    return fz, fx
