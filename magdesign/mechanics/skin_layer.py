"""Displacement field of an elastic layer bonded to a rigid base under a local surface load.

The layer (thickness h, shear modulus mu, Poisson's ratio nu) fills 0 <= z <= h, with
u = 0 on the base z = 0 and a prescribed traction on the top surface z = h: a normal
pressure p(r) and a tangential traction q(r) along a fixed direction, both on a disc of
radius a about the load centre. Linear, small-strain elasticity; the result is the
displacement vector u(x, y, z) anywhere in the layer (SI: m, Pa, N).

Method (Sneddon, "Fourier Transforms", 1951; the layer problem as in Burmister, "The
general theory of stresses and displacements in layered systems", J. Appl. Phys. 16,
1945): a 2-D Fourier transform in (x, y) turns the Navier equations into ordinary
differential equations in z for each wavenumber k. Along the wavevector the in-plane
(longitudinal) and vertical displacements couple (four solutions, e^(kz), kz e^(kz),
e^(-kz), kz e^(-kz) with the Kolosov constant kappa = 3 - 4 nu); across it the transverse
displacement is sinh(kz) alone. The four coefficients come from a 4 x 4 linear solve per
k: u = 0 at z = 0, traction at z = h. The growing solutions are written about the top
surface, e^(k (z - h)), and the decaying ones about the base, e^(-k z), so no entry of the
4 x 4 matrix exceeds 1 and nothing overflows however large k h is (the coupling between
the faces is e^(-k h)). Because the layer is written with mu and kappa only
(lambda (kappa - 1) = mu (3 - kappa)), nu = 0.5 (kappa = 1, incompressible) is exact, not
a limit: the displacements stay finite and smooth through it.

For a load whose magnitude is axisymmetric the inverse transform reduces to Hankel
integrals over k with J0, J1 / (k r) and J2 / (k r)^2 (the tangential load has the
angular orders 0, 1 and 2). They are computed with fixed Gauss-Legendre nodes in
s = k a: geometric panels from s = 1e-6 to 1 (the layer's own scale k ~ 1 / h when
h >> a: the thick-layer limit), then equal panels of width 1/2 (:data:`DEFAULT_QUADRATURE`).
The node spacing follows the load radius because the oscillations come from J(k r) and
the load's transform J(k a); the thickness enters the kernels smoothly, through e^(-k h)
and e^(-k (h - z)), on the scale s ~ a / h, resolved for a thin layer as for a thick one.
On the surface the integrands decay only with the load's transform (k^(-3/2) for the
uniform disc, k^(-2) for Hertz's), and a sharp cut at some s_max would leave an error of
the half-space's size times s_max^(-2): far more than the whole displacement of a thin
layer, which is (h / a)^3 times the half-space's. The integrands are therefore cut
smoothly, by the window erfc((s - 100) / 25) / 2 (nodes to s = 250): an oscillating part
exp(i w s) (w = |r +- a| / a) then leaves an error of order exp(-(25 w)^2 / 4), nil
except within about a / 10 of the load's edge r = a, where the field is as if the load's
edge were smoothed over about a / 25. Inside the layer the integrands also decay like
e^(-k (h - z)). The panels resolve the oscillation of J0(k r) for r / a up to about 40;
further out a bonded layer's displacement has decayed exponentially (over a few h when
h < r / 10) and is returned as the (small) quadrature residue. Nodes scale with a, so the
result is differentiable in h, a, mu, nu, the forces and the load centre.

On the cells of a layer (a regular grid of centres, :func:`layer_displacement_grid`) the
displacement and its rotation curl(u) / 2 come instead from a 2-D Fourier sum per level of
cells: the transfer functions times the load's transform and the phase of its centre, on a
lattice of wavevectors k = 2 pi (m_x / (P_x dx), m_y / (P_y dy)) (dx, dy the cell sides,
P_x, P_y whole numbers of cells), summed by an inverse FFT. The sum is the field made periodic
with the periods P dx, P dy: each period spans the layer and SPECTRAL_PADDING thicknesses
beyond it, where a bonded layer's displacement has fallen below about 1e-3 of its peak (it
decays like e^(-0.85 r / h) at nu = 0.49). Sampled at the cells only, the lattice folds onto
the cell grid's own (modes m and m + P give the same values there), so a fine lattice costs
one pass over half its modes (the field is real: the modes -m are the conjugates of m) and
an FFT of P_x x P_y. At a level d below the top the kernels
decay like e^(-k d): its lattice reaches k d >= SPECTRAL_REACH along each axis, a whole
multiple r of the cell grid's own reach pi / dx (:func:`spectral_grid`; with 7, the sum
matches the Hankel quadrature to about 1e-4 of the peak displacement and 3e-4 of the peak
rotation on a 2 mm layer of 16 x 16 x 8 cells). The z-derivatives of the rotation are those
of the kernels (forward-mode in z), the in-plane ones i k. The lattice's counts are static,
chosen from concrete values of the layer's size and thickness; where a design then moves them
the counts stay, and the reach k d scales with h / dx (halved if the layer thins by half).

Load profiles (total normal force Fn, tangential force Ft, radius a):

- ``"uniform"``: p = Fn / (pi a^2), q = Ft / (pi a^2) on r < a.
- ``"hertz"``: p = p0 sqrt(1 - r^2 / a^2), p0 = 3 Fn / (2 pi a^2), and the tangential
  traction of the same shape with q0 = 3 Ft / (2 pi a^2) (full sliding, or Mindlin's
  tangential load without slip annulus: K. L. Johnson, "Contact Mechanics", 1985, ch. 3
  and 7).
- ``"thin"``: p = p0 (1 - r^2 / a^2)^2, p0 = 3 Fn / (pi a^2) (and q likewise): the contact
  pressure of a sphere on a thin incompressible bonded layer (:func:`thin_layer_contact`).
- ``"flat"``: p = Fn / (2 pi a^2 sqrt(1 - r^2 / a^2)) (and q likewise): a rigid flat punch
  of radius a on the half-space (Boussinesq's pressure, Johnson 1985, ch. 3), which presses
  its face down uniformly by Fn (1 - nu) / (4 mu a). On a layer it holds while a / h is
  small, as Hertz's does: the base stiffens the layer under a wide punch.

Contact of a rigid sphere of radius R, two limits:

- :func:`hertz_contact`, the half-space (Johnson 1985, ch. 4): a = (3 Fn R / (4 E*))^(1/3),
  E* = 2 mu / (1 - nu), Hertz's pressure, depth a^2 / R; valid while a / h is small. On
  a bonded layer (nu 0.49-0.5) the surface under Hertz's pressure keeps the half-space's
  curvature to 0.1 % at a / h = 0.1, 2 % at 0.3, 8 % at 0.5 (so the contact radius, which
  goes as its cube root, to 1 % up to a / h = 0.3, 3 % at 0.5), but the depth is smaller than the
  half-space's already at a / h = 0.1 (by 7 %; 22 % at 0.3): take the depth from
  :func:`layer_displacement` at the centre there.
- :func:`thin_layer_contact`, a thin incompressible layer (a / h large, nu = 0.5): the
  layer squeezes out like a lubricating film, w = h^3 lap(p) / (3 mu) (a half-Poiseuille
  flow through the thickness, no shear on top), so the sphere's shape
  w = -(delta - r^2 / (2 R)) needs lap(p) to be a quadratic in r, and p = 0 with p' = 0 at
  the edge gives p = p0 (1 - r^2 / a^2)^2, p0 = 3 mu a^4 / (32 h^3 R), so
  a = (32 Fn h^3 R / (pi mu))^(1/6), delta = a^2 / (4 R). Its error is of order
  (h / a)^2: the layer's surface under this pressure departs from the sphere's depth by
  3 % at a / h = 21 and 0.8 % at 42. Between the limits neither is exact; the contact
  radius of the finite layer is not solved for here.
"""

