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

The tangent is assembled straight into these blocks (:class:`Blocks`, by gathers:
:func:`summing_tables`), never as the dense matrix, which on the default mesh is eight
times larger: XLA assembles a dense matrix by scatter-add, a serial loop on CPU, and a
batch of dense matrices leaves the cache.
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
    flattened blocks. A :class:`Blocks` flattened (:meth:`Blocks.from_flat`) holds the
    diagonal blocks, from ``below_start`` the blocks below them, from ``column_start`` the
    travel's column: ``flat_size`` entries.
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
        self.n_dof = rows * row_size
        b, K = self.block, self.count
        self.below_start, self.column_start = K * b * b, (2 * K - 1) * b * b
        self.flat_size = self.column_start + K * b

    def band(self, v):
        """The displacements of v (n_dof + 1,) in the blocks' places (K, b), 0 at the pads."""
        return jnp.where(self.pad, 0.0, v[self.source])

    def unband(self, x):
        """The displacements (n_dof,) held in the blocks' places x (K, b)."""
        return x.ravel()[self.place]

    def positions(self, i, j):
        """Where entry (i, j) of a symmetric matrix M (n_dof + 1, n_dof + 1) is kept in
        the flattened :class:`Blocks` (diagonal, below, column; see :meth:`Blocks.from_flat`),
        for index arrays i, j; -1 for an entry kept as its transpose or not kept (the
        corner, M[-1, -1], which :meth:`Blocks.from_flat` takes apart)."""
        i, j = np.asarray(i), np.asarray(j)
        b, n = self.block, self.n_dof
        travel_i, travel_j = i == n, j == n
        gi, pi = np.divmod(self.place[np.where(travel_i, 0, i)], b)
        gj, pj = np.divmod(self.place[np.where(travel_j, 0, j)], b)
        displacements = ~travel_i & ~travel_j
        position = np.full(i.shape, -1)
        on_diagonal = displacements & (gi == gj)
        position[on_diagonal] = ((gi * b + pi) * b + pj)[on_diagonal]
        below = displacements & (gi == gj + 1)
        position[below] = (self.below_start + (gj * b + pi) * b + pj)[below]
        column = ~travel_i & travel_j
        position[column] = (self.column_start + gi * b + pi)[column]
        if np.any(displacements & (np.abs(gi - gj) > 1)):
            raise ValueError("the matrix is not block tridiagonal in this layout")
        return position


def summing_tables(targets, count):
    """Index tables that sum entries into ``count`` slots with gathers: ``targets`` (n,)
    the slot of each entry (-1: dropped). Returns (table (m, k), spread (count,)): with
    src the entries and a 0 appended, the m slots that receive entries sum
    src[table] over its last axis, and with a 0 appended to those sums, sums[spread] is
    every slot. (XLA's scatter-add on CPU is a serial loop; see the module docstring.)"""
    targets = np.asarray(targets)
    kept = np.flatnonzero(targets >= 0)
    slots, counts = np.unique(targets[kept], return_counts=True)
    table = np.full((slots.size, max(counts.max(initial=0), 1)), targets.size)
    order = kept[np.argsort(targets[kept], kind="stable")]
    row = np.repeat(np.arange(slots.size), counts)
    table[row, np.arange(order.size) - np.repeat(np.cumsum(counts) - counts, counts)] = order
    spread = np.full(count, slots.size)
    spread[slots] = np.arange(slots.size)
    return table, spread


def gather_sum(tables, src):
    """The sums that :func:`summing_tables` ``tables`` describe, of the entries src (n,)."""
    table, spread = tables
    sums = jnp.sum(jnp.append(src, 0.0)[table], axis=-1)
    return jnp.append(sums, 0.0)[spread]


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

    @classmethod
    def from_flat(cls, layout: Layout, flat, corner) -> "Blocks":
        """The blocks kept in ``flat`` (layout.flat_size,: the places of
        :meth:`Layout.positions`), an identity added at the padding, and the ``corner``."""
        b, K = layout.block, layout.count
        diagonal = flat[: layout.below_start].reshape(K, b, b) + np.eye(b) * layout.pad[:, :, None]
        below = flat[layout.below_start : layout.column_start].reshape(K - 1, b, b)
        return cls(diagonal, below, flat[layout.column_start :].reshape(K, b), corner)

    @classmethod
    def zeros(cls, layout: Layout) -> "Blocks":
        """Blocks of the zero matrix (a loop's initial value)."""
        b, K = layout.block, layout.count
        return cls(jnp.zeros((K, b, b)), jnp.zeros((K - 1, b, b)), jnp.zeros((K, b)), jnp.zeros(()))

    def matvec(self, layout: Layout, v):
        """M v for v (n_dof + 1,)."""
        band = layout.band(v)
        from_above = jnp.einsum("kij,kj->ki", self.below, band[:-1])
        from_below = jnp.einsum("kji,kj->ki", self.below, band[1:])
        x = jnp.einsum("kij,kj->ki", self.diagonal, band) + self.column * v[-1]
        x = x + jnp.pad(from_above, ((1, 0), (0, 0))) + jnp.pad(from_below, ((0, 1), (0, 0)))
        return jnp.append(layout.unband(x), jnp.sum(self.column * band) + self.corner * v[-1])

    def restricted(self, layout: Layout, mask) -> "Blocks":
        """M on the unknowns (mask (n_dof + 1,) 1), the identity on the held values."""
        m, last = layout.band(mask), mask[-1]
        eye = np.eye(layout.block)
        return Blocks(
            self.diagonal * m[:, :, None] * m[:, None, :] + eye * (1 - m)[:, :, None],
            self.below * m[1:, :, None] * m[:-1, None, :],
            self.column * m * last,
            self.corner * last * last + (1 - last),
        )

    def diagonal_entries(self, layout: Layout):
        """M's diagonal (n_dof + 1,)."""
        return jnp.append(layout.unband(jnp.diagonal(self.diagonal, axis1=1, axis2=2)), self.corner)

    def last_column(self, layout: Layout):
        """M's last column (n_dof + 1,): the travel's."""
        return jnp.append(layout.unband(self.column), self.corner)

    def dense(self, layout: Layout):
        """M (n_dof + 1, n_dof + 1), for checks."""
        unit = np.eye(layout.n_dof + 1)
        return jax.vmap(lambda v: self.matvec(layout, v))(unit).T


def blocks(layout: Layout, M) -> Blocks:
    """The :class:`Blocks` of a dense M, whose displacement part has the layout's block
    tridiagonal pattern (entries outside it are ignored): for checks (the dome assembles
    its tangent as blocks)."""
    s, pad = layout.source, layout.pad
    eye = np.eye(layout.block)
    diagonal = jnp.where(pad[:, :, None] | pad[:, None, :], eye * pad[:, :, None], M[s[:, :, None], s[:, None, :]])
    below = jnp.where(pad[1:, :, None] | pad[:-1, None, :], 0.0, M[s[1:, :, None], s[:-1, None, :]])
    return Blocks(diagonal, below, layout.band(M[:, -1]), M[-1, -1])


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
    it are ignored), for checks; ``shift`` a scalar or (n_dof + 1,). Not positive definite: a factor
    that is not :meth:`Factor.finite`."""
    return factor_blocks(layout, blocks(layout, M), shift)


def solve(layout: Layout, F: Factor, r):
    """M^-1 r for the factor F of M; r (n_dof + 1,)."""
    band = layout.band(r)
    x = _banded_solve(F.inverse, F.below, band)
    travel = (r[-1] - jnp.sum(band * F.border)) / F.schur
    x = x - F.border * travel
    return jnp.append(layout.unband(x), travel)
