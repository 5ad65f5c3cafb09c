"""Sinusoidally magnetised flexible film (Yan et al., "Soft magnetic skin for super-resolution
tactile sensing with force self-decoupling", Sci. Robot. 6, eabc8801 (2021)).

The film's own frame: x along the magnetisation pattern, z the depth below the film's
bottom face (pointing away from the film, towards the sensors), y along the stripes.
The film fills -d <= z <= 0 with the polarization (Halbach pattern, period T, k = 2 pi / T)

    J(x) = J0 (-sin kx, 0, cos kx)

whose strong side faces the sensors. Below an infinite film (z >= 0), from its magnetic
charges (and checked against an independent charge integration in the tests):

    B = J0 (1 - e^{-kd}) e^{-kz} (sin kx, cos kx)      (Bx, Bz in this frame)

so |B| = J0 (1 - e^{-kd}) e^{-kz} depends on z only and Bx / Bz = tan(kx) on x only:
normal load (z) changes |B| only, shear (x) the field angle only. Yan et al.'s Eq. 1 prints
M0 (e^{kd} - 1) e^{-kz}, which is this field with z measured from the film's TOP face;
measured from the bottom face, as here, it is e^{kd} too large. Bz here is the component
along the depth axis; in a frame whose z axis points up towards the film (a scene's
frame), the same field reads (Bx, -Bz) (see :class:`magdesign.scene.FilmScene`).

A film only a few periods wide is not infinite (its edges carry magnetic charges): with
``periods=N`` the field is the exact one of a strip of N periods, |x| <= N T / 2, still
infinite along y (:func:`film`).
"""

import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import EDGE_DISTANCE_MIN, expm1_ratio, safe_atan2
from magdesign._validation import check_broadcasts, check_positive, renamed_keyword

# Gauss-Legendre nodes per half period of a finite film (see _strip_field): the smooth
# part of its integrand is e^{ikx} times an entire function of x, integrated over
# k * T / 2 = pi, so the error of n nodes falls like pi^(2n+1) (n!)^4 / ((2n+1) ((2n)!)^3):
# 1e-20 at n = 10, 2e-25 at FILM_NODES. Measured against 1000 nodes per half period:
# below 1e-15 relative at every depth.
FILM_NODES = 12
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(FILM_NODES)


def film_magnitude(
    z: Float[ArrayLike, "..."],
    *,
    period: float,
    thickness: float,
    polarization: float | None = None,
    magnetization: float | None = None,
) -> Float[Array, "..."]:
    """|B| (T) at depth ``z`` (m) below the bottom face of an infinite film.

    Args:
        z: depth below the bottom face (m), any shape; z >= 0 is the physical range.
        period: magnetisation period T (m), > 0.
        thickness: film thickness d (m), > 0.
        polarization: the amplitude J0 = mu0 M0 of the film's polarization (T);
            ``magnetization`` is its deprecated name (the same quantity, in T).

    Returns |B| = J0 (1 - e^{-kd}) e^{-kz}, with 1 - e^{-kd} = -expm1(-kd) (full
    relative precision for a thin film, kd << 1); never overflows.
    """
    polarization = renamed_keyword("film_magnitude", "magnetization", magnetization, "polarization", polarization)
    return _magnitude(z, period, thickness, polarization)


def _magnitude(z, period, thickness, polarization):
    check_positive(period=period, thickness=thickness, unit="m")
    k = 2.0 * jnp.pi / period
    return polarization * -jnp.expm1(-k * thickness) * jnp.exp(-k * jnp.asarray(z))


