"""Special functions of the cylinder kernel, written so that XLA fuses them into one loop.

- Bulirsch's generalised complete elliptic integral

      cel(kc, p, a, b) = int_0^{pi/2} (a cos^2 t + b sin^2 t)
                         / ((cos^2 t + p sin^2 t) sqrt(cos^2 t + kc^2 sin^2 t)) dt

  (Bulirsch, Numer. Math. 13, 305 (1969); used for the cylinder by Derby and Olbert,
  Am. J. Phys. 78, 229 (2010)): every integral a face of the cylinder needs shares the
  modulus ``kc`` and so one arithmetic-geometric-mean sequence (:func:`cel_face`).
- The field of a set of axial multipoles and its derivatives (:func:`multipole`), the
  far field of the cylinder.
"""

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

# XLA on CPU never fuses a divide or a square root into more than one consumer (it
# counts them as expensive to duplicate), so in a kernel where each such value is used
# several times every one of them becomes a separate pass over memory: the cel loop ran
# at ~1 M points/s that way. rsqrt below is built from cheap operations only (a bit-level
# first guess, then Newton steps), so that the whole kernel fuses into one loop.
# Lomont's first guess for 1/sqrt(x) in float64 is within 3.5 % of it; each Newton step
# squares the relative error: 3.5e-2, 1.8e-3, 5e-6, 4e-11, 1 ulp after RSQRT_NEWTON_STEPS.
RSQRT_MAGIC = np.int64(0x5FE6EB50C7B537A9)
RSQRT_NEWTON_STEPS = 4


@jax.custom_jvp
def rsqrt(x):
    """1/sqrt(x) (x > 0) from multiply-adds only in float64, so it fuses into any XLA CPU
    loop; float32 takes the native rsqrt.

    At x = 0 it returns a large finite number (so x * rsqrt(x) = 0 there).
    """
    if x.dtype == jnp.float32:
        return jax.lax.rsqrt(x)
    bits = jax.lax.bitcast_convert_type(x, jnp.int64)
    y = jax.lax.bitcast_convert_type(RSQRT_MAGIC - (bits >> 1), jnp.float64)
    half_x = 0.5 * x
    for _ in range(RSQRT_NEWTON_STEPS):
        y = y * (1.5 - half_x * y * y)
    return y


@rsqrt.defjvp
def _rsqrt_jvp(primals, tangents):
    (x,), (dx,) = primals, tangents
    y = rsqrt(x)
    return y, -0.5 * y * y * y * dx


def reciprocal(x):
    """1/x for x > 0, fused like :func:`rsqrt` (its square)."""
    y = rsqrt(x)
    return y * y


def materialize(pair_a, pair_b, positive):
    """``complex(pair_a, pair_b)``, or ``pair_a`` alone when ``pair_b`` is None, computed
    once into memory by one loop.

    XLA on CPU builds no multi-output loops: two arrays computed from one kernel cost two
    runs of it, and a consumer that reads a cheap-to-recompute kernel at several output
    elements (the three field components) re-runs it for each. Packing two results into
    one complex array makes the kernel one loop with one output; the true division at the
    end (by ``positive``, a value > 0, after multiplying by it: at most 1 ulp of rounding)
    is what XLA will not duplicate into its consumers, so that loop runs once and its
    consumers read memory. Measured for the face terms (elliptic integrals shared by the
    pair): 1.8x faster than the two results apart, and 15x faster than a stacked (n, 3)
    output computed in one loop. But XLA does not vectorise a complex loop: where the
    shared work is cheap, real loops apart are faster (the far series' p and z at 1e6
    points: 6.6 ms each as real loops, 18 ms as one complex loop).
    """
    if pair_b is None:
        return (pair_a * positive) / positive
    packed = jax.lax.complex(pair_a * positive, pair_b * positive)
    return packed / positive.astype(packed.dtype)


# Steps of the AGM after Bulirsch's first step. The relative gap between the two means
# squares at each step; from kc = 1e-6 (a point 2e-6 radii from an edge) it falls below
# float64 resolution after 6 steps (1e-12 radii from an edge: 7), and from kc >= 0.05
# after 4.
CEL_STEPS = 7

# Smallest complementary modulus passed to cel. kc -> 0 exactly on an edge of the
# cylinder, where cel has a logarithmic pole (the radial field diverges like the log
# of the distance to the edge); flooring kc there returns the field at a distance of
# about 2 KC_MIN radii from the edge instead, finite with finite gradients. In float32
# the floor is KC_MIN_FLOAT32 (float32 resolves no finer, and the products of the fused
# AGM below stay inside its range).
KC_MIN = 1e-15
KC_MIN_FLOAT32 = 1e-6


class FaceIntegrals(NamedTuple):
    """The complete elliptic integrals of one face (see :func:`cel_face`)."""

    radial: jax.Array  # cel(kc, 1, 1, -1) / (1 - kc^2)
    first: jax.Array  # K = cel(kc, 1, 1, 1)
    axial: jax.Array  # cel(kc, gamma^2, 1, gamma)
    cosine: jax.Array  # cel(kc, gamma^2, 1, 0)