import dataclasses
import itertools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import double_where
from magdesign._validation import _concrete, check_positive

PROFILES = ("uniform", "hertz", "thin", "flat")

# The cells' grid evaluation (module docstring): each period spans the layer and this many
# thicknesses beyond it, and at a level d below the top the lattice reaches k d >= SPECTRAL_REACH.
SPECTRAL_PADDING = 10.0
SPECTRAL_REACH = 7.0
# The k = 0 mode (a mean displacement) is the kernels' limit k h -> 0, taken at this k h.
ZERO_MODE_KH = 1e-6

# Bessel functions: the power series below SERIES_LIMIT (its largest term there is
# 6^12 / (6!)^2 ~ 4e3, so cancellation leaves ~1e-12 absolute), the Hankel asymptotic
# expansion above it (truncated at ASYMPTOTIC_TERMS, error ~ e^(-2 x) ~ 4e-11 at x = 12).
SERIES_LIMIT = 12.0
SERIES_TERMS = 32
ASYMPTOTIC_TERMS = 22
# Hertz's load transform 3 (sin x - x cos x) / x^3 switches to its series (to x^6, the
# first term left out x^8 / 1330560 < 1e-13 here) below this argument, where the
# difference loses digits (x^3 / 3 from two terms of size x: 3e-14 relative here).
HERTZ_SERIES_LIMIT = 0.1


