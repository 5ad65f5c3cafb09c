"""One step of the search: the quadratic subproblem at a point, its Hessian made
definite, its solution and active set, and the settled step of up to three solves."""

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from magdesign.design._qp import solve_qp
from magdesign.design._sqp.jet import _lagrangian_hessian, _pick
from magdesign.design._sqp.merit import _violation
from magdesign.design._sqp.sqp import SQP


class _Step(eqx.Module):
    """The subproblem's answer at a point: step d (n,), multipliers (m,) of the constraint
    rows and (n,) of the lower and upper bounds, the l1 violation of the linearised rows
    after the step, and the active set it implies."""

    d: Float[Array, " n"]
    multipliers: Float[Array, " m"]
    linear_violation: Float[Array, ""]
    active_limits: Bool[Array, " l"]
    at_lower: Bool[Array, " n"]
    at_upper: Bool[Array, " n"]
    qp_rows: Bool[Array, " mi"]


def _held_rows(step: _Step):
    """(m,) the constraint rows that a step holds as equations: every target, and the
    limits active there."""
    n_targets = step.multipliers.shape[0] - step.active_limits.shape[0]
    return jnp.concatenate([jnp.ones(n_targets, bool), step.active_limits])


def _no_slack_rows(n, n_targets, n_limits):
    """The first step's guess of the subproblem's active rows (see :func:`subproblem` for
    their order): every elastic slack at zero, no limit or bound active."""
    return jnp.arange(n_limits + 2 * n + 2 * n_targets + n_limits) >= n_limits + 2 * n


def subproblem_box(n, n_targets, n_limits):
    """(variables, signs): the :func:`subproblem`'s last rows of G as simple bounds
    (``box`` of :func:`solve_qp`): d <= ..., -d <= ..., -slack <= 0."""
    n_slack = 2 * n_targets + n_limits
    variables = np.concatenate([np.arange(n), np.arange(n), n + np.arange(n_slack)])
    return variables, np.concatenate([np.ones(n), -np.ones(n + n_slack)])


def subproblem(jet, y, y_max, multipliers, weight, n_targets, has_objective, radius=jnp.inf, *, sqp=None):
    """The QP of one step, (Q, q, A, b, G, h), holding no limit: :func:`_subproblem`'s first part
    (``sqp``: the solver's thresholds, default :class:`SQP`'s)."""
    sqp = SQP() if sqp is None else sqp
    return _subproblem(jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, None, sqp=sqp)[0]


def _definite(eigenvalues, size, *, sqp):
    """The moduli of a Hessian's ``eigenvalues``, those below sqp.kept_curvature times
    ``size`` raised to sqp.hessian_floor times it; and where they are kept."""
    moduli = jnp.abs(eigenvalues)
    kept = moduli >= sqp.kept_curvature * size
    return jnp.maximum(moduli, jnp.where(kept, 0.0, sqp.hessian_floor * size)), kept


