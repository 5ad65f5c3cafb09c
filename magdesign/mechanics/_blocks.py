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


def factor(layout: Layout, M, shift=0.0) -> Factor:
    """Cholesky factor of M + diag(``shift``) for the symmetric matrix M (n_dof + 1, n_dof + 1),
    whose displacement part has the layout's block tridiagonal pattern (entries outside
    it are ignored); ``shift`` a scalar or (n_dof + 1,). Not positive definite: a factor
    that is not :meth:`Factor.finite`."""
    s, pad = layout.source, layout.pad
    eye = np.eye(layout.block)
    shift = jnp.broadcast_to(shift, M.shape[:1])
    blocks = M[s[:, :, None], s[:, None, :]] + shift[s][:, :, None] * eye
    diagonal = jnp.where(pad[:, :, None] | pad[:, None, :], eye * pad[:, :, None], blocks)
    below = jnp.where(pad[1:, :, None] | pad[:-1, None, :], 0.0, M[s[1:, :, None], s[:-1, None, :]])

    def inverted_factor(D):
        return jsl.solve_triangular(jnp.linalg.cholesky(D), eye, lower=True)

    def step(Li, blocks):
        D, E = blocks
        C = E @ Li.T  # E L^-T: the factor's block under the diagonal
        Li = inverted_factor(D - C @ C.T)
        return Li, (Li, C)

    first = inverted_factor(diagonal[0])
    _, (rest, below) = lax.scan(step, first, (diagonal[1:], below))
    inverse = jnp.concatenate([first[None], rest])
    w = jnp.where(pad, 0.0, M[s, -1])
    border = _banded_solve(inverse, below, w)
    schur = M[-1, -1] + shift[-1] - jnp.sum(w * border)
    return Factor(inverse, below, border, jnp.where(schur > 0, schur, jnp.nan))


def solve(layout: Layout, F: Factor, r):
    """M^-1 r for the factor F of M; r (n_dof + 1,)."""
    band = jnp.where(layout.pad, 0.0, r[layout.source])
    x = _banded_solve(F.inverse, F.below, band)
    travel = (r[-1] - jnp.sum(band * F.border)) / F.schur
    x = x - F.border * travel
    return jnp.append(x.ravel()[layout.place], travel)