class Quadrature(eqx.Module):
    """Gauss-Legendre nodes for the inverse Hankel transforms, in s = k a (dimensionless).

    Attributes:
        s: nodes (M,), in s = k a, a the load radius.
        weights: their weights (M,).
    """

    s: Float[Array, " M"]
    weights: Float[Array, " M"]


def make_quadrature(
    *,
    s_min: float = 1e-6,
    s_geometric: float = 1.0,
    s_taper: float = 100.0,
    taper_width: float = 25.0,
    width: float = 0.5,
    order: int = 12,
) -> Quadrature:
    """Nodes on [0, s_taper + 6 taper_width]: one panel [0, s_min], geometric panels (one per
    decade) up to ``s_geometric``, then equal panels of ``width``; ``order`` Gauss-Legendre
    nodes per panel. The weights carry the window erfc((s - s_taper) / taper_width) / 2
    (module docstring). All arguments are dimensionless and static."""
    s_max = s_taper + 6.0 * taper_width  # where the window has fallen to erfc(6) / 2 = 1e-17
    decades = max(1, round(math.log10(s_geometric / s_min)))
    edges = np.concatenate(
        [[0.0], np.geomspace(s_min, s_geometric, decades + 1), np.arange(s_geometric + width, s_max + width / 2, width)]
    )
    x, w = np.polynomial.legendre.leggauss(order)
    lo, hi = edges[:-1, None], edges[1:, None]
    s = (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel()
    window = np.array([0.5 * math.erfc((si - s_taper) / taper_width) for si in s])
    weights = (0.5 * (hi - lo) * w).ravel() * window
    # numpy arrays: building the default at import starts no JAX backend (the CLI sets the
    # number of CPU devices after import)
    return Quadrature(s=np.asarray(s, np.float64), weights=np.asarray(weights, np.float64))


DEFAULT_QUADRATURE = make_quadrature()


def _series_coefficients(n):
    """Coefficients c_m of J_n(x) / x^n = sum_m c_m (x^2 / 4)^m (highest power first)."""
    return np.array([(-1.0) ** m / (2.0**n * math.factorial(m) * math.factorial(m + n)) for m in range(SERIES_TERMS)])[
        ::-1
    ]


_SERIES = {n: _series_coefficients(n) for n in (0, 1, 2, 3)}


def _asymptotic_coefficients(n):
    """a_j(n) = prod_{i=1..j} (4 n^2 - (2 i - 1)^2) / (j! 8^j), the Hankel expansion's terms."""
    out, term = [], 1.0
    for j in range(ASYMPTOTIC_TERMS):
        out.append(term)
        term *= (4 * n * n - (2 * j + 1) ** 2) / ((j + 1) * 8.0)
    return np.array(out)


_ASYMPTOTIC = {n: _asymptotic_coefficients(n) for n in (0, 1)}


def _bessel_asymptotic(n, x):
    """J_n(x) for large x: sqrt(2 / (pi x)) (P cos chi - Q sin chi), chi = x - (n / 2 + 1/4) pi
    (Abramowitz & Stegun, "Handbook of Mathematical Functions", 1964, 9.2.5)."""
    a = _ASYMPTOTIC[n]
    inv = 1.0 / x
    # P = sum_j (-1)^j a_2j / x^2j, Q = sum_j (-1)^j a_(2j+1) / x^(2j+1), by Horner in 1 / x^2
    sign = (-1.0) ** np.arange(len(a[0::2]))
    p = jnp.polyval(jnp.asarray((a[0::2] * sign)[::-1]), inv * inv)
    sign_q = (-1.0) ** np.arange(len(a[1::2]))
    q = inv * jnp.polyval(jnp.asarray((a[1::2] * sign_q)[::-1]), inv * inv)
    chi = x - (0.5 * n + 0.25) * jnp.pi
    return jnp.sqrt(2.0 / (jnp.pi * x)) * (p * jnp.cos(chi) - q * jnp.sin(chi))


def bessel_scaled(x: Float[ArrayLike, "..."]) -> tuple[Float[Array, "..."], Float[Array, "..."], Float[Array, "..."]]:
    """(J0(x), J1(x) / x, J2(x) / x^2) for x >= 0, smooth (and with finite derivatives) at
    x = 0, where they are (1, 1/2, 1/8)."""
    x = jnp.asarray(x, dtype=float)
    return bessel_scaled_squared(x * x)


def bessel_scaled_squared(
    x2: Float[ArrayLike, "..."],
) -> tuple[Float[Array, "..."], Float[Array, "..."], Float[Array, "..."]]:
    """:func:`bessel_scaled` of x = sqrt(``x2``): even functions of x written in x^2, so their
    derivatives in the coordinates stay finite on the load's axis (no sqrt at 0)."""
    x2 = jnp.asarray(x2, dtype=float)
    small = x2 < SERIES_LIMIT**2
    u = jnp.where(small, x2, 0.0) / 4.0
    series = [jnp.polyval(jnp.asarray(_SERIES[n]), u) for n in (0, 1, 2)]
    t = jnp.sqrt(jnp.where(small, SERIES_LIMIT**2, x2))
    j0, j1 = _bessel_asymptotic(0, t), _bessel_asymptotic(1, t)
    big = (j0, j1 / t, (2.0 * j1 / t - j0) / (t * t))
    return tuple(jnp.where(small, s, b) for s, b in zip(series, big))


class ElasticLayer(eqx.Module):
    """A linear elastic layer bonded to a rigid base (z = 0) with a free top surface (z = h).

    Attributes:
        thickness: h (m), > 0.
        shear_modulus: mu (Pa), > 0.
        poisson_ratio: nu (-), in (-1, 0.5]; 0.5 (incompressible) is exact.
    """

    thickness: Float[ArrayLike, ""]
    shear_modulus: Float[ArrayLike, ""]
    poisson_ratio: Float[ArrayLike, ""]

    def __check_init__(self):
        check_positive(thickness=self.thickness, unit="m")
        check_positive(shear_modulus=self.shear_modulus, unit="Pa")
        nu = _concrete(self.poisson_ratio)
        if nu is not None and not np.all((np.asarray(nu) > -1.0) & (np.asarray(nu) <= 0.5)):
            raise ValueError(f"poisson_ratio must lie in (-1, 0.5], got {nu}")

    @classmethod
    def from_material(cls, *, thickness: float, material) -> "ElasticLayer":
        """The layer of ``thickness`` h (m) of a material's small-strain moduli."""
        return cls(thickness=thickness, shear_modulus=material.shear_modulus, poisson_ratio=material.poisson_ratio)


class SurfaceLoad(eqx.Module):
    """A local traction on the layer's top surface: a disc of radius a about ``centre``.

    Attributes:
        centre: (x, y) of the load centre (m), shape (2,).
        radius: a (m), > 0: the contact (patch) radius.
        normal_force: Fn (N), pressing into the layer (>= 0 for contact).
        shear_force: (Ftx, Fty) (N), shape (2,): the tangential force on the surface.
        profile: "uniform", "hertz", "thin" or "flat" (module docstring); static.
    """

    centre: Float[ArrayLike, "2"]
    radius: Float[ArrayLike, ""]
    normal_force: Float[ArrayLike, ""]
    shear_force: Float[ArrayLike, "2"]
    profile: str = eqx.field(static=True, default="hertz")

    def __check_init__(self):
        if self.profile not in PROFILES:
            raise ValueError(f"profile must be one of {PROFILES}, got {self.profile!r}")
        check_positive(radius=self.radius, unit="m")


def load_transform(profile: str, ka: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Hankel transform 2 pi int_0^a f(r) J0(k r) r dr of a unit-force profile f (-), from
    int_0^1 (1 - t^2)^m J0(x t) t dt = 2^m m! J_(m+1)(x) / x^(m+1) (x = k a): 2 J1(x) / x for
    the uniform disc (m = 0), 3 (sin x - x cos x) / x^3 for Hertz's (m = 1/2), 48 J3(x) / x^3
    for the thin layer's (m = 2), sin x / x for the flat punch's (m = -1/2)."""
    ka = jnp.asarray(ka, dtype=float)
    if profile == "flat":
        return jnp.sinc(ka / jnp.pi)  # sin x / x, its value and slopes at x = 0 by jnp's series
    if profile == "uniform":
        return 2.0 * bessel_scaled(ka)[1]
    if profile == "thin":
        small = ka < SERIES_LIMIT
        series = jnp.polyval(jnp.asarray(_SERIES[3]), jnp.where(small, ka, 0.0) ** 2 / 4.0)
        t = jnp.where(small, SERIES_LIMIT, ka)
        _, j1_x, j2_x2 = bessel_scaled(t)
        return 48.0 * jnp.where(small, series, (4.0 * j2_x2 - j1_x) / (t * t))  # J3 = 4 J2 / x - J1
    small = ka < HERTZ_SERIES_LIMIT

    def direct(x):
        return 3.0 * (jnp.sin(x) - x * jnp.cos(x)) / x**3

    series = 1.0 - ka**2 / 10.0 + ka**4 / 280.0 - ka**6 / 15120.0
    return double_where(small, series, direct, ka)


def _kernels(k, z, layer):
    """Transfer functions of the layer at wavenumbers ``k`` (M,) and heights ``z`` (N, 1).

    Returns (U_L, W_L, U_z, W_z, V_T), each (N, M) (m/Pa after the 1 / (mu k) scale):
    the amplitude of the longitudinal (U) and vertical (W) displacement at z per unit
    longitudinal (L) or normal (z, upward) traction at z = h, and the transverse response
    V_T per unit transverse traction. For a Fourier mode e^(i k x) the longitudinal
    displacement is i U, the longitudinal traction i T_L.
    """
    h, mu = layer.thickness, layer.shear_modulus
    kappa = 3.0 - 4.0 * layer.poisson_ratio
    kh = k * h
    e = jnp.exp(-kh)
    # unknowns (c1, c2, c3, c4) of e^t, t e^t, e^-b, b e^-b with t = k (z - h), b = k z; the
    # conditions U(0) = 0, W(0) = 0, shear and normal traction / (mu k) at z = h:
    #   e c1 - k h e c2 + c3 = 0
    #   e c1 - (k h + kappa) e c2 - c3 - kappa c4 = 0
    #   2 c1 + (1 - kappa) c2 - 2 e c3 + (1 - 2 k h - kappa) e c4 = T_L
    #   2 c1 - (1 + kappa) c2 + 2 e c3 + (2 k h + kappa + 1) e c4 = T_z
    # The first two give c3 and c4 from (c1, c2); the last two are then a 2 x 2 system in
    # (c1, c2) whose determinant has |det| >= 4 for every k h >= 0 and kappa >= 1 (no pivoting:
    # the solve is elementwise over k)
    e2 = e * e
    lift = 2.0 * kh + kappa
    a11 = 2.0 + 2.0 * e2 + 2.0 * e2 * (1.0 - lift) / kappa
    a12 = 1.0 - kappa - 2.0 * kh * e2 - (1.0 - lift) * lift * e2 / kappa
    a21 = 2.0 - 2.0 * e2 + 2.0 * e2 * (lift + 1.0) / kappa
    a22 = -(1.0 + kappa) + 2.0 * kh * e2 - (lift + 1.0) * lift * e2 / kappa
    scale = mu * k * (a11 * a22 - a12 * a21)

    def coefficients(c1, c2):
        return c1, c2, -e * c1 + kh * e * c2, (2.0 * e * c1 - lift * e * c2) / kappa

    columns = (coefficients(a22 / scale, -a21 / scale), coefficients(-a12 / scale, a11 / scale))  # T_L, T_z
    t, b = k * (z - h), k * z  # (N, M)
    et, eb = jnp.exp(t), jnp.exp(-b)

    def field(col):
        c1, c2, c3, c4 = columns[col]
        U = c1 * et + c2 * t * et + c3 * eb + c4 * b * eb
        W = c1 * et + c2 * (t - kappa) * et - c3 * eb - c4 * (b + kappa) * eb
        return U, W

    U_L, W_L = field(0)
    U_z, W_z = field(1)
    # transverse: mu (V'' - k^2 V) = 0, V(0) = 0, mu V'(h) = 1: sinh(k z) / (mu k cosh(k h))
    V_T = (et - jnp.exp(-k * (z + h))) / (mu * k * (1.0 + e * e))
    return U_L, W_L, U_z, W_z, V_T


def layer_displacement(
    points: Float[ArrayLike, "... 3"],
    *,
    layer: ElasticLayer,
    load: SurfaceLoad,
    quadrature: Quadrature = DEFAULT_QUADRATURE,
) -> Float[Array, "... 3"]:
    """Displacement u (m), shape (..., 3), at ``points`` (..., 3) = (x, y, z) (m) of the
    ``layer`` under the surface ``load``; z is measured from the base (0 <= z <= h, the top
    surface at z = h). Pressure moves the surface down (u_z < 0)."""
    points = jnp.asarray(points, dtype=float)
    batch = points.shape[:-1]
    p = points.reshape(-1, 3)
    centre = jnp.asarray(load.centre, dtype=float)
    x, y, z = p[:, 0:1] - centre[0], p[:, 1:2] - centre[1], p[:, 2:3]  # (N, 1)
    a = load.radius
    k = quadrature.s / a  # (M,)
    dk = quadrature.weights / a
    U_L, W_L, U_z, W_z, V_T = _kernels(k, z, layer)
    L = load_transform(load.profile, k * a)  # per unit force
    j0, j1_x, j2_x2 = bessel_scaled_squared(k * k * (x * x + y * y))
    # (1 / 2 pi) int ... k dk with the load transform and the Hankel measure folded in
    measure = dk * k * L / (2.0 * jnp.pi)

    def integrate(f):
        return jnp.sum(f * measure, axis=-1)

    fn = load.normal_force
    fx, fy = jnp.asarray(load.shear_force, dtype=float)
    # normal pressure: traction T_z = -p, so u_r = (1/2pi) int U_z P J1 k dk, w = -(1/2pi) int W_z P J0 k dk
    radial = integrate(U_z * k * j1_x)  # u_r / r per unit normal force
    u_n = fn * jnp.stack([radial * x[:, 0], radial * y[:, 0], integrate(-W_z * j0)], axis=-1)
    # tangential traction along x: u_x with J0 and J2 cos 2 theta, u_y with J2 sin 2 theta, w with J1 cos theta
    even = integrate(0.5 * (U_L + V_T) * j0)
    odd = integrate(0.5 * (U_L - V_T) * k * k * j2_x2)  # times r^2 cos 2theta or r^2 sin 2theta
    lift = integrate(W_L * k * j1_x)  # times r cos theta

    def along_x(xx, yy):
        return jnp.stack([even - odd * (xx * xx - yy * yy), -odd * 2.0 * xx * yy, lift * xx], axis=-1)

    x0, y0 = x[:, 0], y[:, 0]
    ux = along_x(x0, y0)
    # a load along y is the load along x in the frame turned by +90 degrees: (x', y') = (y, -x)
    uy_local = along_x(y0, -x0)
    uy = jnp.stack([-uy_local[:, 1], uy_local[:, 0], uy_local[:, 2]], axis=-1)
    u = u_n + fx * ux + fy * uy
    return u.reshape(batch + (3,))


@dataclasses.dataclass(frozen=True)
class SpectralGrid:
    """The wavevector lattice of :func:`layer_displacement_grid` (static, hashable).

    Attributes:
        periods: (P_x, P_y), the period of the periodic sum in cells (>= the layer's cells).
        refine: per level of cells, bottom to top, (r_x, r_y): the lattice reaches the
            wavenumber r pi / (cell side) along each axis, r times the cell grid's own.
    """

    periods: tuple[int, int]
    refine: tuple[tuple[int, int], ...]


def _level_heights(cells, levels):
    """The levels' heights as fractions of the thickness, bottom to top: ``levels``, or the
    midpoints of ``cells[2]`` equal cells."""
    if levels is None:
        return (np.arange(cells[2]) + 0.5) / cells[2]
    levels = np.asarray(levels, dtype=float)
    if levels.shape != (cells[2],) or not np.all((levels > 0.0) & (levels < 1.0)):
        raise ValueError(f"levels must be {cells[2]} fractions of the thickness in (0, 1), got {levels}")
    return levels


def spectral_grid(*, size, thickness, cells: tuple[int, int, int], levels=None) -> SpectralGrid:
    """The lattice for a layer of sides ``size`` (L_x, L_y) (m) and ``thickness`` h (m) cut
    into ``cells`` (n_x, n_y, n_z), from their concrete values (module docstring): periods
    of at least L + SPECTRAL_PADDING h, and at each level, d below the top, a lattice
    reaching k d >= SPECTRAL_REACH. The levels are the cells' centres, or ``levels`` (static:
    n_z heights as fractions of h, bottom to top, as :func:`layer_displacement_grid` takes)."""
    sides, h = _concrete(size), _concrete(thickness)
    if sides is None or h is None:
        raise ValueError("spectral_grid needs the concrete size and thickness (not traced values)")
    sides, h = np.asarray(sides, dtype=float), float(h)
    side = sides / np.asarray(cells[:2])
    periods = tuple(int(n + math.ceil(SPECTRAL_PADDING * h / s)) for n, s in zip(cells[:2], side))
    depths = (1.0 - _level_heights(cells, levels)) * h  # bottom to top
    refine = tuple(tuple(max(1, math.ceil(SPECTRAL_REACH * s / (math.pi * d))) for s in side) for d in depths)
    return SpectralGrid(periods=periods, refine=refine)


def layer_displacement_grid(
    *,
    layer: ElasticLayer,
    load: SurfaceLoad,
    size: Float[ArrayLike, "2"],
    cells: tuple[int, int, int],
    grid: SpectralGrid,
    levels=None,
) -> tuple[Float[Array, "nx ny nz 3"], Float[Array, "nx ny nz 3"]]:
    """Displacement u (m) and rotation curl(u) / 2 (rad) at the centres of a layer's cells
    (those of :func:`magdesign.fields.cells.layer_cells` with bottom 0), or at the cells'
    in-plane centres on given heights, by a 2-D Fourier sum per level (module docstring).

    Args:
        layer: the layer (its thickness is the cells' height).
        load: the surface load.
        size: the layer's sides (L_x, L_y) (m), centred on x = y = 0.
        cells: (n_x, n_y, n_z) (static).
        grid: the wavevector lattice (static), e.g. :func:`spectral_grid`'s, one entry of
            ``refine`` per level.
        levels: the heights (static), n_z fractions of the thickness in (0, 1), bottom to
            top; None: the cells' midpoints (level + 1/2) / n_z.

    Returns:
        (u, rotation), each (n_x, n_y, n_z, 3): C order over the cells, as layer_cells lists them.
    """
    nx, ny, nz = cells
    (px, py), h = grid.periods, layer.thickness
    side = jnp.asarray(size, dtype=float) / jnp.array([nx, ny])
    centre = jnp.asarray(load.centre, dtype=float)
    # the first cell's centre is the origin of the inverse transform's grid
    start = -0.5 * jnp.array([nx - 1, ny - 1]) * side - centre
    fn = load.normal_force
    fx, fy = jnp.asarray(load.shear_force, dtype=float)
    heights = _level_heights(cells, levels)
    if len(grid.refine) != nz:
        raise ValueError(f"grid.refine must have one entry per level ({nz}), got {len(grid.refine)}")
    planes = []
    # the levels of one lattice (consecutive equal refine, every level of the linear field's
    # band-limited lattice) are one batch of heights: one program for them, whatever their count
    for (rx, ry), run in itertools.groupby(zip(heights, grid.refine), key=lambda level: level[1]):
        run_heights = np.array([height for height, _ in run])
        # the lattice |m_x| <= (r_x P_x - 1) / 2 (an even count's unpaired -M dropped) by
        # 0 <= m_y <= (r_y P_y - 1) / 2: the field is real, so the modes -m are the conjugates
        # of m, and the half m_y > 0 counts twice in the real part of the sum. Along y it is
        # padded with weightless modes to whole periods, for the fold below.
        mx, my = np.arange(rx * px) - rx * px // 2, np.arange(-(-ry // 2) * py)
        weights = (
            np.where(my == 0, 1.0, np.where(my <= (ry * py - 1) // 2, 2.0, 0.0))[None, :]
            * (np.abs(mx) <= (rx * px - 1) // 2)[:, None]
        )
        kx1, ky1 = 2.0 * jnp.pi * mx / (px * side[0]), 2.0 * jnp.pi * my / (py * side[1])
        kx, ky = kx1[:, None], ky1[None, :]
        # the k = 0 mode is the limit k h -> 0, taken at k h = ZERO_MODE_KH; its direction is x
        zero = (mx[:, None] == 0) & (my[None, :] == 0)
        k = jnp.sqrt(jnp.where(zero, (ZERO_MODE_KH / h) ** 2, kx * kx + ky * ky))
        ex, ey = jnp.where(zero, 1.0, kx / k), jnp.where(zero, 0.0, ky / k)
        z = jnp.asarray(run_heights)[:, None] * h  # (N, 1), N the run's levels
        kernels, slopes = jax.jvp(lambda zz: _kernels(k.ravel(), zz, layer), (z,), (jnp.ones_like(z),))
        U_L, W_L, U_z, W_z, V_T = (f.reshape((-1, *k.shape)) for f in kernels)
        dU_L, _, dU_z, _, dV_T = (f.reshape((-1, *k.shape)) for f in slopes)
        # the load's transform at the lattice, shifted to the load's centre, per unit area of a cell
        phase = jnp.exp(1j * kx1 * start[0])[:, None] * jnp.exp(1j * ky1 * start[1])[None, :]
        unit = load_transform(load.profile, k * load.radius) * phase / (side[0] * side[1])
        # longitudinal and transverse shear traction, normal traction T_z = -p (_kernels' modes)
        t_l, t_t, t_z = (ex * fx + ey * fy) * unit, (ex * fy - ey * fx) * unit, -fn * unit
        u_l, u_t = U_L * t_l + 1j * U_z * t_z, V_T * t_t
        du_l, du_t = dU_L * t_l + 1j * dU_z * t_z, dV_T * t_t
        ux, uy, uz = ex * u_l - ey * u_t, ey * u_l + ex * u_t, -1j * W_L * t_l + W_z * t_z
        dux, duy = ex * du_l - ey * du_t, ey * du_l + ex * du_t
        curl = (1j * ky * uz - duy, dux - 1j * kx * uz, 1j * (kx * uy - ky * ux))
        spectrum = jnp.stack([ux, uy, uz, *curl]) * weights  # (6, N, r_x P_x, r_y P_y / 2 padded)
        # sampled at the cells only, the lattice folds onto the cell grid's own (period P)
        folded = spectrum.reshape(6, -1, rx, px, -(-ry // 2), py).sum(axis=(2, 4))
        folded = jnp.roll(folded, mx[0], axis=2)
        planes.append(jnp.fft.ifft2(folded).real[..., :nx, :ny])
    fields = jnp.moveaxis(jnp.concatenate(planes, axis=1), 1, -1)  # (6, n_x, n_y, n_z)
    return jnp.moveaxis(fields[:3], 0, -1), 0.5 * jnp.moveaxis(fields[3:], 0, -1)


class HertzContact(eqx.Module):
    """Contact of a rigid sphere on the layer (:func:`hertz_contact`, :func:`thin_layer_contact`).

    Attributes:
        radius: contact radius a (m).
        peak_pressure: p0 (Pa), the pressure at the centre.
        depth: indentation depth delta (m), the sphere's travel from first touch.
    """

    radius: Float[Array, "..."]
    peak_pressure: Float[Array, "..."]
    depth: Float[Array, "..."]


def hertz_contact(
    *, normal_force: Float[ArrayLike, "..."], sphere_radius: Float[ArrayLike, "..."], layer: ElasticLayer
) -> HertzContact:
    """Hertz's half-space contact of a rigid sphere of radius R (m) pressed with
    ``normal_force`` Fn (N, > 0) on the ``layer``'s material: a = (3 Fn R / (4 E*))^(1/3),
    E* = 2 mu / (1 - nu). Valid for a / h small (module docstring); it ignores the base."""
    check_positive(normal_force=normal_force, unit="N")
    check_positive(sphere_radius=sphere_radius, unit="m")
    e_star = 2.0 * layer.shear_modulus / (1.0 - layer.poisson_ratio)
    a = (3.0 * normal_force * sphere_radius / (4.0 * e_star)) ** (1.0 / 3.0)
    return HertzContact(
        radius=a, peak_pressure=3.0 * normal_force / (2.0 * jnp.pi * a * a), depth=a * a / jnp.asarray(sphere_radius)
    )


def thin_layer_contact(
    *, normal_force: Float[ArrayLike, "..."], sphere_radius: Float[ArrayLike, "..."], layer: ElasticLayer
) -> HertzContact:
    """Contact of a rigid sphere of radius R (m) pressed with ``normal_force`` Fn (N, > 0) on a
    thin incompressible ``layer``: a = (32 Fn h^3 R / (pi mu))^(1/6), pressure
    p0 (1 - r^2 / a^2)^2 with p0 = 3 Fn / (pi a^2) (the ``"thin"`` profile), depth a^2 / (4 R)
    (module docstring). Valid for a / h large and nu close to 0.5 (1 - 2 nu << (h / a)^2);
    the layer's Poisson ratio is not used."""
    check_positive(normal_force=normal_force, unit="N")
    check_positive(sphere_radius=sphere_radius, unit="m")
    R = jnp.asarray(sphere_radius)
    a = (32.0 * normal_force * layer.thickness**3 * R / (jnp.pi * layer.shear_modulus)) ** (1.0 / 6.0)
    return HertzContact(radius=a, peak_pressure=3.0 * normal_force / (jnp.pi * a * a), depth=a * a / (4.0 * R))
