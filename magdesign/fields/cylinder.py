"""Axially magnetised solid cylinder: exact field everywhere (PHYSICS.md 1.1).

Layers (as in magpylib): a dimensionless core in the magnet frame with lengths in
units of the radius, the public wrapper applying scale and polarization on top.

The exact kernel is Derby and Olbert, Am. J. Phys. 78, 229 (2010): for a face at
height z_f = z -+ h/2, alpha = 1 / sqrt(z_f^2 + (1 + rho)^2), k_c^2 = (z_f^2 + (1 - rho)^2)
alpha^2 and gamma = (1 - rho) / (1 + rho),

    B_rho = J/pi   sum_faces +- alpha cel(k_c, 1, 1, -1)
    B_z   = J/pi / (1 + rho) sum_faces +- z_f alpha cel(k_c, gamma^2, 1, gamma)

valid inside and outside (B, not H). Far away the two faces cancel, and the field is
taken from the axial multipole series instead (magdesign.fields._special).
"""

import math

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import double_where, float_array, safe_sqrt
from magdesign._validation import check_last_axis, check_positive
from magdesign.fields._special import (
    KC_MIN,
    MULTIPOLE_SWITCH,
    MULTIPOLE_TERMS,
    axial_multipole,
    cel_face_pair,
    rsqrt,
)
from magdesign.fields.dipole import dipole
from magdesign.units import MU0

FIDELITIES = ("exact", "dipole", "axis")


def _binomial(x, n):
    """Generalised binomial coefficient x choose n (x real, n >= 0 integer)."""
    return math.prod(x - i for i in range(n)) / math.factorial(n)


