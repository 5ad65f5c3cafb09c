"""Cholesky factor of the axisymmetric dome's tangent: block tridiagonal, with one border.

The unknowns are ordered by meridian node rows (apex to base). An element spans three
node rows (2a, 2a + 1, 2a + 2), so grouping the rows as (0), (1, 2), (3, 4), ... couples
each group with its two neighbours only: the displacements' part of the matrix is block
tridiagonal, K = n_meridian + 1 blocks of b = 4 (2 n_wall + 1) unknowns (the apex row's
group padded to b with unknowns of their own, an identity). The plate travel, last,
couples with the u_z of the whole outer surface: a border row and column, eliminated
through its Schur complement. The diagonal blocks' factors are kept inverted, so that a
solve is matrix products only. A factor costs a few K b^3 instead of (K b)^3 / 3: one
factor and solve take 0.18 ms against a dense Cholesky's 0.77 ms on the default mesh
(2 x 16, 331 unknowns) and 1.2 ms against 19-21 ms on the 4 x 32 mesh (1171), on one
core, the two solutions agreeing to 1.2e-14 relative (benchmarks/mechanics.py).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np
from jax import lax


class Layout:
    """Static index tables of the blocks of a mesh with ``rows`` node rows (odd:
    2 n_meridian + 1) of ``cols`` nodes (2 unknowns each) and the plate travel last.

    ``source`` (K, b): the unknown at each place of the padded blocks (0 at a pad);
    ``pad`` (K, b): the padding places; ``place`` (n_dof,): each unknown's place in the
    flattened blocks.
    """

    def __init__(self, rows: int, cols: int):
        if rows % 2 != 1:
            raise ValueError(f"rows must be odd (2 n_meridian + 1), got {rows}")
        row_size = 2 * cols
        self.block = 2 * row_size
        self.count = (rows + 1) // 2
        padded = np.arange(self.count * self.block) - row_size  # the apex row's group padded in front
        self.pad = (padded < 0).reshape(self.count, self.block)
        self.source = np.where(padded < 0, 0, padded).reshape(self.count, self.block)
        self.place = np.arange(rows * row_size) + row_size


class Factor(eqx.Module):
    """The factor L L^T of one matrix: the inverses of L's diagonal blocks ``inverse``
    (K, b, b) and L's blocks under the diagonal ``below`` (K - 1, b, b), ``border`` (K, b)
    = A^-1 w for the travel's column w, and the Schur complement ``schur`` of the travel
    (NaN where the matrix is not positive definite, as the blocks are)."""

    inverse: jax.Array
    below: jax.Array
    border: jax.Array
    schur: jax.Array

    def finite(self):
        return jnp.all(jnp.isfinite(self.inverse)) & jnp.all(jnp.isfinite(self.below)) & jnp.isfinite(self.schur)


def _banded_solve(inverse, below, r):
    """A^-1 r for A = L L^T, L with the inverted diagonal blocks ``inverse`` and the
    ``below`` blocks; r (K, b)."""

    def forward(y, blocks):
        Li, C, rk = blocks
        y = Li @ (rk - C @ y)
        return y, y

    y0 = inverse[0] @ r[0]
    _, ys = lax.scan(forward, y0, (inverse[1:], below, r[1:]))
    ys = jnp.concatenate([y0[None], ys])

    def backward(x, blocks):
        Li, C, yk = blocks
        x = Li.T @ (yk - C.T @ x)
        return x, x

    x_last = inverse[-1].T @ ys[-1]
    _, xs = lax.scan(backward, x_last, (inverse[:-1], below, ys[:-1]), reverse=True)
    return jnp.concatenate([xs, x_last[None]])


class Blocks(eqx.Module):
    """The parts of a symmetric matrix M (n_dof + 1, n_dof + 1) that its factor reads: the
    diagonal blocks ``diagonal`` (K, b, b) (an identity at the padding), the blocks under
    them ``below`` (K - 1, b, b), the travel's column ``column`` (K, b) and its diagonal
    entry ``corner``."""

    diagonal: jax.Array
    below: jax.Array
    column: jax.Array
    corner: jax.Array


def blocks(layout: Layout, M) -> Blocks:
    """The :class:`Blocks` of M, whose displacement part has the layout's block
    tridiagonal pattern (entries outside it are ignored)."""
    s, pad = layout.source, layout.pad
    eye = np.eye(layout.block)
    diagonal = jnp.where(pad[:, :, None] | pad[:, None, :], eye * pad[:, :, None], M[s[:, :, None], s[:, None, :]])
    below = jnp.where(pad[1:, :, None] | pad[:-1, None, :], 0.0, M[s[1:, :, None], s[:-1, None, :]])
    return Blocks(diagonal, below, jnp.where(pad, 0.0, M[s, -1]), M[-1, -1])


def factor_blocks(layout: Layout, parts: Blocks, shift=0.0) -> Factor:
    """Cholesky factor of M + diag(``shift``) from M's :class:`Blocks`; ``shift`` a scalar
    or (n_dof + 1,). Not positive definite: a factor that is not :meth:`Factor.finite`.
    A loop that factors one matrix with several shifts holds only its blocks (copying
    the whole matrix into the loop made each factor 0.1 ms slower on the default mesh)."""
    eye = np.eye(layout.block)
    shift = jnp.broadcast_to(shift, (layout.place.shape[0] + 1,))
    diagonal = parts.diagonal + jnp.where(layout.pad, 0.0, shift[layout.source])[:, :, None] * eye

    def inverted_factor(D):
        return jsl.solve_triangular(jnp.linalg.cholesky(D), eye, lower=True)

    def step(Li, pair):
        D, E = pair
        C = E @ Li.T  # E L^-T: the factor's block under the diagonal
        Li = inverted_factor(D - C @ C.T)
        return Li, (Li, C)

    first = inverted_factor(diagonal[0])
    _, (rest, below) = lax.scan(step, first, (diagonal[1:], parts.below))
    inverse = jnp.concatenate([first[None], rest])
    border = _banded_solve(inverse, below, parts.column)
    schur = parts.corner + shift[-1] - jnp.sum(parts.column * border)
    return Factor(inverse, below, border, jnp.where(schur > 0, schur, jnp.nan))


def factor(layout: Layout, M, shift=0.0) -> Factor:
    """Cholesky factor of M + diag(``shift``) for the symmetric matrix M (n_dof + 1, n_dof + 1),
    whose displacement part has the layout's block tridiagonal pattern (entries outside
    it are ignored); ``shift`` a scalar or (n_dof + 1,). Not positive definite: a factor
    that is not :meth:`Factor.finite`."""
    return factor_blocks(layout, blocks(layout, M), shift)


def solve(layout: Layout, F: Factor, r):
    """M^-1 r for the factor F of M; r (n_dof + 1,)."""
    band = jnp.where(layout.pad, 0.0, r[layout.source])
    x = _banded_solve(F.inverse, F.below, band)
    travel = (r[-1] - jnp.sum(band * F.border)) / F.schur
    x = x - F.border * travel
    return jnp.append(x.ravel()[layout.place], travel)
