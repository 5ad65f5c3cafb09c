"""The only home of numerical stability tricks.

Every guard here says which singularity it protects, what it returns there and why.
Thresholds are named constants. Guards use the "double where": the unsafe branch is
fed a harmless argument where it would be singular, so that neither the value nor the
gradient of the discarded branch can be NaN (a NaN in the discarded branch of a plain
``jnp.where`` still poisons the gradient).
"""

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
