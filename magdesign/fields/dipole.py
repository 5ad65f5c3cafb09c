"""Point magnetic dipole: the far field of every finite magnet."""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import float_array, safe_div, safe_sqrt
from magdesign._validation import check_broadcasts, check_last_axis
from magdesign.units import MU0


def dipole(points: Float[ArrayLike, "... 3"], moment: Float[ArrayLike, "... 3"]) -> Float[Array, "... 3"]:
    """Flux density B (T) of a point dipole at the origin.

        B = mu0 / (4 pi) [3 (m . r) r / r^5 - m / r^3]

    Args:
        points: observation points (m), shape (..., 3).
        moment: dipole moment m (A m^2), shape (..., 3), broadcasting with ``points``.

    Returns:
        B (T), shape of ``points`` and ``moment`` broadcast together. At the dipole
        itself (r = 0), where the field is singular, B = 0 with zero gradient.
    """
    check_last_axis("points", points, 3)
    check_last_axis("moment", moment, 3)
    check_broadcasts("points", points, moment=moment)
    points = float_array(points)
    moment = float_array(moment)
    inv_r2 = safe_div(1.0, jnp.sum(points * points, axis=-1, keepdims=True))
    inv_r3 = inv_r2 * safe_sqrt(inv_r2)
    m_dot_r = jnp.sum(moment * points, axis=-1, keepdims=True)
    return MU0 / (4.0 * jnp.pi) * (3.0 * m_dot_r * inv_r2 * points - moment) * inv_r3
