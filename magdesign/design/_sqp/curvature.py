"""Curvature at a stationary point: the least curvature on the active constraints' null
space, the directions to escape or probe along, their second-order corrections, the
faces of a cone of weakly active rows, and the room along a direction."""

import jax
import jax.numpy as jnp
import numpy as np

from magdesign._numerics import (
    TINY,
)
from magdesign.design._sqp.jet import _lagrangian_hessian
from magdesign.design._sqp.step import _active_matrix, _null_space, _Step


def _bend(jet, d, rows, fixed, *, sqp):
    """(n,) the second-order correction of a step d: the least-norm w with
    J_i w = -d^T H_i d / 2 on the constraint ``rows`` (m,) and w_j = 0 on the ``fixed``
    variables (n,), so that the arc y + a d + a^2 w keeps those rows where their
    linearisation puts them to second order in a (it follows a curved constraint)."""
    bent = jnp.where(rows, 0.5 * jnp.einsum("j,ijk,k->i", d, jet.H[1:], d), 0.0)
    matrix = _active_matrix(jet, rows, fixed)
    return -jnp.linalg.pinv(matrix, rtol=sqp.null_space_rtol) @ jnp.concatenate([bent, jnp.zeros(d.shape[0])])


def _strongly_active(step: _Step, bound_multipliers, n_targets, *, sqp):
    """((m,), (n,), (n,)) bool: the constraint rows that are strongly active at a step
    (every target, and the limits with a positive multiplier), and the variables on their
    lower and upper bounds with one."""
    lower, upper = jnp.split(bound_multipliers > sqp.active_multiplier, 2)
    return (step.multipliers > sqp.active_multiplier).at[:n_targets].set(True), lower, upper


def _least_curvature(jet, step: _Step, bound_multipliers, weight, approach, n_targets, face=None, *, sqp):
    """(e, v, w, u, wu): the least eigenvalue e of the Hessian of the Lagrangian on the
    null space of the strongly active constraints (targets, limits and bounds with a
    positive multiplier; and the rows (m,) and variables (n,) of ``face``, a pair of masks
    that :func:`_saddle_on_faces` holds too), relative to the Hessian's largest
    eigenvalue modulus (plus 1; about 2 where that null space is empty); the direction v
    (n,) to leave or probe the point along: e's eigenvector where e is negative beyond
    sqp.curvature_tol, else a combination of all the eigenvectors whose curvature is at
    most sqp.flat_curvature, weighted 1, 2, 3, ... (a probe along the least eigenvector
    alone misses y^3 inside a disk beside a variable x that the objective ignores: it
    probes along x); the probe's second direction u (n,): the ``approach`` (the
    direction the steps come from where they come only linearly, else 0) on that null
    space, 0 where it is v's. The steps' approach to y^3's 0 leaves y a curvature of
    6 y, small but above the flat one's; mixed into v, a curved direction's quadratic
    rise hides a flat one's cubic fall, so u is probed apart. v and u are scaled to a
    largest entry of 1; w and wu (n,) are their second-order corrections on those
    constraints (:func:`_bend`)."""
    hessian = _lagrangian_hessian(jet, step.multipliers, weight)
    strong, lower, upper = _strongly_active(step, bound_multipliers, n_targets, sqp=sqp)
    fixed = lower | upper
    if face is not None:
        strong, fixed = strong | face[0], fixed | face[1]
    vectors, null = _null_space(_active_matrix(jet, strong, fixed), sqp=sqp)
    basis = vectors * null  # (n, n), columns outside the null space zeroed
    size = 1.0 + jnp.max(jnp.abs(jnp.linalg.eigvalsh(hessian)))
    # the zeroed columns get curvature 2 size, so that only the null space's count
    eigenvalues, vectors = jnp.linalg.eigh(basis.T @ hessian @ basis + jnp.diag(jnp.where(null, 0.0, 2.0 * size)))
    flat = (eigenvalues <= sqp.flat_curvature * size) & (eigenvalues[0] >= -sqp.curvature_tol * size)
    weights = jnp.where(flat, 1.0 + jnp.arange(eigenvalues.shape[0]), 0.0).at[0].set(1.0)
    v = basis @ (vectors @ weights)
    v = v / jnp.maximum(jnp.max(jnp.abs(v)), TINY)
    u = basis @ (basis.T @ approach)
    u = u / jnp.maximum(jnp.max(jnp.abs(u)), TINY)
    parallel = jnp.abs(jnp.dot(u, v)) >= sqp.parallel * jnp.linalg.norm(u) * jnp.linalg.norm(v)
    u = jnp.where(parallel, 0.0, u)
    # both corrections from one pseudo-inverse: under vmap it depends on neither direction
    w, wu = jax.vmap(lambda d: _bend(jet, d, strong, fixed, sqp=sqp))(jnp.stack([v, u]))
    return eigenvalues[0] / size, v, w, u, wu


