"""A central-difference derivative for the inverse's least-squares residuals.

The exact field kernel's own derivative takes XLA tens of seconds to compile per copy
and a least-squares solver traces several (see _numerics.FD_JACOBIAN_STEP); the
differences of all directions are one batched evaluation of the forward chain.
"""

import jax
import jax.numpy as jnp


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