def cel_face(kc, gamma, p_chain=True, first=True, steps=CEL_STEPS):
    """Every cel integral one face of a cylinder needs, from one AGM sequence.

    Args:
        kc: complementary modulus in [KC_MIN, 1], any shape.
        gamma: (R - rho) / (R + rho) in (-1, 1], broadcasting with ``kc``.
        p_chain: also the integrals with p = gamma^2 (axial, cosine); without them
            (static False) each step is cheaper, and those two are None.
        first: also K (static; None without).
        steps: AGM steps after the first (static).

    Returns:
        :class:`FaceIntegrals`. radial = cel(kc, 1, 1, -1) / (1 - kc^2) is kept finite and
        accurate as kc -> 1 (on the axis and far away, where cel itself vanishes);
        axial and cosine (p = gamma^2) are finite at gamma = 0 (rho = R), where axial
        takes the mean of its limits from either side (sign(0) = 0).
    """
    # Bulirsch's recursion is linear in (a, b) for given (kc, p): integrals with the same
    # p share everything but their (a, b) pair, and all share kc and the mean em.
    # p = 1 (radial, first): Bulirsch's p equals em at every step. After his first step
    # (a, b) = (0, 2 (kc - 1)) for (1, -1), scaled by 1 / (1 - kc); (2, 2 (1 + kc)) for
    # (1, 1), scaled by 1/2.
    # p = gamma^2 (axial, cosine): a, b and p grow like 1 / |gamma|; they are carried
    # multiplied by q = |gamma| so that rho = R is regular. After the first step,
    # q (a, b) = (q + sign(gamma), 2 (gamma + kc)) for (1, gamma), (q, 2 kc) for (1, 0),
    # and q p = kc + q^2.
    q = jnp.abs(gamma)
    ones = jnp.ones_like(kc * q)
    c_rad, s_rad = 0.0 * ones, -2.0 * ones
    c_k, s_k = ones, 1.0 + kc
    c_ax, s_ax = q + jnp.sign(gamma), 2.0 * (gamma + kc)
    c_cos, s_cos = q * ones, 2.0 * kc
    p_ax = kc + q * q if p_chain else ones
    em = 1.0 + kc
    kk = kc
    for _ in range(steps):
        # One rsqrt gives sqrt(kk), 1/em (and 1/p): r = 1 / (sqrt(kk) em p).
        r = rsqrt(kk * (em * p_ax) ** 2)
        root = kk * em * p_ax * r
        inv_em = root * p_ax * r
        k = 2.0 * root
        kk = k * em
        c_rad, s_rad = c_rad + s_rad * inv_em, 2.0 * (s_rad + c_rad * k)
        if first:
            c_k, s_k = c_k + s_k * inv_em, 2.0 * (s_k + c_k * k)
        if p_chain:
            inv_p = root * em * r
            g_ax = q * kk * inv_p
            c_ax, s_ax = c_ax + q * s_ax * inv_p, 2.0 * (s_ax + c_ax * g_ax)
            c_cos, s_cos = c_cos + q * s_cos * inv_p, 2.0 * (s_cos + c_cos * g_ax)
            p_ax = q * g_ax + p_ax
        em = k + em
    # 1 / em, 1 / (q em + p) and 1 / (1 + kc) from one reciprocal of their product.
    denominator = q * em + p_ax if p_chain else ones
    one_kc = 1.0 + kc
    t = reciprocal(em * denominator * one_kc)
    inv_em, inv_d = denominator * one_kc * t, em * one_kc * t
    return FaceIntegrals(
        radial=0.25 * jnp.pi * (s_rad + c_rad * em) * inv_em * inv_em * (em * denominator * t),
        first=0.5 * jnp.pi * (s_k + c_k * em) * inv_em * inv_em if first else None,
        axial=0.5 * jnp.pi * (s_ax + c_ax * em) * inv_em * inv_d if p_chain else None,
        cosine=0.5 * jnp.pi * (s_cos + c_cos * em) * inv_em * inv_d if p_chain else None,
    )


# Far-field switch of the cylinder, in units of the radius of the smallest sphere
# enclosing the magnet: beyond it the face terms (whose top- and bottom-face parts
# cancel: measured relative error 1e-14 at 4 enclosing radii for a 3 x 1 mm magnet,
# growing like the distance) give way to the axial multipole series, whose truncation
# error falls like (1 / MULTIPOLE_SWITCH)^(2 MULTIPOLE_TERMS) (measured 2e-15 at the
# switch, against a 40-digit quadrature of Derby-Olbert).
MULTIPOLE_SWITCH = 4.0
MULTIPOLE_TERMS = 14