def _saddle_on_faces(jet, step: _Step, bound_multipliers, weight, y, y_max, n_targets, *, sqp):
    """(decided, found, e, v, w) for a stationary point whose direction of negative
    curvature on the strongly active constraints' null space cannot leave it on either
    side, first order, because rows and bounds met with no multiplier (weakly active)
    block it: whether some direction leaves the point on the cone those constraints leave
    (``found``), and of those the one of least curvature (:func:`_least_curvature`'s e,
    v, w; v signed to leave). At (1, 0), a vertex of min -(x^2 + y^2) on x + y <= 1 in the
    box [0, 1]^2, the QP gives x's upper bound the whole multiplier: y is free on the null
    space, with curvature -2, but x + y <= 1 blocks +y and y >= 0 blocks -y, and the
    vertex, a strict minimum, would otherwise read "not_a_minimum".

    The least curvature on that cone lies on one of its faces, where some of the weak rows
    are held too, along the least eigenvector there; so each face's least eigenvector,
    either way, is tried against every row and bound (:func:`_room`, :func:`_limits_room`).
    Where one leaves with negative curvature the point is a saddle, where the least that
    leaves is flat it is probed along it (-(y^2 + x^4) under y <= x^2 at 0: y blocked, x
    flat, and f falls as -x^4), and where none leaves it is a minimum on the cone. Faces of
    at most sqp.face_rows weak rows and bounds are gone through: with more, ``decided`` is
    False (where none is found, the point stays a saddle that cannot be left)."""
    n, m = y.shape[0], step.multipliers.shape[0]
    strong, lower, upper = _strongly_active(step, bound_multipliers, n_targets, sqp=sqp)
    # met with no slack (as _room and _limits_room read them) and no multiplier
    met = jnp.concatenate([jnp.zeros(n_targets, bool), jet.v[1 + n_targets :] >= 0.0])
    weak = jnp.concatenate([met & ~strong, ((y <= 0.0) & ~lower) | ((y >= y_max) & ~upper)])  # (m + n,)
    k = min(sqp.face_rows, m + n)
    chosen = jnp.argsort(~weak, stable=True)[:k]  # the weak ones first
    subsets = (np.arange(2**k)[:, None] >> np.arange(k)) & 1 == 1
    faces = jnp.zeros((2**k, m + n), bool).at[:, chosen].set(subsets & weak[chosen])
    e, v, w, _, _ = jax.vmap(
        lambda face: _least_curvature(
            jet, step, bound_multipliers, weight, jnp.zeros(n), n_targets, (face[:m], face[m:]), sqp=sqp
        )
    )(faces)
    v = jnp.where(faces[:, m:] | lower | upper, 0.0, v)  # a held variable's rounding must not block its bound

    def leaves(d):
        return (_room(y, d, y_max) > 0.0) & (_limits_room(jet, d, n_targets, sqp=sqp) > 0.0)

    ahead, back = jax.vmap(leaves)(v), jax.vmap(leaves)(-v)
    least = jnp.argmin(jnp.where(ahead | back, e, jnp.inf))
    v = jnp.where(ahead[least], 1.0, -1.0) * v[least]
    return jnp.sum(weak) <= sqp.face_rows, ahead[least] | back[least], e[least], v, w[least]


def _room_along(slack, rate):
    """The largest a in [0, 1] with slack - a rate >= 0 in every row that the direction
    raises (rate > 0); a row without slack (<= 0) leaves no room along it."""
    ratios = jnp.where(rate > 0, jnp.maximum(slack, 0.0) / jnp.where(rate > 0, rate, 1.0), jnp.inf)
    return jnp.clip(jnp.min(ratios, initial=jnp.inf), 0.0, 1.0)


def _room(y, v, y_max):
    """The largest a in [0, 1] with y + a v inside the box."""
    return _room_along(jnp.concatenate([y_max - y, y]), jnp.concatenate([v, -v]))


def _limits_room(jet, v, n_targets, *, sqp):
    """The largest a in [0, 1] with the limit rows (<= 0 when met), linearised at the jet, met
    at a v. A row whose rate along v is below sqp.null_space_rtol of its gradient's norm
    (times v's) counts as not raised: v lies in the null space of the strongly active rows,
    up to rounding, which must not choose a side."""
    gradients = jet.J[1 + n_targets :]
    rate = gradients @ v
    level = sqp.null_space_rtol * jnp.linalg.norm(gradients, axis=1) * jnp.linalg.norm(v)
    return _room_along(-jet.v[1 + n_targets :], jnp.where(rate > level, rate, 0.0))
