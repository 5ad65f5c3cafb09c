"""Bulirsch's generalised complete elliptic integral, fused for the cylinder kernel.

    cel(kc, p, c, s) = int_0^{pi/2} (c cos^2 t + s sin^2 t)
                       / ((cos^2 t + p sin^2 t) sqrt(cos^2 t + kc^2 sin^2 t)) dt

(Bulirsch, Numer. Math. 13, 305 (1969); used for the cylinder by Derby and Olbert,
Am. J. Phys. 78, 229 (2010)). Both integrals a face of the cylinder needs share the
modulus ``kc`` and so one arithmetic-geometric-mean sequence; they are run together for
a fixed number of steps (no data-dependent branches, one fused XLA loop).
"""

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

# Steps of the AGM after Bulirsch's first step. The relative gap between the two means
# squares at each step; from kc = 1e-6 (a point 2e-6 radii from an edge) it falls below
# float64 resolution after 6 steps (1e-12 radii from an edge: 7), and from kc >= 0.05
# after 4.
CEL_STEPS = 6

# Smallest complementary modulus passed to cel. kc -> 0 exactly on an edge of the
# cylinder, where cel has a logarithmic pole (the radial field diverges like the log
# of the distance to the edge); flooring kc there returns the field at a distance of
# about 2 KC_MIN radii from the edge instead, finite with finite gradients.
KC_MIN = 1e-15


def cel_face_pair(kc, gamma, steps=CEL_STEPS):
    """The two cel integrals of one face of an axially magnetised cylinder.

    Args:
        kc: complementary modulus in [KC_MIN, 1], any shape.
        gamma: (R - rho) / (R + rho) in (-1, 1], broadcasting with ``kc``.
        steps: AGM steps after the first (static).

    Returns:
        (radial, axial): radial = cel(kc, 1, 1, -1) / (1 - kc), kept finite and
        accurate as kc -> 1 (on the axis and far away, where cel itself vanishes);
        axial = cel(kc, gamma^2, 1, gamma), finite at gamma = 0 (rho = R), where it
        takes the mean of its limits from either side (sign(0) = 0).
    """
    # Radial integral (p = 1): Bulirsch's pp equals the arithmetic mean em at every
    # step. Its first step gives cc = 0, ss = 2 (kc - 1); both are scaled by 1 / (1 - kc).
    # Axial integral (p = gamma^2): cc, ss, pp of Bulirsch's recursion grow like 1/|gamma|;
    # they are carried multiplied by q = |gamma| (c_ax, s_ax, p_ax) so that rho = R is
    # regular. Values after Bulirsch's first step:
    q = jnp.abs(gamma)
    c_rad = jnp.zeros_like(kc)
    s_rad = -2.0 * jnp.ones_like(kc)
    c_ax = q + jnp.sign(gamma)
    s_ax = 2.0 * (gamma + kc)
    p_ax = kc + q * q
    em = 1.0 + kc
    kk = kc
    for _ in range(steps):
        k = 2.0 * kk * rsqrt(kk)
        kk = k * em
        inv_em_p = rsqrt(em * p_ax) ** 2
        inv_em = p_ax * inv_em_p
        inv_p = em * inv_em_p
        g_ax = q * kk * inv_p
        c_rad, s_rad = c_rad + s_rad * inv_em, 2.0 * (s_rad + c_rad * k)
        c_ax, s_ax = c_ax + q * s_ax * inv_p, 2.0 * (s_ax + c_ax * g_ax)
        p_ax = q * g_ax + p_ax
        em = k + em
    inv_em = rsqrt(em) ** 2
    radial = 0.25 * jnp.pi * (s_rad + c_rad * em) * inv_em * inv_em
    axial = 0.5 * jnp.pi * (s_ax + c_ax * em) * inv_em * rsqrt(q * em + p_ax) ** 2
    return radial, axial


# Far-field switch of the cylinder, in units of the radius of the smallest sphere
# enclosing the magnet: beyond it the exact kernel (whose top- and bottom-face terms
# cancel: measured relative error 1e-14 (1e-13 for a disc of height R/50) at 4
# enclosing radii, 3e-10 at 100) gives way to the axial multipole series, whose
# truncation error falls like (1 / MULTIPOLE_SWITCH)^(2 MULTIPOLE_TERMS) (measured
# 2e-15 at the switch, against a 40-digit quadrature of Derby-Olbert).
MULTIPOLE_SWITCH = 4.0
MULTIPOLE_TERMS = 14


def axial_multipole(coefficients, rho2, z, switch_r2):
    """Field of an axisymmetric set of odd axial multipoles, and its radial part over rho.

    The on-axis field B_z(z) = sum_l c_l / z^(l+2) (l = 1, 3, 5, ...) extends off the
    axis as B_z = sum_l c_l P_{l+1}(mu) / r^(l+2) and
    B_rho / rho = sum_l c_l P'_{l+1}(mu) / ((l+1) r^(l+3)), with mu = z / r.

    Args:
        coefficients: (c_1, c_3, ...) as a sequence of arrays broadcasting with rho2.
        rho2, z: squared distance to the axis and height, in the units the c_l use.
        switch_r2: squared radius inside which the series is not used.

    Returns:
        (B_rho / rho, B_z). Points inside the switch sphere are evaluated as if at its
        radius (the series diverges towards the origin and would overflow there): the
        result is finite, with finite gradients, and meant to be discarded by the caller.
    """
    inv_r = rsqrt(jnp.maximum(rho2 + z * z, switch_r2))
    u = inv_r * inv_r
    mu = z * inv_r
    # Legendre polynomials P_n(mu) and their derivatives, upwards from n = 0, 1.
    p_prev, p = jnp.ones_like(mu), mu
    dp = jnp.ones_like(mu)
    b_z = jnp.zeros_like(mu)
    b_rho_over_rho = jnp.zeros_like(mu)
    scale = u * inv_r
    for n in range(1, 2 * len(coefficients)):
        p_prev, p = p, ((2 * n + 1) * mu * p - n * p_prev) / (n + 1)
        dp = (n + 1) * p_prev + mu * dp
        if n % 2 == 1:  # p is now P_{l+1} for l = n
            c = coefficients[n // 2]
            b_z = b_z + c * p * scale
            b_rho_over_rho = b_rho_over_rho + c / (n + 1) * dp * scale * inv_r
            scale = scale * u
    return b_rho_over_rho, b_z