def _subproblem(
    jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, held_limits, last_held=None, *, sqp
):
    """((Q, q, A, b, G, h), flat): the QP of one step at y for :func:`solve_qp`, and the
    flat directions of its Hessian (n, n) (the eigenvectors that get the floor; the
    others zeroed; those of the whole Hessian, where the dependent rows split it). The
    QP: minimise the quadratic model of the Lagrangian subject to the linearised rows and
    the box, each target row relaxed by two elastic slacks and each limit row by one,
    costing sqp.elastic per unit: w = (d, slack+, slack-, slack of limits),
    |d_i| <= radius. The quadratic term is the Hessian of the Lagrangian with its
    eigenvalues' moduli, those below sqp.hessian_floor (relative) raised to it, except
    one above sqp.kept_curvature, which stays (see there), and less the floor again
    along the gradients of the targets and of the ``held_limits`` (l,) (bool; None: none)
    projected onto the flat directions, where their linearisation fixes the step. Where the
    rows and bounds ``last_held`` ((m,), (n,) bool: those that the last step held; None:
    none) are dependent at a point that meets the rows, the Hessian on their null space
    is the Lagrangian's own there made definite (sqp.dependent_met). Without an
    objective it is |d|^2 / 2 (the minimum-norm step of Gauss-Newton)."""
    n = y.shape[0]
    c, J_c = jet.v[1:], jet.J[1:]
    m = c.shape[0]
    n_limits = m - n_targets
    lagrangian = _lagrangian_hessian(jet, multipliers, weight)
    eigenvalues, vectors = jnp.linalg.eigh(lagrangian)
    if has_objective:
        size = 1.0 + jnp.max(jnp.abs(eigenvalues))
        floor = sqp.hessian_floor * size
        moduli, kept = _definite(eigenvalues, size, sqp=sqp)
    else:
        moduli = jnp.maximum(jnp.abs(eigenvalues), 1.0)
    hessian = (vectors * moduli) @ vectors.T
    flat = vectors * ~kept if has_objective else jnp.zeros_like(vectors)
    fixing = J_c[:n_targets]  # the rows whose linearisation fixes the step
    if held_limits is not None:
        fixing = jnp.concatenate([fixing, jnp.where(held_limits[:, None], J_c[n_targets:], 0.0)])
    if has_objective and fixing.shape[0]:
        # The floor bounds steps along flat directions; along those that the targets'
        # linearisation fixes it only slows the step: x^4 on x + y = 1, where y is flat, gets
        # the floor's curvature along the target's line and crawls (steps of 1/130 of
        # Newton's, "max_steps_reached" 4e-4 from the minimum). Off: on the span of the
        # targets' gradients projected onto the flat directions (regularised by
        # sqp.null_space_rtol of their squared sizes, so that a gradient barely in the
        # flat directions removes barely any floor). Limits only where a first solve
        # holds them (see _settled_step): which hold is known only after the QP (with the
        # last step's active ones, hs106's polish ends 1.9e-10 outside a limit).
        spread = flat @ (flat.T @ fixing.T)  # (n, rows)
        gram = spread.T @ spread
        gram = gram + sqp.null_space_rtol * (1.0 + jnp.trace(gram)) * jnp.eye(fixing.shape[0])
        hessian = hessian - floor * spread @ jnp.linalg.solve(gram, spread.T)
    if has_objective and last_held is not None:
        # the cross terms between the null space and the rows' span are dropped (the rows'
        # linearisation fixes the step's part in their span)
        rows, fixed = last_held
        singular_vectors, null = _null_space(_active_matrix(jet, rows, fixed), sqp=sqp)
        # (n, n) each, the other's columns zeroed
        free, spanned = singular_vectors * null, singular_vectors * ~null
        dependent = (jnp.sum(rows) + jnp.sum(fixed) > jnp.sum(~null)) & jnp.any(null)
        dependent = dependent & (_violation(c, n_targets, sqp=sqp) <= sqp.dependent_met)
        reduced_eigenvalues, reduced_vectors = jnp.linalg.eigh(free.T @ lagrangian @ free)
        reduced = (reduced_vectors * _definite(reduced_eigenvalues, size, sqp=sqp)[0]) @ reduced_vectors.T
        split = free @ reduced @ free.T + spanned @ (spanned.T @ hessian @ spanned) @ spanned.T
        hessian = jnp.where(dependent, split, hessian)
    n_slack = 2 * n_targets + n_limits
    nw = n + n_slack
    Q = jnp.zeros((nw, nw)).at[:n, :n].set(hessian)
    q = jnp.concatenate([weight * jet.J[0], jnp.full(n_slack, sqp.elastic)])
    eye_t, eye_l = jnp.eye(n_targets), jnp.eye(n_limits)
    A = jnp.concatenate([J_c[:n_targets], -eye_t, eye_t, jnp.zeros((n_targets, n_limits))], axis=1)
    G = jnp.concatenate(
        [
            jnp.concatenate([J_c[n_targets:], jnp.zeros((n_limits, 2 * n_targets)), -eye_l], axis=1),
            jnp.concatenate([jnp.eye(n), jnp.zeros((n, n_slack))], axis=1),
            jnp.concatenate([-jnp.eye(n), jnp.zeros((n, n_slack))], axis=1),
            jnp.concatenate([jnp.zeros((n_slack, n)), -jnp.eye(n_slack)], axis=1),
        ]
    )
    h = jnp.concatenate([-c[n_targets:], jnp.minimum(y_max - y, radius), jnp.minimum(y, radius), jnp.zeros(n_slack)])
    return (Q, q, A, -c[:n_targets], G, h), flat


