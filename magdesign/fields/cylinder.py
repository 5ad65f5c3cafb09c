"""Uniformly magnetised solid cylinder, any direction of polarization: exact field
everywhere.

Layers (as in magpylib): a dimensionless core in the magnet frame with lengths in units
of the radius, the public wrapper applying scale, polarization and fidelity on top.

For a uniformly magnetised body B = Hess(psi) J + chi J, with J the polarization,
chi = 1 inside and 0 outside, and psi(r) = (1/4pi) int_V dV' / |r - r'| the potential of
the body filled with unit charge. For a cylinder psi depends on rho^2 = s and z only,
so every field component follows from four functions of (s, z) (radius 1, polarization 1):

    p = B_rho / rho and z = B_z of the axial field (J along the axis)
    u = (dpsi / drho) / rho, and v = 2 du/ds = -(2 u + z) / s (Laplace's equation)

    B = J_z (p x, p y, z) + J_x (u + v x^2 + chi, v x y, p x) + J_y (v x y, u + v y^2 + chi, p y)

Each is a difference of face terms, f(z + b) - f(z - b) (b = half height / radius):
p and z after Derby and Olbert, Am. J. Phys. 78, 229 (2010),

    p_face = 4 alpha^3 cel(kc, 1, 1, -1) / (pi (1 - kc) (1 + kc))
    z_face = zeta alpha cel(kc, gamma^2, 1, gamma) / (pi (1 + rho))

with alpha = 1 / sqrt(zeta^2 + (1 + rho)^2), kc^2 = (zeta^2 + (1 - rho)^2) alpha^2,
gamma = (1 - rho) / (1 + rho), and u from the side wall's charges (derived here; checked
against an independent 40-digit integration of the wall's charges in the tests),

    u_face = zeta alpha [cel(kc, 1, 1, 0) - cel(kc, gamma^2, 1, 0)] / (pi rho).

Their derivatives along the axis are the field of one current loop (the wall is a stack
of loops), in closed form from the same integrals:

    p_loop = 4 zeta alpha^5 [cel(kc, 1, 1, -1) / (1 - kc^2) + cel(kc, 1, 1, 0) / kc^2] / pi
    z_loop = alpha^3 cel(kc, 1, (1 - rho) / kc^2, 1 + rho) / pi

and d u_face / d zeta = p_face. Three regimes, each where it keeps full precision:

- near: the face differences;
- far (beyond MULTIPOLE_SWITCH enclosing radii): the axial multipole series, where the
  faces cancel;
- thin magnets (WALL_SWITCH b below the switch radius): points farther than WALL_SWITCH
  half heights from the side wall, where the two faces cancel to the magnet's thinness,
  integrate the loops over the wall's height with WALL_NODES Gauss nodes instead.

The derivatives of the field with respect to the points and the height come from the
same closed forms (a custom JVP), not from differentiating the elliptic-integral loop.
"""

