"""A central-difference derivative for the inverse's least-squares residuals.

The exact field kernel's own derivative takes XLA tens of seconds to compile per copy
and a least-squares solver traces several (see FD_JACOBIAN_STEP); the
differences of all directions are one batched evaluation of the forward chain.
"""

import jax
import jax.numpy as jnp

# Step tolerances of the least-squares solves of magdesign.inverse, whose unknowns are
# scaled to order one there (displacements in units of the wanted resolution, fitted
# constants as factors on their start values): far below any resolution asked for,
# far above float64's rounding (1e-16) so that the solvers terminate.
LSQ_RTOL = 1e-10
LSQ_ATOL = 1e-10

# Step of the central-difference Jacobian of magdesign.inverse's forward models, in the
# solver's scaled unknowns (units of the wanted resolution, 1-100 um): the exact field
# kernel's own derivative takes XLA tens of seconds to compile per copy, and a least-squares
# solver holds several. At 1e-2 resolutions (0.01-1 um, against field length scales of
# millimetres) the truncation error (step / length)^2 and the rounding error
# (1e-16 / step, relative) both stay below 1e-8 of the Jacobian.
FD_JACOBIAN_STEP = 1e-2


def difference_jacobian(fn, step):
    """``fn`` (a map (p,) -> (m,) of scaled unknowns) with a central-difference JVP.

    Values are ``fn``'s own; derivatives (jvp, jacfwd, linearize) use differences of
    ``step`` (in the unknowns' scaled units) along each unknown.
    """

    @jax.custom_jvp
    def wrapped(y):
        return fn(y)

    @wrapped.defjvp
    def _wrapped_jvp(primals, tangents):
        (y,), (t,) = primals, tangents
        n = y.shape[0]
        # the value and the 2 n differences in one batched call (one compiled copy of fn)
        values = jax.vmap(fn)(y + step * jnp.concatenate([jnp.zeros((1, n)), jnp.eye(n), -jnp.eye(n)]))
        jacobian = (values[1 : n + 1] - values[n + 1 :]).T / (2.0 * step)
        return values[0], jacobian @ t

    return wrapped