def _elastic(multipliers, *, sqp):
    """Where multipliers are priced at the elastic cost (sqp.elastic, to rounding): their
    rows' linearisation cannot be met."""
    return jnp.abs(multipliers) >= (1.0 - sqp.elastic_rounding) * sqp.elastic


def _last_held(last: _Step, bound_multipliers, *, sqp):
    """((m,), (n,)) bool: the rows and bounds that the ``last`` step held, with its bounds'
    multipliers (2n,); not the rows priced at the elastic cost (:func:`_elastic`)."""
    lower, upper = jnp.split(bound_multipliers, 2)
    fixed = (jnp.maximum(lower, upper) > sqp.active_multiplier) | last.at_lower | last.at_upper
    return _held_rows(last) & ~_elastic(last.multipliers, sqp=sqp), fixed


def _hessian_multipliers(jet, last: _Step, bound_multipliers, last_held, *, sqp):
    """(m,) the multipliers that weight the rows' Hessians in the next subproblem: the
    ``last`` step's, those of its active rows (``last_held``, :func:`_last_held`) replaced
    by the least-norm ones that give the same combination of gradients, with the bounds'
    (``bound_multipliers`` (2n,): lower, then upper; the radius's, where it limits the
    step). Where active rows are dependent, the QP's multipliers lie anywhere in an
    unbounded set, and its interior-point method ends half way to the elastic price: at
    hs108's x9 = 0, where the limits x3 x9 and -x5 x9 (both at least 0) and the bound x9
    at least 0 all have gradients along x9, two multipliers of 4e5 and 6e5 whose
    Hessians' cross terms, made definite, would give x3 and x5 curvatures of 1e6, and
    steps of 3e-7 that crawl to "max_steps_reached" at a point far from stationary. A row
    priced at the elastic cost keeps its multiplier: the linearisation cannot meet it, and its multiplier is the
    price of its violation, not a share of a combination (min x with a target x^2 of -1/2,
    projected with the radius's multiplier, would get a Hessian a billionth of the elastic
    one, and steps to and fro across the point of least violation)."""
    rows, fixed = last_held
    lower, upper = jnp.split(bound_multipliers, 2)
    matrix = _active_matrix(jet, rows, fixed)  # (m + n, n)
    weights = jnp.concatenate([jnp.where(rows, last.multipliers, 0.0), jnp.where(fixed, upper - lower, 0.0)])
    combined = matrix.T @ weights
    least = jnp.linalg.pinv(matrix.T, rtol=sqp.null_space_rtol) @ combined
    return jnp.where(rows, least[: last.multipliers.shape[0]], last.multipliers)