# Thin magnets: beyond WALL_SWITCH half heights from the side wall the two faces of a thin
# magnet cancel to about (half height / distance) (relative error of the difference
# ~ 5e-16 distance / half height), and the wall's loops are integrated over its height
# instead: WALL_NODES Gauss-Legendre nodes, whose error there falls like
# (2 WALL_SWITCH)^(-2 WALL_NODES) = 1.6e-14 (measured lower, below 1e-15). Inside the
# switch the face differences lose at most a factor WALL_SWITCH (measured 3e-14).
WALL_SWITCH = 30.0
WALL_NODES = 4

# Long magnets: a face farther than FACE_SWITCH radii from a point is taken from the
# series of the semi-infinite rod it ends (see cylinder._rod_end), ROD_TERMS terms falling
# like (1 / FACE_SWITCH)^(2 k): 16^-14 = 1.4e-17. Nearer, the face terms as usual. Without
# it a face far from the point loses digits in proportion to (distance / rho) and, beyond
# the rod's end, (distance)^2 (measured 5e-10 at 130 radii beyond a rod 1000 radii long);
# magnets longer than LONG_HALF_HEIGHT radii (half height) take this branch.
FACE_SWITCH = 4.0
ROD_TERMS = 14
LONG_HALF_HEIGHT = 2.0

# Squared distance to the axis (in radii^2) below which the diametral functions and the
# s-derivatives are taken from their series in s: the closed forms divide by rho or s
# there (relative error ~1e-16 / rho of u at the switch, 2.5e-14), while the series,
# four terms, are exact to s^4 = 1e-24.
AXIS_SERIES_S = 1e-6


@functools.partial(jax.jit, static_argnames="wanted")
def multipole(coefficients, rho2, z, switch_r2, wanted=("p", "z", "u", "p_z", "z_z")):
    """Field parts of an axisymmetric multipole source, in the units of its coefficients.

    With the scalar potential psi of the source (B = Hess(psi) J for a uniformly
    magnetised body, J its polarization) given through its axial derivative
    W = dpsi/dz = sum_n w_n P_n(mu) / r^(n+1) (r^2 = rho^2 + z^2, mu = z / r): from
    d/dz [P_n(mu) / r^(n+1)] = -(n+1) P_{n+1}(mu) / r^(n+2) and
    (1/rho) d/drho [P_n(mu) / r^(n+1)] = -P'_{n+1}(mu) / r^(n+3),

        z = dW/dz = B_z = -sum w_n (n+1) P_{n+1} / r^(n+2)
        p = (1/rho) dW/drho = B_rho / rho = -sum w_n P'_{n+1} / r^(n+3)
        u = (dpsi/drho) / rho = sum_{n>=1} w_n P'_n / (n r^(n+2)) + w_0 / (r (r + z))
        z_z = dz/dz = sum w_n (n+1) (n+2) P_{n+2} / r^(n+3)
        p_z = dp/dz = sum w_n (n+1) P'_{n+2} / r^(n+4)

    (the n = 0 term of u is that of a line of sources along the axis below the origin,
    the only potential whose z-derivative is w_0 / r and which is finite above it: it
    holds for z >= 0, where it is used).

    Args:
        coefficients: dict {n: w_n} of scalars or arrays broadcasting with rho2.
        rho2, z: squared distance to the axis and height, in the units the w_n use.
        switch_r2: squared radius inside which the series is not used.
        wanted: which of p, z, u, p_z, z_z to compute (static).

    Returns:
        A dict of the wanted parts. Points inside the switch sphere are evaluated as if at
        its radius (the series diverges towards the origin and would overflow there): the
        result is finite, with finite gradients, and meant to be discarded by the caller.
    """
    top = max(coefficients) + 2
    r2 = jnp.maximum(rho2 + z * z, switch_r2)
    inv_r = rsqrt(r2)
    inv_r2, z_r2 = inv_r * inv_r, z * inv_r * inv_r
    # The solid harmonics Q_n = P_n(mu) / r^(n+1) and D_n = P'_n(mu) / r^(n+2), upwards
    # from n = 0, 1, by Bonnet's recursion and P'_{n+1} = (n+1) P_n + mu P'_n with the
    # powers of 1/r carried along (no separate powers or products in the terms).
    solid, derivative = [inv_r, z_r2 * inv_r], [0.0 * inv_r, inv_r2 * inv_r]
    for n in range(1, top):
        solid.append((2 * n + 1) / (n + 1) * z_r2 * solid[n] - n / (n + 1) * inv_r2 * solid[n - 1])
        derivative.append((n + 1) * inv_r2 * solid[n] + z_r2 * derivative[n])
    terms = {
        "p": lambda n, w: -w * derivative[n + 1],
        "z": lambda n, w: -w * (n + 1) * solid[n + 1],
        "u": lambda n, w: w * reciprocal(r2 + z * r2 * inv_r) if n == 0 else w / n * derivative[n],
        "p_z": lambda n, w: w * (n + 1) * derivative[n + 2],
        "z_z": lambda n, w: w * (n + 1) * (n + 2) * solid[n + 2],
    }
    return {name: sum(terms[name](n, w) for n, w in coefficients.items()) for name in wanted}