# On the axis, with radius 1 and half height b, B_z / J = sum_l c_l / z^(l+2) for odd
# l, from expanding the closed form (u / sqrt(1 + u^2) at u = z +- b) in 1/z:
# c_l = sum over n >= 1, odd m with 2n + m = l + 2 of binom(-1/2, n) binom(-2n, m) b^m.
_MULTIPOLE_POLYNOMIALS = tuple(
    tuple((m, _binomial(-0.5, (l + 2 - m) // 2) * _binomial(-(l + 2 - m), m)) for m in range(1, l + 1, 2))
    for l in range(1, 2 * MULTIPOLE_TERMS, 2)
)


def _exact_core(rho2, z, b):
    """(B_rho / rho, (1 + rho) B_z) / J of the cylinder of radius 1, half height b."""
    rho = safe_sqrt(rho2)
    gamma = (1.0 - rho) * rsqrt(1.0 + rho) ** 2
    b_rho_over_rho = 0.0
    b_z = 0.0
    for sign, z_face in ((1.0, z + b), (-1.0, z - b)):
        alpha = rsqrt(z_face * z_face + (1.0 + rho) ** 2)
        alpha2 = alpha * alpha
        # On an edge (rho = 1, z_face = 0) k_c = 0: see KC_MIN for the value returned.
        kc2 = jnp.maximum((z_face * z_face + (1.0 - rho) ** 2) * alpha2, KC_MIN * KC_MIN)
        kc = kc2 * rsqrt(kc2)
        radial, axial = cel_face_pair(kc, gamma)
        # cel(k_c, 1, 1, -1) = (1 - k_c) radial and 1 - k_c = 4 rho alpha^2 / (1 + k_c).
        b_rho_over_rho = b_rho_over_rho + sign * 4.0 * alpha * alpha2 * radial / (1.0 + kc)
        b_z = b_z + sign * z_face * alpha * axial
    return b_rho_over_rho / jnp.pi, b_z / jnp.pi


def _core(rho2, z, b):
    """(B_rho / rho, B_z) / J, exact kernel near the magnet, multipole series far away."""
    switch_r2 = MULTIPOLE_SWITCH**2 * (1.0 + b * b)
    coefficients = [sum(coef * b**m for m, coef in poly) for poly in _MULTIPOLE_POLYNOMIALS]
    far_rho, far_z = axial_multipole(coefficients, rho2, z, switch_r2)
    near_rho, near_z = _exact_core(rho2, z, b)
    far = rho2 + z * z > switch_r2
    # Both results end in one true division, by 1 + rho: XLA (CPU) then computes each
    # kernel once into memory, instead of fusing and re-running it for every output
    # component (cheap producers are duplicated into each consumer; a division, used
    # twice, is not). This doubles the speed.
    one_rho = 1.0 + safe_sqrt(rho2)
    b_rho_over_rho = jnp.where(far, far_rho * one_rho, near_rho * one_rho) / one_rho
    b_z = jnp.where(far, far_z * one_rho, near_z) / one_rho
    return b_rho_over_rho, b_z


def cylinder(
    points: Float[ArrayLike, "... 3"],
    *,
    radius: Float[ArrayLike, ""],
    height: Float[ArrayLike, ""],
    polarization: Float[ArrayLike, ""],
    fidelity: str = "exact",
) -> Float[Array, "... 3"]:
    """Flux density B (T) of a uniformly, axially magnetised solid cylinder.

    Args:
        points: observation points (m) in the magnet frame, shape (..., 3): centre at
            the origin, axis along z, magnetised along +z. Inside and outside.
        radius: cylinder radius R (m), > 0.
        height: cylinder height D (m), > 0.
        polarization: magnetic polarization J = mu0 M (T) along +z (the remanence Br
            for a permanent magnet); any sign.
        fidelity: "exact" (Derby-Olbert with Bulirsch's cel; beyond MULTIPOLE_SWITCH
            enclosing-sphere radii the axial multipole series; relative error below
            1e-12 at any distance) or "dipole" (the point dipole of the same moment
            J pi R^2 D / mu0; relative error O((R^2 + D^2/4) / r^2) far away, wrong near),
            or "axis" (seed 001's on-axis closed form, :func:`cylinder_on_axis`, taken at
            the point's height: exact on the axis, where B_rho = 0; off the axis an
            approximation whose error grows like (rho / R)^2, for scenes whose sensors sit
            on the axis and move along it).

    Returns:
        B (T), shape (..., 3).

    Conventions at the singular points (fidelity "exact"):
        - on the side wall (rho = R, |z| < D/2), where B_z jumps by J across the
          surface current, B_z is the mean of its inside and outside limits;
        - on an edge (rho = R, z = +-D/2), where B_rho diverges logarithmically, the
          value is that at about 2e-15 R from the edge (see _special.KC_MIN).
    """
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    check_last_axis("points", points, 3)
    check_positive(radius=radius, height=height)
    points = float_array(points)
    if fidelity == "dipole":
        moment = polarization * jnp.pi * radius**2 * height / MU0
        return dipole(points, jnp.stack([jnp.zeros_like(moment), jnp.zeros_like(moment), moment], axis=-1))
    if fidelity == "axis":
        # B_z on the axis is even in z: the height above the nearer face is |z| - D/2.
        b_z = cylinder_on_axis(jnp.abs(points[..., 2]) - 0.5 * height, radius=radius, height=height, remanence=polarization)
        return jnp.stack([jnp.zeros_like(b_z), jnp.zeros_like(b_z), b_z], axis=-1)
    x, y, z = points[..., 0] / radius, points[..., 1] / radius, points[..., 2] / radius
    b_rho_over_rho, b_z = _core(x * x + y * y, z, 0.5 * height / radius)
    return polarization * jnp.stack([b_rho_over_rho * x, b_rho_over_rho * y, b_z], axis=-1)


def cylinder_on_axis(
    z: Float[ArrayLike, "..."],
    *,
    radius: Float[ArrayLike, ""],
    height: Float[ArrayLike, ""],
    remanence: Float[ArrayLike, ""],
) -> Float[Array, "..."]:
    """B_z (T) on the axis of an axially magnetised cylinder (seed 001, Eq. 1).

        B_z = Br/2 [(D + z) / sqrt(R^2 + (D + z)^2) - z / sqrt(R^2 + z^2)]

    Args:
        z: distance (m) above the TOP face, any shape; negative values go into the
            magnet (-D < z < 0) and below it.
        radius: R (m), > 0.
        height: D (m), > 0.
        remanence: Br (T).

    Returns:
        B_z (T), shape of ``z``. With u = D + z, v = z and s_u, s_v the two roots, the
        bracket is evaluated as R^2 D (u + v) / (s_u s_v (u s_v + v s_u)) where u, v have
        the same sign (no cancellation at any distance), and as written where they differ.
    """
    check_positive(radius=radius, height=height)
    z = float_array(z)
    u = height + z
    s_u = jnp.sqrt(radius**2 + u * u)
    s_v = jnp.sqrt(radius**2 + z * z)
    opposite = u * z < 0.0
    direct = u / s_u - z / s_v
    # Where u and v differ in sign u s_v + v s_u can vanish (at the centre, z = -D/2).
    combined = double_where(
        opposite,
        direct,
        lambda zz: radius**2 * height * (height + 2.0 * zz) / (s_u * s_v * ((height + zz) * s_v + zz * s_u)),
        z,
    )
    return 0.5 * remanence * combined