def _step(
    jet, y, y_max, last: _Step, bound_multipliers, weight, n_targets, has_objective, radius, held_limits=None, *, sqp
):
    """The :func:`subproblem`'s solution at y, its QP's rows active at the ``last`` step
    taken as a guess; the ``last`` step's multipliers, with its ``bound_multipliers``
    (2n,), weight the rows' Hessians (:func:`_hessian_multipliers`). The active set is
    the rows and bounds that the step ends on (within sqp.on_constraint without an
    objective, whose multipliers say nothing; with one, to rounding) and those with a
    positive multiplier (a bound only where it, not the ``radius``, limits the step).
    ``held_limits``: see :func:`_subproblem`. Returns the :class:`_Step`, the bounds'
    multipliers (2n,): lower, then upper (0 where below the bound's slack), and (l,) the
    limits that the step holds and whose gradients reach into the QP's flat directions,
    with whether its QP was solved (a finite answer)."""
    n = y.shape[0]
    c, J_c = jet.v[1:], jet.J[1:]
    n_limits = c.shape[0] - n_targets
    last_held = _last_held(last, bound_multipliers, sqp=sqp) if has_objective else None
    multipliers = (
        _hessian_multipliers(jet, last, bound_multipliers, last_held, sqp=sqp) if has_objective else last.multipliers
    )
    (Q, q, A, b, G, h), flat = _subproblem(
        jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, held_limits, last_held, sqp=sqp
    )
    qp = solve_qp(Q, q, A, b, G, h, guess=last.qp_rows, box=subproblem_box(n, n_targets, n_limits))
    # A subproblem that failed (non-finite) offers no step; the polish then judges the point.
    solved = jnp.all(jnp.isfinite(jnp.concatenate([qp.w, qp.y, qp.z])))
    qp = jax.tree.map(lambda a: jnp.where(jnp.isfinite(a), a, 0.0) if a.dtype == jnp.float64 else a, qp)
    d = qp.w[:n]
    # each (limit rows, upper bounds, lower bounds): their multipliers, and their slacks after the step
    (limit_multipliers, upper_multipliers, lower_multipliers), (limit_slack, upper_slack, lower_slack) = (
        jnp.split(rows[: n_limits + 2 * n], [n_limits, n_limits + n]) for rows in (qp.z, h - G @ qp.w)
    )
    linearised = c + J_c @ d
    # the limits and bounds that the step ends on, within ``near``
    ends_on = lambda near: (linearised[n_targets:] >= -near, y + d <= near, y + d >= y_max - near)  # noqa: E731
    if has_objective:
        # An inactive row's multiplier is the interior-point method's residual over the row's
        # slack, so a row counts as active only where its multiplier exceeds its slack too:
        # beside multipliers of 1e6 (hs055's six dependent targets) the lower bound of a
        # variable 0.017 inside the box gets a multiplier of 3e-8, which alone would make
        # the polish hold the variable on it.
        active = ((limit_multipliers, limit_slack), (lower_multipliers, lower_slack), (upper_multipliers, upper_slack))
        active_limits, at_lower, at_upper = (
            multiplier > jnp.maximum(sqp.active_multiplier, slack) for multiplier, slack in active
        )
        # (a bound's multiplier below its slack is no multiplier; where the radius, not the
        # bound, limits the step it is the radius's, kept for the Hessian's multipliers)
        lower_multipliers, upper_multipliers = (
            jnp.where(at_lower, lower_multipliers, 0.0),
            jnp.where(at_upper, upper_multipliers, 0.0),
        )
        at_lower, at_upper = at_lower & (y <= radius), at_upper & (y_max - y <= radius)
        # Those the step ends on to rounding are active too, with no multiplier (weakly): at
        # hs108's optimum x9 >= 0, x3 x9 >= 0 and -x5 x9 >= 0 hold so, and without them it
        # ends "limit_violated" (the polish, holding the rows with a multiplier, moves along
        # the optimum's manifold to x9 < 0). Within sqp.on_constraint, a limit 1e-10 below
        # a bound would bring the bound in too, and the polish would split the two.
        weakly = ends_on(sqp.rounded)
        held = (active_limits, at_lower, at_upper)
        active_limits, at_lower, at_upper = (strong | weak for strong, weak in zip(held, weakly))
    else:
        active_limits, at_lower, at_upper = ends_on(sqp.on_constraint)
    # The limits that the step holds by a multiplier (above sqp.held_multiplier, and not
    # priced at the elastic cost) and whose gradients reach into the flat directions:
    # _settled_step solves again with the floor off along them.
    J_l = J_c[n_targets:]
    reach = jnp.sum((flat.T @ J_l.T) ** 2, axis=0) > sqp.null_space_rtol * jnp.sum(J_l**2, axis=1)
    holds = (limit_multipliers > jnp.maximum(sqp.held_multiplier, limit_slack)) & ~_elastic(limit_multipliers, sqp=sqp)
    return (
        _Step(
            d=d,
            multipliers=jnp.concatenate([qp.y, limit_multipliers]),
            linear_violation=_violation(linearised, n_targets, sqp=sqp),
            active_limits=active_limits,
            at_lower=at_lower,
            at_upper=at_upper,
            qp_rows=qp.z > sqp.active_multiplier,
        ),
        jnp.concatenate([lower_multipliers, upper_multipliers]),
        (holds & reach, solved),
    )


