"""What readings can resolve: the Cramer-Rao bound of parameters estimated from noisy readings.

R readings r(p) of P parameters, each with independent Gaussian noise of standard deviation
sigma_i: no unbiased estimate of p has a smaller covariance than the inverse of the Fisher
information, (J^T W J)^-1 with J = dr/dp (R, P) and W = diag(1 / sigma_i^2) (H. Cramer,
"Mathematical Methods of Statistics", 1946; C. R. Rao, "Information and the accuracy
attainable in the estimation of statistical parameters", 1945). It is computed from the
singular value decomposition of the whitened Jacobian W^(1/2) J = U S V^T as
V S^-2 V^T, never by forming and inverting J^T W J (which squares its condition number).

A direction of p that changes no reading (a zero singular value) cannot be estimated at all:
its variance is not zero, it is unbounded. The bound gives it the finite, huge variance of a
singular value UNRESOLVED_RATIO times the largest, and reports the smallest singular value
(``conditioning``): below 1, some unit step of the parameters changes the readings by less
than their noise.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

# Singular values of the whitened Jacobian below this fraction of the largest count as that
# fraction: their directions get a variance (UNRESOLVED_RATIO s_max)^-2, finite and far
# above any resolved one, instead of 1 / 0.
UNRESOLVED_RATIO = 1e-8


class Bound(eqx.Module):
    """The Cramer-Rao bound of P parameters (in the parameters' units).

    Attributes:
        covariance: (P, P) the smallest covariance of any unbiased estimate.
        deviation: (P,) the square roots of its diagonal: each parameter's standard deviation.
        conditioning: () the whitened Jacobian's smallest singular value (-): the change, in
            noise units, of the least visible unit step of the parameters.
    """

    covariance: Float[Array, "p p"]
    deviation: Float[Array, " p"]
    conditioning: Float[Array, ""]


def cramer_rao(jacobian: Float[ArrayLike, "r p"], noise: Float[ArrayLike, "*r"]) -> Bound:
    """The Cramer-Rao bound (module docstring) of the parameters of ``jacobian``.

    Args:
        jacobian: d readings / d parameters, shape (R, P) (reading unit per parameter unit).
        noise: the readings' noise standard deviations (reading unit, > 0), a scalar or (R,).

    Returns:
        :class:`Bound`. Differentiable (the SVD's derivative exists where the singular values
        are distinct).
    """
    jacobian = jnp.asarray(jacobian, dtype=float)
    noise = jnp.broadcast_to(jnp.asarray(noise, dtype=jacobian.dtype), jacobian.shape[:1])
    _, singular, vt = jnp.linalg.svd(jacobian / noise[:, None], full_matrices=False)
    floored = jnp.maximum(singular, UNRESOLVED_RATIO * singular[0])
    covariance = jnp.einsum("ki,k,kj->ij", vt, 1.0 / floored**2, vt)
    return Bound(covariance, jnp.sqrt(jnp.diagonal(covariance)), singular[-1])
