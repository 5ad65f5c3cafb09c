"""The axisymmetric dome's mesh ladder and the error estimate from two of its levels.

Each level refines the wall and the meridian together, so that the element size h falls by
the same ratio across the wall and along it; each level is one compiled program.

The estimate of the value at level k >= 1 is ``ESTIMATE_FACTOR |f_k - f_(k-1)|``, and not
below ``ESTIMATE_FLOOR |f_k|``. Richardson's argument for a value converging as h^p, with
refinement ratio r, gives |f_k - f| = |f_k - f_(k-1)| / (r^p - 1): 0.8 for p = 2 and r = 1.5,
3 for p = 1 and r = 1.33. The measured convergence is neither monotone nor of one order (the
penalty contact moves between elements, and past a buckle the followed path changes its
branch): over bonded domes of t / R_o 0.05 and 0.125 (R_o 8 mm), forces from a travel of
t / 10 to past the buckle, against meshes at least twice as fine each way, the ratio of true
error to difference reached 3.4 where the difference was above the floor; on the dome-Hall
sensor's dome (t / R_o 0.25, 5 N) two levels agreed to 0.03 % with the finer 0.19 % from
the fine mesh. The floor, 0.3 %, is that scatter of the contact between meshes; with it and
the factor 4 the largest true error measured was 0.86 of its estimate. The lowest level's
value is estimated from the level above it:
|f_0 - f| <= |f_0 - f_1| + |f_1 - f| <= (1 + ESTIMATE_FACTOR) |f_1 - f_0|.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

# (elements through the wall, elements along the meridian), coarsest first
LADDER = ((2, 16), (3, 24), (4, 32), (6, 48))
# Multiplier of the difference between two consecutive levels (see the module docstring)
ESTIMATE_FACTOR = 4.0
# Smallest estimate, as a fraction of the value: the contact's scatter between meshes
ESTIMATE_FLOOR = 3e-3


def level_of(mesh):
    """Index of ``mesh`` in LADDER, or None for a mesh off the ladder."""
    mesh = tuple(int(n) for n in mesh)
    return LADDER.index(mesh) if mesh in LADDER else None


def companion(level):
    """The level whose value the estimate at ``level`` is compared with: the one below, or
    for the lowest level the one above."""
    return level - 1 if level > 0 else 1


def bound(value, other, other_is_finer):
    """Estimated absolute error of ``value`` from ``other``, the value one level finer
    (``other_is_finer``) or one level coarser (the module docstring's rule), elementwise, in
    the units of the value. Numbers or numpy arrays are bounded with numpy (a command's
    estimate, on the host: no program to compile), jax arrays with jax."""
    factor = 1 + ESTIMATE_FACTOR if other_is_finer else ESTIMATE_FACTOR
    xp = jnp if isinstance(value, jax.Array) or isinstance(other, jax.Array) else np
    return xp.maximum(factor * xp.abs(value - other), ESTIMATE_FLOOR * xp.abs(value))


def estimate(value, other, level, usable):
    """Estimated absolute error of ``value`` (level ``level``) from ``other`` (the value at
    ``companion(level)``), in the units of the value; +inf where ``usable`` is False (the
    companion's solve failed, so nothing is known). Not differentiated."""
    value, other = lax.stop_gradient(value), lax.stop_gradient(other)
    return jnp.where(usable, bound(value, other, companion(level) > level), jnp.inf)


def met(value, error, rtol):
    """Whether ``error`` <= ``rtol`` |value|, elementwise."""
    return error <= rtol * jnp.abs(value)