class _Solves(NamedTuple):
    """:func:`_settled_step`'s loop: the latest step, its bounds' multipliers and whether
    its QP was solved; the solves made; the first solve's step and bounds' multipliers, the
    limits (l,) that it holds and whose gradients reach into the flat directions (which
    the second solve is to hold)."""

    step: _Step
    bound_multipliers: Array
    solved: Array
    trips: Array
    first: _Step
    first_bound_multipliers: Array
    held_limits: Array


def _settled_step(jet, y, y_max, last: _Step, bound_multipliers, weight, n_targets, radius, xtol, *, sqp):
    """:func:`_step` with an objective, solved up to three times: one QP in a loop, not
    three QPs, so the program holds one copy of the QP solver.

    A second solve, from the first (its multipliers weight the Hessian of the Lagrangian,
    as :func:`_hessian_multipliers` makes them, and its active rows are the QP's guess),
    runs where the first step is shorter than ``xtol``: the first solve's Hessian takes the
    ``last`` point's multipliers, which after an infeasible (elastic) subproblem are priced
    at sqp.elastic and then fall by orders of magnitude a step; a Hessian that large
    makes a step short at a point that is not stationary (hs063 would stop after 6 steps,
    "infeasible_target", with the objective's gradient 0.3 off the constraints' span).

    It also runs where the first step holds limits whose gradients reach into the flat
    directions (:func:`_step`), and takes the floor off along them, as along the targets.
    The floor makes the steps crawl to a degenerate minimum on a limit: min x^4 - (x + y)
    with x + y at most 1, from (1, -0.5), would end "max_steps_reached" after 100
    evaluations, a millionth and a half from (0, 1); hs097 and hs098 from their published
    start would end at another vertex. Off along a limit, the floor no longer bounds the
    step away from it, so the second step stands only where its QP was solved and it still
    holds those limits; else the first step does, or, where that was short, a third solve
    from the first with the floor along every limit."""

    def solve(solves):
        source = _pick(solves.trips == 0, (last, bound_multipliers), (solves.first, solves.first_bound_multipliers))
        held = solves.held_limits & (solves.trips == 1)
        step, multipliers, (reaching, solved) = _step(
            jet, y, y_max, *source, weight, n_targets, True, radius, held, sqp=sqp
        )
        first = solves.trips == 0
        return _Solves(
            step,
            multipliers,
            solved,
            solves.trips + 1,
            *_pick(first, (step, multipliers), (solves.first, solves.first_bound_multipliers)),
            jnp.where(first, reaching, solves.held_limits),
        )

    def dropped(solves):
        """The second solve failed, or its step left a limit that it was to hold."""
        left = jnp.any(solves.held_limits & ~solves.step.active_limits)
        return (solves.trips == 2) & jnp.any(solves.held_limits) & (left | ~solves.solved)

    def again(solves):
        short = jnp.max(jnp.abs(solves.first.d)) <= xtol
        second = (solves.trips == 1) & (short | jnp.any(solves.held_limits))
        return (solves.trips == 0) | second | (dropped(solves) & short)

    none = jnp.zeros_like(last.active_limits)
    start = _Solves(last, bound_multipliers, jnp.asarray(True), jnp.asarray(0), last, bound_multipliers, none)
    solves = jax.lax.while_loop(again, solve, start)
    first = (solves.first, solves.first_bound_multipliers)
    return _pick(dropped(solves), first, (solves.step, solves.bound_multipliers))


def _active_matrix(jet, rows, fixed):
    """(m + n, n) the gradients of the constraint ``rows`` (m,) and of the bounds of the
    ``fixed`` variables (n,), the others zeroed."""
    n = jet.J.shape[1]
    return jnp.concatenate([jnp.where(rows[:, None], jet.J[1:], 0.0), jnp.where(fixed[:, None], jnp.eye(n), 0.0)])


def _null_space(matrix, *, sqp):
    """((n, n), (n,)): the right singular vectors of an (m + n, n) ``matrix`` as columns,
    and which of them span its null space (singular value below sqp.null_space_rtol of
    the largest)."""
    _, singular, vt = jnp.linalg.svd(matrix, full_matrices=False)
    return vt.T, singular <= sqp.null_space_rtol * jnp.max(singular, initial=0.0)
