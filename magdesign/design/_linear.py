"""The linear solver of the design solver's polish: LU where it is safe, SVD where not.

lineax's SVD gives the minimum-norm solution where a Jacobian is rank-deficient (a
degenerate active set), which the polish needs; but a batched SVD of a tiny matrix costs
10-25 times its LU (LAPACK's gesdd against getrf: 26 against 1.1 ms for 3334 4 x 4
matrices on the 2-core development machine), and on the default design's batched sweep the
polish's SVDs took a quarter of the time. Almost every KKT Jacobian is square and well
conditioned, so this solver factors it by LU and runs the SVD only where the LU's pivots
say the matrix is near singular (:data:`_PIVOT_RTOL`), or the answer is not finite; under
vmap the SVD then runs only if some member needs it (:func:`where_needed`).
"""

from typing import Any

import equinox.internal as eqxi
import jax.numpy as jnp
import jax.scipy as jsp
import lineax as lx
from lineax.internal import pack_structures, ravel_vector, transpose_packed_structures, unravel_solution

from magdesign.design._qp import where_needed

# An LU whose smallest pivot is below this fraction of its largest goes to the SVD. Far
# above the SVD's own cut-off (2 eps n), so that every matrix the SVD would treat as rank-
# deficient goes there; below it the two agree to the matrix's condition times eps.
_PIVOT_RTOL = 1e-8


class LUOrSVD(lx.AbstractLinearSolver):
    """LU for square, well-conditioned operators; lineax's SVD (minimum norm, as
    ``scipy.linalg.lstsq``) for the others."""

    def init(self, operator, options: dict[str, Any]):
        del options
        matrix = operator.as_matrix()
        n_out, n_in = matrix.shape
        if n_out == n_in and n_in > 0:
            lu, pivots = jsp.linalg.lu_factor(matrix)
            diagonal = jnp.abs(jnp.diagonal(lu))
            well = jnp.all(jnp.isfinite(lu)) & (jnp.min(diagonal) > _PIVOT_RTOL * jnp.max(diagonal))
        else:
            lu, pivots, well = matrix, jnp.zeros(0, jnp.int32), jnp.asarray(False)
        return (matrix, lu, pivots, well), pack_structures(operator), eqxi.Static(False)

    def compute(self, state, vector, options: dict[str, Any]):
        del options
        (matrix, lu, pivots, well), packed_structures, transposed = state
        vector = ravel_vector(vector, packed_structures)
        if transposed.value:
            matrix = matrix.T
        if matrix.shape[0] == matrix.shape[1] and matrix.shape[0] > 0:
            by_lu = jsp.linalg.lu_solve((lu, pivots), vector, trans=1 if transposed.value else 0)
        else:
            by_lu = jnp.zeros(matrix.shape[1], vector.dtype)
        solution = where_needed(
            ~(well & jnp.all(jnp.isfinite(by_lu))),
            lambda operands: _minimum_norm(*operands),
            (matrix, vector),
            by_lu,
        )
        return unravel_solution(solution, packed_structures), lx.RESULTS.successful, {}

    def transpose(self, state, options: dict[str, Any]):
        del options
        factors, packed_structures, transposed = state
        return (factors, transpose_packed_structures(packed_structures), eqxi.Static(not transposed.value)), {}

    def conj(self, state, options: dict[str, Any]):
        del options
        return state, {}  # real matrices only (the design solver's are float64)

    def assume_full_rank(self):
        return False


def _minimum_norm(matrix, vector):
    """The minimum-norm least-squares solution, by lineax's SVD."""
    return lx.linear_solve(lx.MatrixLinearOperator(matrix), vector, lx.SVD()).value
