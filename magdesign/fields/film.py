"""Sinusoidally magnetised flexible film (seed 004, Eq. 1; PHYSICS.md 1.2).

A film of thickness d carries a 1-D sinusoidal (Halbach-like) magnetisation of period
T, k = 2 pi / T. At depth z below its bottom face and lateral position x:

    |B|(z)  = M0 (e^{kd} - 1) e^{-kz}      (independent of x)
    Bx / Bz = tan(kx)                       (independent of z)

so Bx = |B| sin(kx), Bz = |B| cos(kx). Normal load moves the film in z and changes |B|
only; shear moves it in x and changes the field angle only.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import safe_atan2
from magdesign._validation import check_positive


def film_magnitude(
    z: Float[ArrayLike, "..."], *, period: float, thickness: float, magnetization: float
) -> Float[Array, "..."]:
    """|B| (T) at depth ``z`` (m) below the film's bottom face.

    Args:
        z: depth below the bottom face (m), any shape; z >= 0 is the physical range.
        period: magnetisation period T (m), > 0.
        thickness: film thickness d (m), > 0.
        magnetization: the field scale M0 of seed 004 Eq. 1, as a flux density (T).

    Written as e^{k(d - z)} (1 - e^{-kd}) with ``expm1``: the same value as
    M0 (e^{kd} - 1) e^{-kz}, but e^{kd} never overflows and 1 - e^{-kd} keeps full
    relative precision for a thin film (kd << 1).
    """
    check_positive(period=period, thickness=thickness)
    k = 2.0 * jnp.pi / period
    return magnetization * jnp.exp(k * (thickness - jnp.asarray(z))) * -jnp.expm1(-k * thickness)


def film(
    x: Float[ArrayLike, "..."],
    z: Float[ArrayLike, "..."],
    *,
    period: float,
    thickness: float,
    magnetization: float,
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(Bx, Bz) (T) of the film at lateral position ``x`` (m) and depth ``z`` (m).

    ``x`` and ``z`` broadcast together. Bx = |B| sin(kx), Bz = |B| cos(kx) with
    k = 2 pi / period; see :func:`film_magnitude` for the arguments.
    """
    magnitude = film_magnitude(z, period=period, thickness=thickness, magnetization=magnetization)
    phase = 2.0 * jnp.pi / period * jnp.asarray(x)
    return magnitude * jnp.sin(phase), magnitude * jnp.cos(phase)


def film_angle(bx: Float[ArrayLike, "..."], bz: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Field angle atan2(Bx, Bz) (rad) in (-pi, pi]: equals kx for |kx| < pi.

    Use this, never arctan(Bx / Bz): it is finite and exact at kx = +-pi/2 where
    Bz = 0, and it keeps the quadrant beyond. Its gradient stays finite however weak
    the field (:func:`magdesign._numerics.safe_atan2`); at Bx = Bz = 0 it returns 0.
    """
    return safe_atan2(bx, bz)
