"""The linear solver of the design solver's polish: LU where it is safe, SVD where not.

lineax's SVD gives the minimum-norm solution where a Jacobian is rank-deficient (a
degenerate active set), which the polish needs; but a batched SVD of a tiny matrix costs
about 24 times its LU (LAPACK's gesdd against getrf: 26 against 1.1 ms for 3334 4 x 4
matrices on the 2-core development machine). Almost every KKT Jacobian of the polish is
square and well conditioned, so this solver factors a square matrix by LU and computes its
SVD only where the LU's condition estimate is above :data:`_CONDITION_LIMIT`; under vmap
the SVD then runs only if some member needs it (:func:`where_needed`). A matrix that is
not square always goes to the SVD.
"""

from typing import Any

import equinox.internal as eqxi
import jax.numpy as jnp
import jax.scipy as jsp
import lineax as lx
from lineax.internal import pack_structures, ravel_vector, transpose_packed_structures, unravel_solution

from magdesign.design._qp import where_needed

# A square matrix whose 1-norm condition number (from its LU) is above this goes to the
# SVD. Where the LU is taken the 2-norm condition is below n times this, far below the
# 1 / (2 n eps) at which lineax's SVD treats a matrix as rank-deficient (in float64, for
# n up to thousands; not in float32), so the SVD would have inverted every singular value
# too, and the two answers agree to the condition times eps.
_CONDITION_LIMIT = 1e8


class LUOrSVD(lx.AbstractLinearSolver):
    """LU for square, well-conditioned operators; the minimum-norm least-squares solution
    (as lineax's SVD, or ``scipy.linalg.lstsq``) for the others. Real float64 matrices
    (the design solver's; see :data:`_CONDITION_LIMIT`)."""

    def init(self, operator, options: dict[str, Any]):
        del options
        # linearised first: a Jacobian operator's matrix is then its linear map pushed
        # along the basis (vmap batches the tangent's program alone), where as_matrix()
        # would batch the function whole, the model inside it included, as JAX batches a
        # jitted call even where none of its inputs is batched (seconds more of tracing
        # for an axisymmetric design); the matrix is the same
        matrix = lx.linearise(operator).as_matrix()
        if jnp.iscomplexobj(matrix):
            raise TypeError("LUOrSVD solves real systems only")
        n_out, n_in = matrix.shape
        if n_out == n_in and n_in > 0:
            lu, pivots = jsp.linalg.lu_factor(matrix)
            inverse = jsp.linalg.lu_solve((lu, pivots), jnp.eye(n_in, dtype=matrix.dtype))
            condition = jnp.max(jnp.sum(jnp.abs(matrix), axis=0)) * jnp.max(jnp.sum(jnp.abs(inverse), axis=0))
            well = condition <= _CONDITION_LIMIT  # False where the LU is not finite (NaN)
            svd = where_needed(~well, _svd, matrix, _svd_shaped_zeros(matrix))
            factors = (lu, pivots, well, svd)
        else:
            factors = (None, None, None, _svd(matrix) if matrix.size else _svd_shaped_zeros(matrix))
        return factors, pack_structures(operator), eqxi.Static(False)

    def compute(self, state, vector, options: dict[str, Any]):
        del options
        (lu, pivots, well, (u, s, vt)), packed_structures, transposed = state
        vector = ravel_vector(vector, packed_structures)
        if transposed.value:
            u, vt = vt.T, u.T
        if s.size == 0:
            solution = jnp.zeros(vt.shape[1], vector.dtype)
        else:
            # lineax's SVD's cut-off (lineax._misc.resolve_rcond)
            kept = s > 2 * jnp.finfo(s.dtype).eps * max(u.shape[0], vt.shape[1]) * s[0]
            inverted = jnp.where(kept, 1.0 / jnp.where(kept, s, 1.0), 0.0)
            solution = vt.T @ (inverted * (u.T @ vector))
        if lu is not None:
            solution = jnp.where(
                well, jsp.linalg.lu_solve((lu, pivots), vector, trans=1 if transposed.value else 0), solution
            )
        return unravel_solution(solution, packed_structures), lx.RESULTS.successful, {}

    def transpose(self, state, options: dict[str, Any]):
        del options
        factors, packed_structures, transposed = state
        return (factors, transpose_packed_structures(packed_structures), eqxi.Static(not transposed.value)), {}

    def conj(self, state, options: dict[str, Any]):
        del options
        return state, {}  # real matrices only (init rejects complex ones)

    def assume_full_rank(self):
        return False


def _svd(matrix):
    """(u, s, vt), the thin SVD."""
    return jsp.linalg.svd(matrix, full_matrices=False)


def _svd_shaped_zeros(matrix):
    k = min(matrix.shape)
    zeros = lambda *shape: jnp.zeros(shape, matrix.dtype)  # noqa: E731
    return zeros(matrix.shape[0], k), zeros(k), zeros(k, matrix.shape[1])