def _strip_term(w, k, half_width, panels):
    """(1/2pi) int_{-a}^{a} e^{ikx'} / (w - x') dx' for Im w > 0 (a = ``half_width``).

    Written as the exactly integrable pole part e^{ikw} [log(w + a) - log(w - a)] plus
    -ik int e^{ikx'} phi1(ik (w - x')) dx', phi1(s) = expm1(s) / s: an entire integrand
    (the pole is removed) that stays bounded however close w is to the film, integrated
    by Gauss-Legendre over ``panels`` half periods. e^{ikw} underflows harmlessly deep
    below the film; Re(ik (w - x')) = -k Im w <= 0, so nothing overflows.
    """
    # At a corner of the film (w = +-a) the field diverges logarithmically: the value
    # returned is that at EDGE_DISTANCE_MIN widths from the corner.
    floor = EDGE_DISTANCE_MIN * 2.0 * half_width

    def log_distance(u):
        return jnp.log(jnp.where(jnp.abs(u) < floor, floor, u))

    pole = jnp.exp(1j * k * w) * (log_distance(w + half_width) - log_distance(w - half_width))
    edges = np.linspace(-1.0, 1.0, panels + 1)
    centres = jnp.asarray((edges[1:] + edges[:-1]) / 2)[:, None] * half_width
    offsets = jnp.asarray(_NODES / panels) * half_width
    nodes = (centres + offsets).ravel()
    weights = jnp.asarray(np.tile(_WEIGHTS, panels) / panels) * half_width
    w = w[..., None]
    smooth = jnp.sum(weights * jnp.exp(1j * k * nodes) * expm1_ratio(1j * k * (w - nodes)), axis=-1)
    return (pole - 1j * k * smooth) / (2.0 * jnp.pi)


def _strip_field(x, z, k, thickness, polarization, periods):
    """(Bx, Bz) of a strip of ``periods`` periods, |x| <= periods pi / k, in the film frame.

    From the line dipoles of the film, in complex form (w = x + i z):
    Bx - i Bz = J0 / (2 pi) int_{-a}^{a} e^{ikx'} [1 / (w - x') - 1 / (w + i d - x')] dx'
    (the depth integral done exactly), which is the infinite film's field as a -> infinity.
    """
    w = x + 1j * z
    half_width = periods * jnp.pi / k
    panels = 2 * periods
    complex_field = polarization * (
        _strip_term(w, k, half_width, panels) - _strip_term(w + 1j * thickness, k, half_width, panels)
    )
    return jnp.real(complex_field), -jnp.imag(complex_field)


def film(
    x: Float[ArrayLike, "..."],
    z: Float[ArrayLike, "..."],
    *,
    period: float,
    thickness: float,
    polarization: float | None = None,
    periods: int | None = None,
    magnetization: float | None = None,
) -> tuple[Float[Array, "..."], Float[Array, "..."]]:
    """(Bx, Bz) (T) of the film at lateral position ``x`` (m) and depth ``z`` (m).

    Args:
        x: position along the pattern (m); ``x`` and ``z`` broadcast together.
        z: depth below the film's bottom face (m), >= 0: the film, an infinite sheet with
            no centre, is the one source whose positions are measured from a face (see
            docs/models.md, "Conventions").
        period, thickness, polarization: T (m), d (m), J0 (T); see :func:`film_magnitude`
            (``magnetization`` is the deprecated name of ``polarization``).
        periods: None for an infinite film (closed form: Bx = |B| sin kx, Bz = |B| cos kx);
            an integer N >= 1 (static) for a strip N periods wide centred on x = 0, computed
            exactly up to Gauss-Legendre quadrature of an entire integrand (FILM_NODES per
            half period: below 1e-15 relative at any depth), at 4 N FILM_NODES complex
            exponentials per point.

    Returns:
        (Bx, Bz) in the film frame (module docstring): Bz along the depth axis.
    """
    polarization = renamed_keyword("film", "magnetization", magnetization, "polarization", polarization)
    check_positive(period=period, thickness=thickness, unit="m")
    check_broadcasts("x", x, z=z)
    k = 2.0 * jnp.pi / period
    x, z = jnp.asarray(x, dtype=float), jnp.asarray(z, dtype=float)
    if periods is not None:
        if not (isinstance(periods, int) and periods >= 1):
            raise ValueError(f"periods must be None or an integer >= 1, got {periods!r}")
        return _strip_field(x, z, k, thickness, polarization, periods)
    magnitude = _magnitude(z, period, thickness, polarization)
    return magnitude * jnp.sin(k * x), magnitude * jnp.cos(k * x)


def film_angle(bx: Float[ArrayLike, "..."], bz: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Field angle atan2(Bx, Bz) (rad) in (-pi, pi], film frame: equals kx for |kx| < pi
    below an infinite film.

    Use this, never arctan(Bx / Bz): it is finite and exact at kx = +-pi/2 where
    Bz = 0, and it keeps the quadrant beyond. Its gradient stays finite however weak
    the field (:func:`magdesign._numerics.safe_atan2`); at Bx = Bz = 0 it returns 0.
    """
    return safe_atan2(bx, bz)