import functools
import math
import warnings

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import double_where, float_array, safe_sqrt
from magdesign._validation import check_broadcasts, check_last_axis, check_positive, check_scalar
from magdesign.fields._partition import FAR, MIXED, NEAR, _is_large, _materialized, _partitioned
from magdesign.fields._special import (
    AXIS_SERIES_S,
    FACE_SWITCH,
    KC_MIN,
    KC_MIN_FLOAT32,
    LONG_HALF_HEIGHT,
    MULTIPOLE_SWITCH,
    MULTIPOLE_TERMS,
    ROD_TERMS,
    WALL_NODES,
    WALL_SWITCH,
    cel_face,
    multipole,
    reciprocal,
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
# The far series' coefficients w_l = -c_l / (l + 1) (see _far_jet) as a matrix acting on
# the odd powers of b: w = _MULTIPOLE_MATRIX @ (b, b^3, ...). One product instead of a sum
# per term: b is traced (an argument of the custom JVP), and a sum of ~300 scalar
# operations costs about 0.1 s to trace per call.
_MULTIPOLE_ORDERS = range(1, 2 * MULTIPOLE_TERMS, 2)  # Python ints: the binomials' products pass int64
_MULTIPOLE_MATRIX = np.array(
    [
        [
            -_binomial(-0.5, (l + 2 - m) // 2) * _binomial(-(l + 2 - m), m) / (l + 1) if m <= l else 0.0
            for m in _MULTIPOLE_ORDERS
        ]
        for l in _MULTIPOLE_ORDERS
    ]
)


def _on_axis_polynomials(order):
    """Numerators of the derivatives of g(t) = t / sqrt(1 + t^2), the on-axis face term:
    g^(n)(t) = N_n(t) (1 + t^2)^(-(2n + 1) / 2), N_0 = t,
    N_{n+1} = N_n' (1 + t^2) - (2n + 1) t N_n."""
    polynomials = [np.polynomial.Polynomial([0.0, 1.0])]
    t, one_t2 = np.polynomial.Polynomial([0.0, 1.0]), np.polynomial.Polynomial([1.0, 0.0, 1.0])
    for n in range(order):
        polynomials.append(polynomials[n].deriv() * one_t2 - (2 * n + 1) * t * polynomials[n])
    return tuple(
        tuple(float(c) for c in p.coef) for p in polynomials
    )  # Python floats: weakly typed, float32 stays float32


# Near the axis (s < AXIS_SERIES_S) the functions are taken from their series in s, whose
# coefficients are derivatives of the on-axis field f(z) (the closed form of cylinder_axial):
# u = sum_m a_m s^m f^(2m)(z), a_m = 2 (m+1) (-1)^(m+1) / (4^(m+1) ((m+1)!)^2).
AXIS_SERIES_TERMS = 4
_AXIS_A = tuple(
    2 * (m + 1) * (-1) ** (m + 1) / (4 ** (m + 1) * math.factorial(m + 1) ** 2) for m in range(AXIS_SERIES_TERMS)
)
_G_POLYNOMIALS = _on_axis_polynomials(2 * AXIS_SERIES_TERMS + 1)


# The jet: per point, radius 1 and polarization 1, the functions of the module docstring
# that are computed (not derived): p, z, u, their derivatives along the axis p_z, z_z, and
# with respect to the half height b, p_b, z_b, u_b. Every kernel below computes only the
# entries it is asked for (``wanted``, static), so that XLA gets, and tracing builds, no
# more than the call needs.
# Of one face: p, z, u are its terms, p_z, z_z the ring current's field (their d/dzeta).
_FACE_NEEDS = {
    "p": ("p",),
    "z": ("z",),
    "u": ("u",),
    "p_z": ("p_z",),
    "z_z": ("z_z",),
    "p_b": ("p_z",),
    "z_b": ("z_z",),
    "u_b": ("p",),
}


def _face_wanted(wanted):
    return tuple(sorted({need for name in wanted for need in _FACE_NEEDS[name]}))


# Traced once per shape and request and reused: the kernel calls it many times (faces,
# passes, regimes), and tracing it each time dominated the first call.
@functools.partial(jax.jit, static_argnames="wanted")
def _face(rho, inv_rho, inv_one_rho, gamma, zeta, wanted):
    """The ``wanted`` face terms (p, z, u) and ring-current fields (p_z, z_z) of one face
    at height ``zeta`` below the point, as a dict."""
    alpha = rsqrt(zeta * zeta + (1.0 + rho) ** 2)
    alpha2 = alpha * alpha
    # On an edge (rho = 1, zeta = 0) k_c = 0: see KC_MIN for the value returned.
    kc_min = KC_MIN_FLOAT32 if zeta.dtype == jnp.float32 else KC_MIN
    kc2 = jnp.maximum((zeta * zeta + (1.0 - rho) ** 2) * alpha2, kc_min * kc_min)
    kc = kc2 * rsqrt(kc2)
    p_chain = "z" in wanted or "u" in wanted
    integrals = cel_face(kc, gamma, p_chain, first=bool({"u", "p_z", "z_z"} & set(wanted)))
    radial = integrals.radial  # cel(kc, 1, 1, -1) / (1 - kc^2)
    out = {}
    if "p" in wanted:
        out["p"] = 4.0 / jnp.pi * alpha * alpha2 * radial
    if "z" in wanted:
        out["z"] = zeta * alpha * integrals.axial * inv_one_rho / jnp.pi
    if {"u", "p_z", "z_z"} & set(wanted):
        minus = 4.0 * rho * alpha2 * radial  # cel(kc, 1, 1, -1): 1 - kc^2 = 4 rho alpha^2
        cosine = 0.5 * (integrals.first + minus)  # cel(kc, 1, 1, 0)
        inv_kc2 = reciprocal(kc2)
    if "u" in wanted:
        out["u"] = zeta * alpha * (cosine - integrals.cosine) * inv_rho / jnp.pi
    if "p_z" in wanted:
        out["p_z"] = 4.0 / jnp.pi * zeta * alpha * alpha2 * alpha2 * (radial + cosine * inv_kc2)
    if "z_z" in wanted:
        a, b = (1.0 - rho) * inv_kc2, 1.0 + rho
        out["z_z"] = alpha * alpha2 / jnp.pi * (0.5 * (a + b) * integrals.first + 0.5 * (a - b) * minus)
    return out


@functools.partial(jax.jit, static_argnames="orders")
def _axis_derivatives(z, b, orders):
    """f^(n)(z) for n in ``orders``: derivatives of the on-axis field
    f = (g(z + b) - g(z - b)) / 2, and their b-derivatives (g^(n+1)(z + b) + g^(n+1)(z - b)) / 2."""
    faces = []
    for zeta in (z + b, z - b):
        r = rsqrt(1.0 + zeta * zeta)
        r2 = r * r
        powers = [r]  # powers[n] = (1 + zeta^2)^(-(2n + 1) / 2)
        for _ in range(max(orders) + 1):
            powers.append(powers[-1] * r2)
        faces.append(
            [sum(c * zeta**i for i, c in enumerate(_G_POLYNOMIALS[n])) * powers[n] for n in range(max(orders) + 2)]
        )
    values = {n: 0.5 * (faces[0][n] - faces[1][n]) for n in orders}
    along_b = {n: 0.5 * (faces[0][n + 1] + faces[1][n + 1]) for n in orders}
    return values, along_b


def _geometry(s):
    """rho and the guarded reciprocals the faces share."""
    rho = safe_sqrt(s)
    near_axis = s < AXIS_SERIES_S
    inv_rho = jnp.where(near_axis, 0.0, rsqrt(jnp.where(near_axis, 1.0, s)))
    inv_one_rho = reciprocal(1.0 + rho)
    gamma = (1.0 - rho) * inv_one_rho
    return rho, inv_rho, inv_one_rho, gamma


def _combine(top, bottom, wanted):
    """The jet from the two faces' terms: differences, and sums for the b-derivatives."""
    sources = {"p": "p", "z": "z", "u": "u", "p_z": "p_z", "z_z": "z_z", "p_b": "p_z", "z_b": "z_z", "u_b": "p"}
    return {
        name: top[sources[name]] + bottom[sources[name]] if name.endswith("_b") else top[name] - bottom[name]
        for name in wanted
    }


def _faces_jet(s, z, b, wanted):
    """The face differences (and, for _b, sums), the near regime."""
    geometry = _geometry(s)
    faces = [_face(*geometry, zeta, wanted=_face_wanted(wanted)) for zeta in (z + b, z - b)]
    jet = _combine(*faces, wanted)
    if "u" in wanted:
        jet["u"] = _axis_u(s, z, b, jet["u"])
    return jet


def _axis_u(s, z, b, u):
    """``u``, or on and near the axis (where u_face divides by rho) its series in s."""
    f, _ = _axis_derivatives(z, b, tuple(range(0, 2 * AXIS_SERIES_TERMS, 2)))
    series = sum(_AXIS_A[m] * s**m * f[2 * m] for m in range(AXIS_SERIES_TERMS))
    return jnp.where(s < AXIS_SERIES_S, series, u)


# Python floats (weakly typed): numpy float64 scalars would turn float32 values into float64
_WALL_X, _WALL_W = (tuple(float(v) for v in a) for a in np.polynomial.legendre.leggauss(WALL_NODES))
# For the wall integral: each wanted entry is the integral of this face quantity, or of
# its zeta-derivative (second element True).
_WALL_SOURCES = {
    "p": ("p_z", False),
    "z": ("z_z", False),
    "u": ("p", False),
    "p_z": ("p_z", True),
    "z_z": ("z_z", True),
}


def _wall_jet(s, z, b, wanted):
    """The rings of the side wall integrated over its height (thin magnets, far from the
    wall): p = int_{-b}^{b} p_ring(z + t) dt, and so on; u integrates p_face; the
    b-derivatives are sums of the faces' (no cancellation)."""
    geometry = _geometry(s)
    integrals = [name for name in wanted if name in _WALL_SOURCES]
    face_wanted = tuple(sorted({_WALL_SOURCES[name][0] for name in integrals}))
    jet = {name: 0.0 for name in integrals}
    for x, w in zip(_WALL_X, _WALL_W):
        zeta = z + b * x
        if any(_WALL_SOURCES[name][1] for name in integrals):
            values, slopes = jax.jvp(lambda t: _face(*geometry, t, wanted=face_wanted), (zeta,), (jnp.ones_like(zeta),))
        else:
            values, slopes = _face(*geometry, zeta, wanted=face_wanted), None
        for name in integrals:
            source, derivative = _WALL_SOURCES[name]
            jet[name] = jet[name] + b * w * (slopes if derivative else values)[source]
    heights = [name for name in wanted if name.endswith("_b")]
    if heights:
        jet.update(_faces_jet(s, z, b, heights))
    return jet


def _multipole_coefficients(b, dtype, along_b):
    """{l: w_l} of the far series of half height ``b`` in ``dtype`` (the points'), or with
    ``along_b`` their b-derivatives."""
    m = np.array(_MULTIPOLE_ORDERS)
    b = jnp.asarray(b, dtype)
    powers = m * b ** (m - 1) if along_b else b**m
    w = jnp.dot(
        jnp.asarray(_MULTIPOLE_MATRIX, dtype), powers, precision=jax.lax.Precision.HIGHEST
    )  # no TF32 / bf16 passes
    return {l: w[k] for k, l in enumerate(_MULTIPOLE_ORDERS)}


def _far_jet(s, z, b, wanted):
    """The axial multipole series (and, for _b, the series of the coefficients' b-derivatives):
    with B_z = sum c_l / z^(l+2) on the axis, dpsi/dz = -sum c_l P_l(mu) / ((l+1) r^(l+1))."""
    switch_r2 = MULTIPOLE_SWITCH**2 * (1.0 + b * b)
    jet = {}
    plain = tuple(name for name in wanted if not name.endswith("_b"))
    if plain:
        coefficients = _multipole_coefficients(b, s.dtype, along_b=False)
        jet.update(multipole(coefficients, s, z, switch_r2, plain))
    heights = tuple(name[0] for name in wanted if name.endswith("_b"))
    if heights:
        along_b = _multipole_coefficients(b, s.dtype, along_b=True)
        jet.update({name + "_b": value for name, value in multipole(along_b, s, z, switch_r2, heights).items()})
    return jet


# The semi-infinite rod of radius 1 filled with unit density below the plane z = 0 (the
# part of a long magnet beyond one face): averaging the potential of the line on its axis
# over the rod's cross-section (the mean-value series of a disc, terms (1/4)^k / (k! (k+1)!)
# times the k-th power of the transverse Laplacian, which is -d^2/dz^2 off the line) gives
# dpsi/dz = -(1/4) sum_k (-1/4)^k (2k)! / (k! (k+1)!) P_2k(mu) / r^(2k+1), exact for r > 1.
_ROD_COEFFICIENTS = {
    2 * k: -0.25 * (-0.25) ** k * math.factorial(2 * k) / (math.factorial(k) * math.factorial(k + 1))
    for k in range(ROD_TERMS)
}


def _infinite_rod(s):
    """z, u of the infinite rod (radius 1, unit polarization; its p is 0): the limits of a
    face term at zeta -> +-infinity are +- half of these (z = chi = 1 inside; u = -1/2
    inside, -1 / (2 s) outside)."""
    return {"z": 0.5 * (1.0 + jnp.sign(1.0 - s)), "u": -0.5 * reciprocal(jnp.maximum(s, 1.0))}


# A face term's parity in zeta: odd for z, u and p_z, even for p and z_z.
_ODD = ("z", "u", "p_z")


def _decaying_face(geometry, s, zeta, wanted):
    """One face term minus its step, F(zeta) - sign(zeta) F_inf / 2, which decays away from
    the face; far from it (FACE_SWITCH radii) from the rod-end series, where F itself is
    near +-F_inf / 2 and would lose the digits of the difference. Above a face
    F = F_inf / 2 - rod(zeta); below it follows from F's parity."""
    near = _face(*geometry, zeta, wanted=wanted)
    end = multipole(_ROD_COEFFICIENTS, s, jnp.abs(zeta), FACE_SWITCH**2, wanted)
    infinite = _infinite_rod(s)
    sign = jnp.sign(zeta)
    far = s + zeta * zeta > FACE_SWITCH**2
    out = {}
    for name in wanted:
        far_value = -(sign * end[name] if name in _ODD else end[name])
        near_value = near[name] - 0.5 * sign * infinite[name] if name in infinite else near[name]
        out[name] = jnp.where(far, far_value, near_value)
    return out, far


def _long_jet(s, z, b, wanted):
    """Long magnets: the decaying parts of the face terms, and the infinite rod between the
    faces (0, 1/2 or 1 of it: outside, on a face, between)."""
    geometry = _geometry(s)
    face_wanted = _face_wanted(wanted)
    (top, top_far), (bottom, bottom_far) = (_decaying_face(geometry, s, zeta, face_wanted) for zeta in (z + b, z - b))
    jet = _combine(top, bottom, wanted)
    between = 0.5 * (jnp.sign(z + b) - jnp.sign(z - b))
    for name, value in _infinite_rod(s).items():
        if name in jet:
            jet[name] = jet[name] + between * value
    if "u" in jet:
        # u_face divides by rho: near the axis, with a face near, u comes from its series.
        jet["u"] = jnp.where(top_far & bottom_far, jet["u"], _axis_u(s, z, b, jet["u"]))
    return jet


THIN, REGULAR, LONG = 0, 1, 2


def _branch(b):
    """Which regime a magnet of half height ``b`` (radii) takes: THIN when some points
    inside the switch sphere are farther than WALL_SWITCH half heights from its wall,
    LONG beyond LONG_HALF_HEIGHT, else REGULAR. A Python int for a concrete ``b`` (one
    branch traced and compiled), an int array for a traced one."""
    thin = (WALL_SWITCH * b) ** 2 < MULTIPOLE_SWITCH**2 * (1.0 + b * b)
    try:
        return THIN if bool(thin) else (LONG if float(b) > LONG_HALF_HEIGHT else REGULAR)
    except (jax.errors.ConcretizationTypeError, jax.errors.TracerBoolConversionError):
        return jnp.where(thin, THIN, jnp.where(b > LONG_HALF_HEIGHT, LONG, REGULAR))


def _near_jet(s, z, b, wanted, regime):
    if regime == REGULAR:
        return _faces_jet(s, z, b, wanted)
    if regime == LONG:
        return _long_jet(s, z, b, wanted)
    wall_distance2 = (safe_sqrt(s) - 1.0) ** 2 + jnp.maximum(jnp.abs(z) - b, 0.0) ** 2
    # The wall's integral is computed into memory (its own loop), not fused with the faces':
    # fused into one loop with b traced (a design's magnet, whose height is an argument of
    # the compiled program), jit(jacfwd) of the field costs XLA CPU's LLVM optimiser minutes
    # and gigabytes, and vmap(jacfwd) of a thin magnet runs ~30 times slower; apart, seconds,
    # a fraction of a gigabyte, and 0.05 s per 1e5 points.
    wall, faces = _materialized(_wall_jet(s, z, b, wanted), s), _faces_jet(s, z, b, wanted)
    return {name: jnp.where(wall_distance2 > (WALL_SWITCH * b) ** 2, wall[name], faces[name]) for name in wanted}


def _jet(s, z, b, names, branch):
    """The named jet entries at (s, z) for half height b, each computed once into memory.

    ``branch`` (see _branch): a Python int picks one regime at trace time; an array picks
    at run time (lax.switch; under vmap every regime runs and the result is selected).
    A call of at least 2 PARTITION_CHUNK points takes :func:`_partitioned`: the far
    series at every point, the elliptic integrals only at its near points (unless most
    of its points are near)."""
    far = s + z * z > MULTIPOLE_SWITCH**2 * (1.0 + b * b)

    def regime_jet(regime):
        if _is_large(s):
            return _partitioned(s, z, far, functools.partial(_zoned_jet, b=b, names=names, regime=regime))
        return _zoned_jet(s, z, far, MIXED, b, names, regime)

    if isinstance(branch, int):
        return regime_jet(branch)
    return jax.lax.switch(branch, [functools.partial(regime_jet, regime) for regime in (THIN, REGULAR, LONG)])


def _zoned_jet(s, z, far, zone, b, names, regime):
    """The jet of points all NEAR (inside the switch sphere), all FAR, or MIXED (both
    computed, each point's own selected). NEAR and MIXED: each pair of names is one loop
    over the points (see _materialized), computing only its own two entries (the
    integrals with p = gamma^2 only for z and u); FAR: each name its own real loop (the
    series share little work, and XLA vectorises real loops, not complex ones)."""
    if zone == FAR:
        return _materialized(_far_jet(s, z, b, tuple(names)), s, paired=False)
    out = {}
    for i in range(0, len(names), 2):
        pair = tuple(names[i : i + 2])
        if zone == NEAR:
            values = _near_jet(s, z, b, pair, regime)
        else:
            near, far_values = _near_jet(s, z, b, pair, regime), _far_jet(s, z, b, pair)
            values = {name: jnp.where(far, far_values[name], near[name]) for name in pair}
        out.update(_materialized(values, s))
    return out


def _safe_over_s(s, numerator, series):
    """numerator / s, or ``series`` where s < AXIS_SERIES_S (double where: no NaN gradient)."""
    near_axis = s < AXIS_SERIES_S
    return jnp.where(near_axis, series, numerator / jnp.where(near_axis, 1.0, s))


def _series(s, derivatives, m_weights):
    if derivatives is None:
        return 0.0
    return sum(weight * s**power * derivatives[order] for power, order, weight in m_weights)


def _derived(s, z, b, jet):
    """v = 2 du/ds, and the s-derivatives of p and v, from Laplace's equation (divided by
    s) away from the axis and from their series in s near it. In a large call (_is_large)
    the series are computed only when some point is near the axis: they cost a quarter
    of a diametral field (under vmap both branches run and one is selected)."""
    if not _is_large(s):
        return _derived_values(s, z, b, jet, True)
    near_axis = jnp.any(s < AXIS_SERIES_S)
    return jax.lax.cond(
        near_axis, lambda: _derived_values(s, z, b, jet, True), lambda: _derived_values(s, z, b, jet, False)
    )


def _derived_values(s, z, b, jet, series):
    """_derived's values; the near-axis series only if ``series`` (static), else no point
    may be near the axis."""
    f, f_b = _axis_derivatives(z, b, tuple(range(2, 2 * AXIS_SERIES_TERMS + 1))) if series else (None, None)
    terms = range(1, AXIS_SERIES_TERMS)
    out = {}
    if "u" in jet:
        v_series = _series(s, f, [(m - 1, 2 * m, 2 * m * _AXIS_A[m]) for m in terms])
        out["v"] = _safe_over_s(s, -(2.0 * jet["u"] + jet["z"]), v_series)
        if "p_z" in jet:
            v_s_series = _series(
                s, f, [(m - 2, 2 * m, 2 * m * (m - 1) * _AXIS_A[m]) for m in range(2, AXIS_SERIES_TERMS)]
            )
            out["v_s"] = _safe_over_s(s, -(2.0 * out["v"] + 0.5 * jet["p_z"]), v_s_series)
        if "u_b" in jet:
            v_b_series = _series(s, f_b, [(m - 1, 2 * m, 2 * m * _AXIS_A[m]) for m in terms])
            out["v_b"] = _safe_over_s(s, -(2.0 * jet["u_b"] + jet["z_b"]), v_b_series)
    if "p_z" in jet:
        p_s_series = _series(s, f, [(m - 1, 2 * m + 1, m * _AXIS_A[m]) for m in terms])
        out["p_s"] = _safe_over_s(s, -(jet["z_z"] + 2.0 * jet["p"]) / 2.0, p_s_series)
    return _materialized(out, s) if out else out


def _inside(s, z, b):
    """1 inside the magnet, 0 outside; 1/2 on a face or the side wall, 1/4 on an edge."""
    return 0.25 * (1.0 + jnp.sign(1.0 - s)) * (1.0 + jnp.sign(b - jnp.abs(z)))


def _components(polarization, axial):
    """(J_x, J_y, J_z), with None for the transverse parts of an axial polarization."""
    if axial:
        return None, None, polarization
    return polarization[..., 0], polarization[..., 1], polarization[..., 2]


# Unit vectors along x, y, z: the field is assembled on (..., 3) arrays, every per-point
# value broadcast along the last axis, so that XLA reads each materialized value from memory
# (a broadcast reuses its operand, so XLA does not fuse an expensive producer into it)
# instead of re-running the kernel that made it once per component.
_E = np.eye(3)


def _field(q, polarization, f, axial):
    """B = (Hess(psi) + chi I) J, written out: the axial column (p x, p y, z) and, for a
    transverse J, the columns (u + v x^2 + chi, v x y, p x) and (v x y, u + v y^2 + chi, p y).
    ``f`` holds p, z (and u, v, inside)."""
    x, y = q[..., :1], q[..., 1:2]
    jx, jy, jz = _components(polarization, axial)
    p, z = f["p"][..., None], f["z"][..., None]
    e = _E.astype(q.dtype)  # float32 points stay float32
    field = jz[..., None] * jnp.where(e[2], z, p * q)
    if not axial:
        diagonal, v = (f["u"] + f["inside"])[..., None], f["v"][..., None]
        column_x = jnp.where(e[2], p * x, v * x * q + diagonal * e[0])
        column_y = jnp.where(e[2], p * y, v * y * q + diagonal * e[1])
        field = field + jx[..., None] * column_x + jy[..., None] * column_y
    return field


def _points_tangent(q, polarization, f, dq, axial):
    """The derivative of B along ``dq``, from the derivatives of p, z, u, v along s = rho^2
    and z: u_s = v / 2, u_z = p, v_z = 2 p_s, z_s = p_z / 2 (Laplace's equation and
    curl B = 0), with p_s, p_z, z_z (and v_s) computed. With q_perp = (x, y, 0):

        B = J_z (p q_perp + z e_z) + (u + chi) J_perp + v (J_perp . q_perp) q_perp
            + p (J_perp . q_perp) e_z
    """
    e = _E.astype(q.dtype)  # float32 points stay float32
    q_perp, dq_perp = q * e[:2].sum(0), dq * e[:2].sum(0)
    dz = dq[..., 2:]
    ds_half = q[..., :1] * dq[..., :1] + q[..., 1:2] * dq[..., 1:2]  # (ds / 2)
    jx, jy, jz = _components(polarization, axial)
    p, p_s, p_z, z_z = (f[name][..., None] for name in ("p", "p_s", "p_z", "z_z"))
    dp = 2.0 * p_s * ds_half + p_z * dz
    tangent = jz[..., None] * (dp * q_perp + p * dq_perp + (p_z * ds_half + z_z * dz) * e[2])
    if not axial:
        v, v_s = f["v"][..., None], f["v_s"][..., None]
        j_perp = jx[..., None] * e[0] + jy[..., None] * e[1]
        along = jx[..., None] * q[..., :1] + jy[..., None] * q[..., 1:2]
        d_along = jx[..., None] * dq[..., :1] + jy[..., None] * dq[..., 1:2]
        du = v * ds_half + p * dz
        dv = 2.0 * v_s * ds_half + 2.0 * p_s * dz
        tangent = tangent + du * j_perp + (dv * along + v * d_along) * q_perp + v * along * dq_perp
        tangent = tangent + (dp * along + p * d_along) * e[2]
    return tangent


def _names(axial, points, height):
    """The jet entries a call needs, in the order they are paired for computation."""
    names = ["p", "z"]
    if points:
        names += ["p_z", "z_z"]
    if height:
        names += ["p_b", "z_b"]
    if not axial:
        names += ["u"] + (["u_b"] if height else [])
    return names


def _evaluate(q, b, axial, branch, points=False, height=False):
    """p, z, ... (the named functions, the derived ones and, for a transverse J, inside)."""
    branch = _branch(b) if branch is None else branch
    s, z = q[..., 0] ** 2 + q[..., 1] ** 2, q[..., 2]
    f = _jet(s, z, b, _names(axial, points, height), branch)
    f.update(_derived(s, z, b, f))
    if not axial:
        f["inside"] = _inside(s, z, b)
    return f


def _evaluate_as_one_call(q, b, axial, branch, points=False, height=False):
    """:func:`_evaluate`, and under vmap over the points one call of the whole batch, so
    that it is partitioned like one (see _jet): for the JVP rule, which vmap(jacfwd(field))
    runs one point per lane. (The field itself does without: the custom vmap's tracing
    and lowering add 0.1-0.15 s to the first call of 1000 points, which has a 1 s goal.)"""
    evaluate = functools.partial(_evaluate, axial=axial, branch=branch, points=points, height=height)
    return _as_one_call(evaluate)(q, b)


def _as_one_call(evaluate):
    """``evaluate(q, b)`` (elementwise in the points q, (..., 3)) whose vmap over q alone
    is ``evaluate`` of the whole batch (jax.custom_batching.custom_vmap; a vmap over b
    maps as usual). custom_vmap has no reverse mode: derivatives of the result (second
    derivatives of the field) are those of ``evaluate`` itself, through a custom JVP."""
    mapped = jax.custom_batching.custom_vmap(evaluate)

    @mapped.def_vmap
    def rule(axis_size, in_batched, q, b):
        q_batched, b_batched = in_batched
        if b_batched:
            out = jax.vmap(evaluate, in_axes=(0 if q_batched else None, 0))(q, b)
        else:
            out = evaluate(q, b)
        return out, {name: True for name in out}

    differentiable = jax.custom_jvp(mapped)
    differentiable.defjvp(lambda primals, tangents: jax.jvp(evaluate, primals, tangents))
    return differentiable


@functools.partial(jax.custom_jvp, nondiff_argnums=(3, 4))
def _unit_field(q, b, polarization, axial, branch):
    """B (units of the polarization) at ``q`` (radii) of the cylinder of radius 1 and half
    height ``b``; ``polarization`` a scalar along the axis when ``axial``, else (..., 3);
    ``branch`` the regime (_branch) when known at trace time, else None."""
    return _field(q, polarization, _evaluate(q, b, axial, branch), axial)


def _is_zero(tangent):
    return isinstance(tangent, jax.custom_derivatives.SymbolicZero)


def _unit_field_jvp(axial, branch, primals, tangents):
    q, b, polarization = primals
    dq, db, dpolarization = tangents
    points, height = not _is_zero(dq), not _is_zero(db)
    f = _evaluate_as_one_call(q, b, axial, branch, points, height)
    field = _field(q, polarization, f, axial)
    tangent = jnp.zeros_like(field)
    if not _is_zero(dpolarization):
        tangent = tangent + _field(q, dpolarization, f, axial)
    if points:
        tangent = tangent + _points_tangent(q, polarization, f, dq, axial)
    if height:
        # the same response with every function replaced by its b-derivative (chi's is 0)
        along_b = {"p": f["p_b"], "z": f["z_b"]}
        if not axial:
            along_b.update(u=f["u_b"], v=f["v_b"], inside=0.0)
        tangent = tangent + _field(q, polarization, along_b, axial) * db[..., None]
    return field, tangent


_unit_field.defjvp(_unit_field_jvp, symbolic_zeros=True)


def cylinder(
    points: Float[ArrayLike, "... 3"],
    *,
    radius: Float[ArrayLike, ""],
    height: Float[ArrayLike, ""],
    polarization: Float[ArrayLike, ""] | Float[ArrayLike, "... 3"],
    fidelity: str = "exact",
) -> Float[Array, "... 3"]:
    """Flux density B (T) of a uniformly magnetised solid cylinder.

    Args:
        points: observation points (m) in the magnet frame, shape (..., 3): centre at
            the origin, axis along z. Inside and outside.
        radius: cylinder radius R (m), > 0, a scalar (one magnet per call).
        height: cylinder height D (m), > 0, a scalar.
        polarization: magnetic polarization J = mu0 M (T) (the remanence Br for a
            permanent magnet): a scalar for a magnet polarized along +z (any sign), or a
            vector (..., 3) (Jx, Jy, Jz) in the magnet frame for any direction (axial plus
            diametral parts), broadcasting with ``points``.
        fidelity: "exact" (relative error below 1e-12 at any point outside the magnet,
            for height / radius from 1e-6 to 1e3: the face terms near the magnet, the
            multipole series beyond MULTIPOLE_SWITCH enclosing-sphere radii, the side
            wall's loops for thin magnets; see the module docstring) or "dipole" (the
            point dipole of the same moment J pi R^2 D / mu0; relative error
            O((R^2 + D^2/4) / r^2) far away, wrong near), or "axis" (the on-axis
            closed form :func:`cylinder_axial` taken at the point's height, with the
            diametral part -J_perp f / 2 + chi J_perp of the on-axis field: exact on the
            axis; off the axis an approximation whose error grows like (rho / R)^2, for
            scenes whose sensors sit on the axis and move along it).

    Returns:
        B (T), shape (..., 3).

    Derivatives (jax.grad, jacfwd, jacrev) with respect to the points, the radius, the
    height and the polarization come from closed forms evaluated beside the field
    (fidelity "exact"), finite everywhere the value is.

    Conventions at the singular points (fidelity "exact"):
        - on the side wall (rho = R, |z| < D/2) and on the faces, where a component jumps
          across the surface current or charge, the value is the mean of its inside and
          outside limits;
        - on an edge (rho = R, z = +-D/2), where the field diverges logarithmically, the
          value is that at about 2e-15 R from the edge (see _special.KC_MIN).
    """
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    check_last_axis("points", points, 3)
    check_scalar("one magnet per call; jax.vmap maps over several", radius=radius, height=height)
    check_positive(radius=radius, height=height, unit="m")
    axial = jnp.ndim(polarization) == 0
    if not axial:
        check_last_axis("polarization", polarization, 3)
        check_broadcasts("points", points, polarization=polarization)
    points = float_array(points)
    polarization = jnp.asarray(polarization, dtype=points.dtype)
    vector = jnp.stack([0.0 * polarization, 0.0 * polarization, polarization], -1) if axial else polarization
    if fidelity == "dipole":
        return dipole(points, vector * (jnp.pi * radius**2 * height / MU0))
    if fidelity == "axis":
        # B_z on the axis is even in z: taken at |z|, on the side of the top face.
        on_axis = cylinder_axial(jnp.abs(points[..., 2]), radius=radius, height=height, polarization=1.0)
        inside = 0.5 * (1.0 + jnp.sign(0.5 * height - jnp.abs(points[..., 2])))
        transverse = inside - 0.5 * on_axis
        return vector * jnp.stack([transverse, transverse, on_axis], axis=-1)
    b = 0.5 * height / radius
    branch = _branch(b)
    return _unit_field(points / radius, b, polarization, axial, branch if isinstance(branch, int) else None)


def cylinder_axial(
    z: Float[ArrayLike, "..."],
    *,
    radius: Float[ArrayLike, "..."],
    height: Float[ArrayLike, "..."],
    polarization: Float[ArrayLike, "..."],
) -> Float[Array, "..."]:
    """B_z (T) on the axis of an axially magnetised cylinder, in closed form (the
    dome-Hall paper's Eq. 1 with z measured from the magnet's centre):

        B_z = J/2 [(z + D/2) / sqrt(R^2 + (z + D/2)^2) - (z - D/2) / sqrt(R^2 + (z - D/2)^2)]

    Args:
        z: the point's coordinate (m) along the axis in the magnet frame (centre at the
            origin, magnetised along +z), any shape: the top face is at z = D/2, so a
            sensor a gap g above the top face is at z = g + D/2. Inside and outside.
        radius: R (m), > 0.
        height: D (m), > 0.
        polarization: J = mu0 M (T): the remanence Br for a permanent magnet. ``radius``,
            ``height`` and ``polarization`` broadcast with ``z``.

    Returns:
        B_z (T), shape of the arguments broadcast together (see docs/models.md,
        "Conventions"). Evaluated without cancellation at any distance (see
        :func:`_on_axis`).
    """
    check_positive(radius=radius, height=height, unit="m")
    check_broadcasts("z", z, radius=radius, height=height, polarization=polarization)
    z = float_array(z)
    return 0.5 * polarization * _on_axis(z + 0.5 * height, z - 0.5 * height, radius, height)


def cylinder_on_axis(
    z: Float[ArrayLike, "..."],
    *,
    radius: Float[ArrayLike, ""],
    height: Float[ArrayLike, ""],
    polarization: Float[ArrayLike, ""] | None = None,
    remanence: Float[ArrayLike, ""] | None = None,
) -> Float[Array, "..."]:
    """Deprecated: :func:`cylinder_axial` at ``z + height / 2``, which measures z from the
    magnet's centre like every other field function. Kept for one release; it warns.

    B_z (T) on the axis of an axially magnetised cylinder (the dome-Hall paper's Eq. 1),

        B_z = Br/2 [(D + z) / sqrt(R^2 + (D + z)^2) - z / sqrt(R^2 + z^2)]

    Args:
        z: distance (m) above the TOP face, any shape; negative values go into the
            magnet (-D < z < 0) and below it.
        radius: R (m), > 0.
        height: D (m), > 0.
        polarization: Br (T); ``remanence`` is its old name (give one of them).

    Returns:
        B_z (T), the same numbers as before the deprecation.
    """
    if (polarization is None) == (remanence is None):
        raise TypeError("cylinder_on_axis(): give polarization= (or its deprecated name remanence=), once")
    polarization = remanence if polarization is None else polarization
    warnings.warn(
        "fields.cylinder_on_axis(z, ..., remanence=) measures z from the top face and is deprecated; use "
        "fields.cylinder_axial(z + height / 2, radius=..., height=..., polarization=...), which measures "
        "z from the magnet's centre",
        DeprecationWarning,
        stacklevel=2,
    )
    check_positive(radius=radius, height=height, unit="m")
    check_broadcasts("z", z, radius=radius, height=height, polarization=polarization)
    z = float_array(z)
    return 0.5 * polarization * _on_axis(height + z, z, radius, height)


def _on_axis(u, v, radius, height):
    """The bracket of the on-axis field, u / s_u - v / s_v, of the heights u and v = u - D
    (m) of the point above the bottom and the top face, with s_u, s_v their roots
    sqrt(R^2 + u^2). It is evaluated as R^2 D (u + v) / (s_u s_v (u s_v + v s_u)) where u,
    v have the same sign (no cancellation at any distance), and as (u s_v - v s_u) /
    (s_u s_v) where they differ (a sum of two positive terms)."""
    s_u = jnp.sqrt(radius**2 + u * u)
    s_v = jnp.sqrt(radius**2 + v * v)
    # The bracket is (u s_v - v s_u) / (s_u s_v); where u and v have the same sign its
    # numerator is R^2 D (u + v) / (u s_v + v s_u), whose denominator can vanish only where
    # they differ (at the centre, u = -v), so each form is taken where it is exact.
    a, b = u * s_v, v * s_u
    opposite = u * v < 0.0
    return double_where(
        opposite, (a - b) / (s_u * s_v), lambda ab: radius**2 * height * (u + v) / (s_u * s_v * ab), a + b
    )
