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


# Default tolerances of the design solver (magdesign.design.solve's rtol and atol; its other
# thresholds are the fields of magdesign.design._sqp.sqp.SQP). Both act on dimensionless
# quantities: variables scaled to their bound width, residuals scaled by their target.
# Default tolerance on scaled target and limit residuals: 1e-10 leaves a margin of 10 below
# the 1e-9 relative accuracy the designs are checked to; the final Newton polish stops
# at a tenth of it (its quadratic convergence usually takes it to rounding).
DESIGN_RTOL = 1e-10
# Default step tolerance in scaled variables: a converged step in a [0, 1] box.
DESIGN_ATOL = 1e-13
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


# Solver thresholds of the axisymmetric dome (magdesign.mechanics._axisymmetric).
# A state is in equilibrium when its largest out-of-balance nodal force is below this
# fraction of mu t^2 (the wall's own force scale, 2.4 N for the dome-Hall sensor's dome): Newton
# converges quadratically there, so the state it leaves is exact to float64 rounding, and
# the tolerance stays above the rounding of the contact forces (the penalty times ~1e-18 m)
# and, for walls thicker than ~0.2 mm of the dome-Hall sensor's resin, of the wall's forces (see
# DOME_ROUNDING_SLACK for thinner ones).
DOME_RESIDUAL_TOL = 1e-10
# Float64 rounding of the wall's nodal forces leaves a floor of about eps K R_o^2 theta^2
# (K the bulk modulus, theta the wall's rotation: the volume change J - 1 is a small
# difference of rotation terms), measured 2e-12 N at rotations of order one whatever the
# wall, which is the tolerance itself for a 0.2 mm wall of the dome-Hall sensor's resin. A state within
# this many tolerances, whose Newton step no longer halves its out-of-balance force,
# sits on that floor and counts as converged.
DOME_ROUNDING_SLACK = 100.0
# Smallest plate travel of the axisymmetric dome, as a fraction of the wall thickness:
# a force whose Reissner travel is below it is evaluated at the force whose Reissner
# travel equals it. Smaller travels press the plate into the dome by amounts comparable
# with the contact smoothing (CONTACT_SMOOTHING t), which then sets the answer; the secant
# compliance of a frictionless contact has no finite zero-load limit anyway (the wall's
# Hertz-like indentation, d ~ F^(2/3)).
DOME_MIN_TRAVEL_FRACTION = 1e-3
# Newton takes its full step, untested by the line search, when the decrease it predicts
# is below this fraction of the potential's magnitude: there the potential's float64
# rounding (measured up to 3e-11 relative, a thin wall's bending energy being a small
# difference of rotations) hides the decrease, and a test on the potential would refuse
# good steps (a t/R = 0.005 dome at a travel of 0.002 t stalls 20x above its tolerance).
# Near equilibrium Newton's step is exact to second order, so nothing is lost.
DOME_ENERGY_RESOLUTION = 1e-9

# First Levenberg shift (tried only when the tangent matrix is not positive definite,
# e.g. while a load step passes through a buckling-like intermediate state), as a
# fraction of each unknown's own diagonal entry (floored at this fraction of the largest);
# it grows tenfold until a Cholesky succeeds.
DOME_LEVENBERG_START = 1e-6

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


# Saturating soft bodies (fields.soft): Newton's method on the cells' polarisation J (T)
# with a backtracking line search, stopped when the residual's largest entry is below
# SATURATION_RESIDUAL (T). Its rounding is about chi eps |J| (chi up to ~1e4, |J| up to
# ~2 T: ~4e-12 T). A step is halved until |r|^2 falls by SATURATION_ARMIJO times the
# step's fraction (Armijo's sufficient decrease), down to SATURATION_SHORTEST_STEP.
SATURATION_RESIDUAL = 1e-9
SATURATION_MAX_STEPS = 100
SATURATION_ARMIJO = 1e-4
SATURATION_SHORTEST_STEP = 2.0**-30
