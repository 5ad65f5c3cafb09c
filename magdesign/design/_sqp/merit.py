"""The exact l1 merit function of the line search: the weighted objective and the
violation of the scaled constraint rows."""

import jax.numpy as jnp


def _violation(c, n_targets, *, sqp):
    """l1 violation: |target rows| + positive parts of the limit rows, each less
    sqp.met_row: a row met to rounding counts as met, so that its rounding noise cannot
    drown the objective's decrease in the merit function near a solution."""
    targets, limits = jnp.abs(c[:n_targets]), c[n_targets:]
    return jnp.sum(jnp.maximum(targets - sqp.met_row, 0.0)) + jnp.sum(jnp.maximum(limits - sqp.met_row, 0.0))


def _merit_parts(jet, weight, n_targets, *, sqp):
    """(2,) the weighted objective and the l1 violation at a jet: the merit's two terms,
    which the line search's history keeps apart, to price them at a later penalty."""
    return jnp.stack([weight * jet.v[0], _violation(jet.v[1:], n_targets, sqp=sqp)])


def _merit(jet, weight, nu, n_targets, *, sqp):
    """The exact l1 merit function weight f + nu |violation|_1 at a jet."""
    return _priced(_merit_parts(jet, weight, n_targets, sqp=sqp), nu)


def _priced(parts, nu):
    """The merit of (..., 2) parts (:func:`_merit_parts`) at penalty nu."""
    return parts[..., 0] + nu * parts[..., 1]
