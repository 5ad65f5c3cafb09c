"""The only home of numerical stability tricks.

Every guard here says which singularity it protects, what it returns there and why.
Thresholds are named constants. Guards use the "double where": the unsafe branch is
fed a harmless argument where it would be singular, so that neither the value nor the
gradient of the discarded branch can be NaN (a NaN in the discarded branch of a plain
``jnp.where`` still poisons the gradient).
"""

import jax
import jax.numpy as jnp

# Relative size below which a denominator counts as zero. Chosen far below any
# physical ratio the library forms (magnet/sensor distances of 1 um over 1 km are
# still 1e-9) and far above float64's smallest normal number.
TINY = 1e-300


def double_where(condition, safe_value, unsafe_fn, x):
    """``where(condition, safe_value, unsafe_fn(x))`` with NaN-free gradients.

    Where ``condition`` holds, ``unsafe_fn`` is evaluated at ``ones_like(x)``
    instead of ``x`` so that its (discarded) value and derivative stay finite.
    """
    x_safe = jnp.where(condition, jnp.ones_like(x), x)
    return jnp.where(condition, safe_value, unsafe_fn(x_safe))


def safe_div(numerator, denominator, at_zero=0.0):
    """numerator / denominator, returning ``at_zero`` where the denominator is 0.

    Singularity: division by an exact zero (e.g. the radial unit vector on the axis
    of a magnet, where the radial field component is 0 by symmetry). Returns the
    caller's limit value ``at_zero`` there, with a zero gradient through the guard.
    """
    is_zero = jnp.abs(denominator) < TINY
    safe_den = jnp.where(is_zero, jnp.ones_like(denominator), denominator)
    return jnp.where(is_zero, at_zero, numerator / safe_den)


def safe_sqrt(x):
    """sqrt(x) for x >= 0 with a finite gradient at x = 0 (d/dx sqrt is infinite there).

    Singularity: the derivative 1/(2 sqrt x) at x = 0, met for instance by the
    distance to the axis evaluated on the axis. Returns 0 with a zero gradient there;
    callers whose result depends on sqrt(x) only through an even function get the
    correct derivative this way.
    """
    is_zero = x <= 0.0
    return jnp.where(is_zero, 0.0, jnp.sqrt(jnp.where(is_zero, 1.0, x)))


def safe_norm(v, axis=-1):
    """Euclidean norm along ``axis``, 0 with a zero gradient at the zero vector."""
    return safe_sqrt(jnp.sum(v * v, axis=axis))


def safe_log(x, at_zero=0.0):
    """log(x) for x > 0; ``at_zero`` with a zero gradient where x <= 0 (log's pole)."""
    bad = x <= 0.0
    return jnp.where(bad, at_zero, jnp.log(jnp.where(bad, 1.0, x)))


# Values that spread by less than this fraction of their size are one number up to rounding:
# reports and pictures show the number, not its noise (sweep maps, tolerance histograms).
ROUNDING_SPREAD = 1e-9


# Width of the smoothed contact ramp, as a fraction of the length it is applied to (the
# wall thickness of a dome): small enough that the smoothing moves contact forces by far
# less than the penalty's own penetration (about 1 % of the wall), large enough that the
# ramp stays a smooth (C-infinity) function in float64 for Newton and design gradients.
CONTACT_SMOOTHING = 1e-5


def smooth_ramp(x, width):
    """max(x, 0) smoothed over ``width``: width * softplus(x / width).

    Singularity: the kink of max(x, 0) at x = 0 (contact opening and closing), which
    would make Newton's method cycle and design gradients jump. Returns width * log 2 at
    x = 0, x + O(width e^(-x/width)) above and width e^(x/width) below: always positive
    with a positive slope, so a contact force built on it is never exactly zero.
    """
    return width * jax.nn.softplus(x / width)


# Smallest distance to a film's corner, as a fraction of the film's width: the field of a
# finite film diverges logarithmically at its corners (where its face meets its side);
# there the value at this distance is returned, finite with finite gradients (like the
# cylinder's KC_MIN on its edges).
EDGE_DISTANCE_MIN = 1e-15


def expm1_ratio(s):
    """(e^s - 1) / s for real or complex s, 1 at s = 0 (the removable singularity).

    Singularity: 0 / 0 at s = 0 (a point on a film's bottom face, exactly below a
    quadrature node). Elsewhere expm1 keeps full relative precision for small |s|.
    """
    is_zero = s == 0
    safe = jnp.where(is_zero, jnp.ones_like(s), s)
    return jnp.where(is_zero, jnp.ones_like(s), jnp.expm1(safe) / safe)


def float_array(x):
    """``x`` as a floating-point array: float32 stays float32 (a documented, tested option
    of the field kernels), anything else becomes float64."""
    x = jnp.asarray(x)
    return x if x.dtype == jnp.float32 else x.astype(jnp.float64)


def safe_atan2(y, x):
    """atan2(y, x) with a finite gradient however small (x, y) are.

    Singularity: the derivative (-y, x) / (x^2 + y^2) underflows to 0/0 once x and y are
    below ~1e-154 (the field deep below a film, k z > ~350), and is a true 0/0 at the
    origin. Dividing both by the larger magnitude leaves the angle unchanged and keeps the
    squares of order 1; at (0, 0) it returns 0 with a zero gradient. The scale is held
    constant for differentiation: the angle does not depend on it, and its own derivative
    would bring back the tiny squares (flushed to zero on CPU).
    """
    scale = jax.lax.stop_gradient(jnp.maximum(jnp.abs(x), jnp.abs(y)))
    is_zero = scale == 0.0
    safe_scale = jnp.where(is_zero, 1.0, scale)
    return jnp.where(is_zero, 0.0, jnp.arctan2(y / safe_scale, jnp.where(is_zero, 1.0, x / safe_scale)))
