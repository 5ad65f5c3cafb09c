"""The design solver: bounded, constrained, exact, with implicit derivatives.

The search works on variables scaled to their bound width, y = (x - lower) / scale in
[0, y_max], the objective scaled to a unit gradient at the start (or, next to a
stationary point, to a gradient of DESIGN_GRADIENT_FLOOR times its Hessian) and each constraint row
to its target or limit. It has two stages:

1. sequential quadratic programming (ours): at each accepted point the quadratic model
   (the Hessian of the Lagrangian at the least-norm multipliers of the last step's active
   rows, made definite by taking its eigenvalues' moduli, the smallest raised to a floor
   except along the rows that fix the step: the targets, and the limits that a first
   solve holds, in a second solve, :func:`_settled_step`; where the last step's active
   rows are dependent at a point that nearly meets them, made definite on their null
   space apart from the rest) is
   minimised subject to the linearised targets and limits, the box and a radius (an
   inf-norm trust region: none until the line search first shortens a step, then the
   length it shortened the last one to, doubled after each whole step that reaches
   it), with elastic slacks so that the subproblem is always feasible
   (:mod:`magdesign.design._qp`); a backtracking line search on the exact l1 merit
   function f + nu |violation|_1 (nu at least twice the multipliers and 1, falling halfway
   towards that at each point: Powell's update) accepts the step, along a descent direction
   against the largest merit of the last few points (nonmonotone, so that a curved constraint's
   higher-order violation does not stop the steps where the objective is flat). A whole
   step that the merit rejects is tried once more along an arc bent by its second-order
   correction, which keeps the active constraints met to second order (from the
   Hessians the search has already; it overcomes the Maratos effect on curved
   constraints), and after a step that needed it the next is bent from its first try.
   Where the step vanishes (the subproblem solved once more with the Hessian at its own
   multipliers: the last point's, after an infeasible subproblem priced at the elastic
   cost, made steps vanish where the point was not stationary) the point is stationary;
   "successful" then also needs the reduced Hessian of the Lagrangian on the null space
   of the active constraints to be positive semi-definite, and a point that fails it is
   left along its direction of negative curvature, bent along the active constraints (at
   most DESIGN_ESCAPES times, then "not_a_minimum"). A stationary point whose least
   curvature is too small to tell (x^3 at 0), or which the steps reached only linearly
   (a stationary start too, which no steps reached), is probed on both sides of a
   direction that combines all its flat ones, then of the steps' approach
   (:func:`_least_curvature`), at a few lengths before it is accepted; a problem without
   objective has no minimum to confirm and is not probed.
   This stage is ours because it chooses the active set, which no JAX library does:
   optimistix's solvers take no constraints or bounds, and jaxopt's bounded QP (BoxOSQP)
   is too inexact for it (measured in benchmarks/design.py).
2. polish (optimistix, to a tenth of the tolerance): with the active set of the last subproblem, the KKT system
   (stationarity on the free variables, targets and active limits as equations, active
   bounds as fixed variables) is solved by optimistix's Newton (``optimistix.Newton``),
   stepped in the search's own loop once the search ends: optimistix's interactive use
   of a solver (its ``init``, ``step`` and ``terminate``; the steps and stopping rule of
   ``optimistix.root_find``), so that one place of the program evaluates the model and
   XLA compiles it once, where a separate root find compiled it again. Newton's first step
   is taken from the search's last jet, so the model is not evaluated again where the
   search has just evaluated it. A problem without objective is a feasibility problem,
   whose equations (targets, active limits, fixed variables; in general fewer than the
   unknowns) Newton through an SVD solves as Gauss-Newton with minimum-norm steps (see
   :func:`_newton`; ``optimistix.least_squares`` would differentiate grad |r|^2 / 2,
   which traces second derivatives: on the spin-valve example that took the compile of a
   batched solve from under 1 GB to over 11 GB). The linear systems go
   to :mod:`magdesign.design._linear`: LU where the Jacobian is square and well
   conditioned, else an SVD, whose minimum-norm step handles rank-deficient Jacobians
   (degenerate active sets, manifolds of solutions). The optimum's implicit derivatives
   (forward mode, with respect to the target values, limit bounds and fixed inputs) are
   those of ``optimistix.ImplicitAdjoint``, asked at the polished root with the model's
   jet from the polish's last evaluation there (:func:`_implicit_derivatives`).

Everything after the Python-level unpacking is one jitted, vmappable function of a fixed
problem structure; the outcome is a :class:`DesignStatus`, never an exception. The search
and the polish are one loop whose body evaluates the model's jet (values, Jacobian,
Hessians) once, at the point the search tries or at Newton's iterate, so XLA compiles one
copy of the model for both.
"""

import contextlib
import functools
import os
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import equinox as eqx
import equinox._errors as _equinox_errors
import jax
import jax.numpy as jnp
import numpy as np
import optimistix as optx
from jax.experimental import multihost_utils
from jax.sharding import Mesh, NamedSharding, PartitionSpec
from jaxtyping import Array, Bool, Float, Int
from tqdm import tqdm

from magdesign._numerics import (
    DESIGN_ACTIVE_MULTIPLIER,
    DESIGN_ATOL,
    DESIGN_BATCH_MEMORY,
    DESIGN_CHAIN,
    DESIGN_CHUNK,
    DESIGN_CURVATURE_TOL,
    DESIGN_DEPENDENT_MET,
    DESIGN_ELASTIC,
    DESIGN_ESCAPES,
    DESIGN_FLAT_CURVATURE,
    DESIGN_GRADIENT_FLOOR,
    DESIGN_HELD_MULTIPLIER,
    DESIGN_HESSIAN_FLOOR,
    DESIGN_KEPT_CURVATURE,
    DESIGN_NULL_SPACE_RTOL,
    DESIGN_ON_CONSTRAINT,
    DESIGN_POINT_SECONDS,
    DESIGN_POLISH_REACH,
    DESIGN_PROGRESS_STEPS,
    DESIGN_RTOL,
    DESIGN_SOLVABLE_RTOL,
    DESIGN_START_NUDGE,
    TINY,
    safe_div,
)
from magdesign._progress import stage
from magdesign._tracing import compiler_options, gc_paused, has_loops, traced_once
from magdesign.design._linear import LUOrSVD
from magdesign.design._qp import solve_qp, where_needed
from magdesign.design.problem import Problem, check_outputs, per_problem
from magdesign.design.report import STATUS_NAMES, DesignResult, DesignStatus, DesignSweep

# Armijo's sufficient-decrease fraction of the line search, and the shortest step it tries;
# a decrease of the merit counts only above _ROUNDING times (1 + |merit|).
_ARMIJO = 1e-4
_SHORTEST_STEP = 1e-12
# The step's radius (an inf-norm trust region on the subproblem, scaled variables): none
# until the line search first shortens a step, then the length it shortened the last one
# to, doubled after each whole step that reaches it, never below _RADIUS_FLOOR times the
# step tolerance.
_RADIUS_GROWTH, _RADIUS_FLOOR = 2.0, 10.0
# Without an objective, the radius grows only after a step that gained more than this
# fraction of the merit's decrease that its linearisation promised (see accept).
_GROWTH_GAIN = 0.75
# The line search compares a step's merit with the largest of the last _HISTORY accepted
# points' (nonmonotone, Grippo, Lampariello and Lucidi 1986).
_HISTORY = 8
# The merit's penalty starts at, and never falls below, this (the objective is scaled to a
# unit gradient at the start, so its multipliers are O(1)).
_PENALTY_FLOOR = 1.0
_NO_POINT = np.stack([np.full(_HISTORY, -np.inf), np.zeros(_HISTORY)], axis=1)  # an empty history
_ROUNDING = 1e-13
# Scaled constraint rows within this of their target or limit count as met in the merit
# function: far below the tolerance on them (DESIGN_RTOL), above their rounding.
_MET_ROW = 1e-13
# The step ends on a limit or bound (with an objective: weakly active) within this, its
# rounding: a limit 1e-13 of a box width inside a bound, taken for both, was held on both.
_ROUNDED = 1e-15
# A row's QP multiplier within this (relative) of DESIGN_ELASTIC is the elastic price: the
# row's slack is in use.
_ELASTIC_ROUNDING = 1e-6


class Settings(eqx.Module):
    """Solver settings: tolerances on scaled quantities and the steps allowed per stage."""

    rtol: Float[Array, ""]
    atol: Float[Array, ""]
    max_steps: int = eqx.field(static=True)


class CoreSolution(NamedTuple):
    """What the core returns (arrays; a leading batch axis under vmap). ``outputs`` holds
    the model outputs named by ``Problem.outputs``; m counts targets and limit rows. A
    NamedTuple, not an eqx.Module: the host builds one per solve, where constructing a
    Module took 25 of :func:`_unpack`'s 47 us."""

    x: Float[Array, " n"]
    multipliers: Float[Array, " m"]
    outputs: Float[Array, " k"]
    residuals: Float[Array, " m"]
    active_limits: Bool[Array, " l"]
    at_lower: Bool[Array, " n"]
    at_upper: Bool[Array, " n"]
    derivatives: Float[Array, "n m"]
    status: Int[Array, ""]
    steps: Int[Array, ""]


def problem_arrays(problem: Problem, xp=jnp):
    """(lower, upper, scale, start, theta) of a problem as float64 arrays.

    theta stacks the target values, then each limit row's bound, then the fixed inputs
    (SI): everything the optimum has implicit derivatives with respect to. ``xp`` is jnp
    inside traced code and numpy outside, where it is much cheaper than eager jnp.
    """
    stack = lambda values: xp.stack([xp.asarray(v, xp.float64) for v in values]) if values else xp.zeros((0,))  # noqa: E731
    variables = problem.variables
    theta = [t.value for t in problem.targets] + [getattr(problem.limits[i], side) for i, side in problem.limit_rows]
    theta += list(problem.fixed_values)
    return (
        stack([v.lower for v in variables]),
        stack([v.upper for v in variables]),
        stack([v.scale for v in variables]),
        stack([v.start for v in variables]),
        stack(theta),
    )


def _evaluate(problem: Problem, y, theta):
    """Model outputs, scaled constraints c (targets == 0, limit rows <= 0) and objective."""
    lower, _, scale, _, _ = problem_arrays(problem)
    x = lower + scale * y
    n_rows = len(problem.targets) + len(problem.limit_rows)
    fixed = {name: theta[n_rows + j] for j, name in enumerate(problem.fixed_names)}
    inputs = {v.name: x[i] for i, v in enumerate(problem.variables)} | fixed
    try:
        outputs = problem.model(inputs)
    except KeyError as error:
        name = error.args[0] if error.args else None
        if isinstance(name, str) and name not in inputs:
            raise ValueError(
                f"{name}: the model reads an input that is neither a variable nor fixed (inputs: {sorted(inputs)})"
            ) from error
        raise
    check_outputs(problem, outputs)
    return outputs, *_scaled_rows(problem, outputs, theta)


def _scaled_rows(problem: Problem, outputs, theta):
    """(c, f): the scaled constraint rows and the objective from the model's ``outputs``
    {name: value (SI)} and theta's target values and limit bounds."""
    n_targets = len(problem.targets)
    rows = [(outputs[t.output] - theta[k]) / t.scale for k, t in enumerate(problem.targets)]
    for k, (i, side) in enumerate(problem.limit_rows):
        limit = problem.limits[i]
        excess = outputs[limit.output] - theta[n_targets + k]
        rows.append((excess if side == "upper" else -excess) / limit.scale)
    # A problem without targets and limits gets one limit row that never binds (-1 <= 0):
    # with zero-size rows, jax 0.10 lowers some LAPACK calls of the solver as untyped
    # custom calls that XLA cannot run ("No registered implementation for untyped custom
    # call to lapack_dgesdd_ffi"). _core drops the row again.
    c = jnp.stack(rows) if rows else jnp.full((1,), -1.0)
    objective = problem.objective
    if objective is None:
        f = jnp.zeros(())
    else:
        f = (1.0 if objective.sense == "min" else -1.0) * objective.weight * outputs[objective.output]
    return c, f


class Jet(eqx.Module):
    """The model at one scaled point y, m constraint rows and n variables.

    ``v`` = (objective f, constraint rows c...) (1 + m,), scaled as in :func:`_evaluate`
    (f unweighted); ``J`` (1 + m, n) and ``H`` (1 + m, n, n) its first and second
    derivatives in y; ``outputs`` (k,) the model outputs named by ``Problem.outputs`` (SI).
    """

    v: Float[Array, " 1+m"]
    J: Float[Array, "1+m n"]
    H: Float[Array, "1+m n n"]
    outputs: Float[Array, " k"]


@traced_once
def _values(problem, y, theta):
    """(v, outputs) at y: (objective, constraint rows...) and the named outputs."""
    outputs, c, f = _evaluate(problem, y, theta)
    return jnp.concatenate([f[None], c]), jnp.stack([outputs[name] for name in problem.outputs])


@traced_once
def _first_jet(problem, y, theta):
    """(J, (v, outputs)) at y: the model's first derivatives, by forward mode."""

    def values(y):
        v, outputs = _values(problem, y, theta)
        return v, (v, outputs)

    return jax.jacfwd(values, has_aux=True)(y)


@traced_once
def _jet(problem, y, theta) -> Jet:
    """The :class:`Jet` at y from one trace of the model (forward over forward mode)."""
    if problem.objective is None:
        # Without an objective the search's Hessian is the floor alone (see _step), so
        # tracing no second derivatives keeps models with costly kernels quick to compile.
        J, (v, outputs) = _first_jet(problem, y, theta)
        return Jet(v, J, jnp.zeros((*J.shape, y.shape[0])), outputs)

    def first(y):
        J, (v, outputs) = _first_jet(problem, y, theta)
        return J, (J, v, outputs)

    H, (J, v, outputs) = jax.jacfwd(first, has_aux=True)(y)
    return Jet(v, J, H, outputs)


def _lagrangian_hessian(jet, multipliers, weight):
    """(n, n) Hessian of weight f + multipliers . c in y."""
    return weight * jet.H[0] + jnp.einsum("i,ijk->jk", multipliers, jet.H[1:])


def _violation(c, n_targets):
    """l1 violation: |target rows| + positive parts of the limit rows, each less
    _MET_ROW: a row met to rounding counts as met, so that its rounding noise cannot
    drown the objective's decrease in the merit function near a solution."""
    targets, limits = jnp.abs(c[:n_targets]), c[n_targets:]
    return jnp.sum(jnp.maximum(targets - _MET_ROW, 0.0)) + jnp.sum(jnp.maximum(limits - _MET_ROW, 0.0))


def _merit_parts(jet, weight, n_targets):
    """(2,) the weighted objective and the l1 violation at a jet: the merit's two terms,
    which the line search's history keeps apart, to price them at a later penalty."""
    return jnp.stack([weight * jet.v[0], _violation(jet.v[1:], n_targets)])


def _merit(jet, weight, nu, n_targets):
    """The exact l1 merit function weight f + nu |violation|_1 at a jet."""
    return _priced(_merit_parts(jet, weight, n_targets), nu)


def _priced(parts, nu):
    """The merit of (..., 2) parts (:func:`_merit_parts`) at penalty nu."""
    return parts[..., 0] + nu * parts[..., 1]


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


def subproblem(jet, y, y_max, multipliers, weight, n_targets, has_objective, radius=jnp.inf):
    """The QP of one step, (Q, q, A, b, G, h), holding no limit: :func:`_subproblem`'s first part."""
    return _subproblem(jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, None)[0]


def _definite(eigenvalues, size):
    """The moduli of a Hessian's ``eigenvalues``, those below DESIGN_KEPT_CURVATURE times
    ``size`` raised to DESIGN_HESSIAN_FLOOR times it; and where they were kept."""
    moduli = jnp.abs(eigenvalues)
    kept = moduli >= DESIGN_KEPT_CURVATURE * size
    return jnp.maximum(moduli, jnp.where(kept, 0.0, DESIGN_HESSIAN_FLOOR * size)), kept


def _subproblem(jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, held_limits, last_held=None):
    """((Q, q, A, b, G, h), flat): the QP of one step at y for :func:`solve_qp`, and the
    flat directions of its Hessian (n, n) (the eigenvectors that got the floor; the
    others zeroed; those of the whole Hessian, where the dependent rows split it). The
    QP: minimise the quadratic model of the Lagrangian subject to the linearised rows and
    the box, each target row relaxed by two elastic slacks and each limit row by one,
    costing DESIGN_ELASTIC per unit: w = (d, slack+, slack-, slack of limits),
    |d_i| <= radius. The quadratic term is the Hessian of the Lagrangian with its
    eigenvalues' moduli, those below DESIGN_HESSIAN_FLOOR (relative) raised to it, except
    one above DESIGN_KEPT_CURVATURE, which stays (see there), and less the floor again
    along the gradients of the targets and of the ``held_limits`` (l,) (bool; None: none)
    projected onto the flat directions, where their linearisation fixes the step. Where the
    rows and bounds ``last_held`` ((m,), (n,) bool: those that the last step held; None:
    none) are dependent at a point that meets the rows, the Hessian on their null space
    is the Lagrangian's own there made definite (DESIGN_DEPENDENT_MET). Without an
    objective it is |d|^2 / 2 (the minimum-norm step of Gauss-Newton)."""
    n = y.shape[0]
    c, J_c = jet.v[1:], jet.J[1:]
    m = c.shape[0]
    n_limits = m - n_targets
    lagrangian = _lagrangian_hessian(jet, multipliers, weight)
    eigenvalues, vectors = jnp.linalg.eigh(lagrangian)
    if has_objective:
        size = 1.0 + jnp.max(jnp.abs(eigenvalues))
        floor = DESIGN_HESSIAN_FLOOR * size
        moduli, kept = _definite(eigenvalues, size)
    else:
        moduli = jnp.maximum(jnp.abs(eigenvalues), 1.0)
    hessian = (vectors * moduli) @ vectors.T
    flat = vectors * ~kept if has_objective else jnp.zeros_like(vectors)
    fixing = J_c[:n_targets]  # the rows whose linearisation fixes the step
    if held_limits is not None:
        fixing = jnp.concatenate([fixing, jnp.where(held_limits[:, None], J_c[n_targets:], 0.0)])
    if has_objective and fixing.shape[0]:
        # The floor bounds steps along flat directions; along those that the targets'
        # linearisation fixes it only slows the step: x^4 on x + y = 1, where y is flat, got
        # the floor's curvature along the target's line and crawled (steps of 1/130 of
        # Newton's, "max_steps_reached" 4e-4 from the minimum). Off: on the span of the
        # targets' gradients projected onto the flat directions (regularised by
        # DESIGN_NULL_SPACE_RTOL of their squared sizes, so that a gradient barely in the
        # flat directions removes barely any floor). Limits only where a first solve
        # holds them (see _settled_step): which hold is known only after the QP (with the
        # last step's active ones, hs106's polish ended 1.9e-10 outside a limit).
        spread = flat @ (flat.T @ fixing.T)  # (n, rows)
        gram = spread.T @ spread
        gram = gram + DESIGN_NULL_SPACE_RTOL * (1.0 + jnp.trace(gram)) * jnp.eye(fixing.shape[0])
        hessian = hessian - floor * spread @ jnp.linalg.solve(gram, spread.T)
    if has_objective and last_held is not None:
        # the cross terms between the null space and the rows' span are dropped (the rows'
        # linearisation fixes the step's part in their span)
        rows, fixed = last_held
        singular_vectors, null = _null_space(_active_matrix(jet, rows, fixed))
        # (n, n) each, the other's columns zeroed
        free, spanned = singular_vectors * null, singular_vectors * ~null
        dependent = (jnp.sum(rows) + jnp.sum(fixed) > jnp.sum(~null)) & jnp.any(null)
        dependent = dependent & (_violation(c, n_targets) <= DESIGN_DEPENDENT_MET)
        reduced_eigenvalues, reduced_vectors = jnp.linalg.eigh(free.T @ lagrangian @ free)
        reduced = (reduced_vectors * _definite(reduced_eigenvalues, size)[0]) @ reduced_vectors.T
        split = free @ reduced @ free.T + spanned @ (spanned.T @ hessian @ spanned) @ spanned.T
        hessian = jnp.where(dependent, split, hessian)
    n_slack = 2 * n_targets + n_limits
    nw = n + n_slack
    Q = jnp.zeros((nw, nw)).at[:n, :n].set(hessian)
    q = jnp.concatenate([weight * jet.J[0], jnp.full(n_slack, DESIGN_ELASTIC)])
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


def _elastic(multipliers):
    """Where multipliers are priced at the elastic cost (DESIGN_ELASTIC, to rounding): their
    rows' linearisation cannot be met."""
    return jnp.abs(multipliers) >= (1.0 - _ELASTIC_ROUNDING) * DESIGN_ELASTIC


def _last_held(last: _Step, bound_multipliers):
    """((m,), (n,)) bool: the rows and bounds that the ``last`` step held, with its bounds'
    multipliers (2n,); not the rows priced at the elastic cost (:func:`_elastic`)."""
    lower, upper = jnp.split(bound_multipliers, 2)
    fixed = (jnp.maximum(lower, upper) > DESIGN_ACTIVE_MULTIPLIER) | last.at_lower | last.at_upper
    return _held_rows(last) & ~_elastic(last.multipliers), fixed


def _hessian_multipliers(jet, last: _Step, bound_multipliers, last_held):
    """(m,) the multipliers that weight the rows' Hessians in the next subproblem: the
    ``last`` step's, those of its active rows (``last_held``, :func:`_last_held`) replaced
    by the least-norm ones that give the same combination of gradients, with the bounds'
    (``bound_multipliers`` (2n,): lower, then upper; the radius's, where it limits the
    step). Where active rows are dependent, the QP's multipliers lie anywhere in an
    unbounded set, and its interior-point method ends half way to the elastic price: at
    hs108's x9 = 0, where the limits x3 x9 and -x5 x9 (both at least 0) and the bound x9
    at least 0 all have gradients along x9, two multipliers of 4e5 and 6e5 whose
    Hessians' cross terms, made definite, gave x3 and x5 curvatures of 1e6; steps of 3e-7 crawled to
    "max_steps_reached" at a point far from stationary. A row priced at the elastic cost
    keeps its multiplier: the linearisation cannot meet it, and its multiplier is the
    price of its violation, not a share of a combination (min x with a target x^2 of -1/2,
    projected with the radius's multiplier, got a Hessian a billionth of the elastic one,
    and steps to and fro across the point of least violation)."""
    rows, fixed = last_held
    lower, upper = jnp.split(bound_multipliers, 2)
    matrix = _active_matrix(jet, rows, fixed)  # (m + n, n)
    weights = jnp.concatenate([jnp.where(rows, last.multipliers, 0.0), jnp.where(fixed, upper - lower, 0.0)])
    combined = matrix.T @ weights
    least = jnp.linalg.pinv(matrix.T, rtol=DESIGN_NULL_SPACE_RTOL) @ combined
    return jnp.where(rows, least[: last.multipliers.shape[0]], last.multipliers)


def _step(jet, y, y_max, last: _Step, bound_multipliers, weight, n_targets, has_objective, radius, held_limits=None):
    """The :func:`subproblem`'s solution at y, its QP's rows active at the ``last`` step
    taken as a guess; the ``last`` step's multipliers, with its ``bound_multipliers``
    (2n,), weight the rows' Hessians (:func:`_hessian_multipliers`). The active set is
    the rows and bounds that the step ends on (within DESIGN_ON_CONSTRAINT without an
    objective, whose multipliers say nothing; with one, to rounding) and those with a
    positive multiplier (a bound only where it, not the ``radius``, limits the step).
    ``held_limits``: see :func:`_subproblem`. Returns the :class:`_Step`, the bounds'
    multipliers (2n,): lower, then upper (0 where below the bound's slack), and (l,) the
    limits that the step holds and whose gradients reach into the QP's flat directions,
    with whether its QP was solved (a finite answer)."""
    n = y.shape[0]
    c, J_c = jet.v[1:], jet.J[1:]
    n_limits = c.shape[0] - n_targets
    last_held = _last_held(last, bound_multipliers) if has_objective else None
    multipliers = _hessian_multipliers(jet, last, bound_multipliers, last_held) if has_objective else last.multipliers
    (Q, q, A, b, G, h), flat = _subproblem(
        jet, y, y_max, multipliers, weight, n_targets, has_objective, radius, held_limits, last_held
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
        # variable 0.017 inside the box got a multiplier of 3e-8, and the polish held the
        # variable on it.
        active = ((limit_multipliers, limit_slack), (lower_multipliers, lower_slack), (upper_multipliers, upper_slack))
        active_limits, at_lower, at_upper = (
            multiplier > jnp.maximum(DESIGN_ACTIVE_MULTIPLIER, slack) for multiplier, slack in active
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
        # ended "limit_violated" (the polish, holding the rows with a multiplier, moved along
        # the optimum's manifold to x9 < 0). Within DESIGN_ON_CONSTRAINT, a limit 1e-10 below
        # a bound brought the bound in too, and the polish split the two.
        weakly = ends_on(_ROUNDED)
        held = (active_limits, at_lower, at_upper)
        active_limits, at_lower, at_upper = (strong | weak for strong, weak in zip(held, weakly))
    else:
        active_limits, at_lower, at_upper = ends_on(DESIGN_ON_CONSTRAINT)
    # The limits that the step holds by a multiplier (above DESIGN_HELD_MULTIPLIER, and not
    # priced at the elastic cost) and whose gradients reach into the flat directions:
    # _settled_step solves again with the floor off along them.
    J_l = J_c[n_targets:]
    reach = jnp.sum((flat.T @ J_l.T) ** 2, axis=0) > DESIGN_NULL_SPACE_RTOL * jnp.sum(J_l**2, axis=1)
    holds = (limit_multipliers > jnp.maximum(DESIGN_HELD_MULTIPLIER, limit_slack)) & ~_elastic(limit_multipliers)
    return (
        _Step(
            d=d,
            multipliers=jnp.concatenate([qp.y, limit_multipliers]),
            linear_violation=_violation(linearised, n_targets),
            active_limits=active_limits,
            at_lower=at_lower,
            at_upper=at_upper,
            qp_rows=qp.z > DESIGN_ACTIVE_MULTIPLIER,
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


def _settled_step(jet, y, y_max, last: _Step, bound_multipliers, weight, n_targets, radius, xtol):
    """:func:`_step` with an objective, solved up to three times: one QP in a loop, not
    three QPs, so the program stays the size it was.

    A second solve, from the first (its multipliers weight the Hessian of the Lagrangian,
    as :func:`_hessian_multipliers` makes them, and its active rows are the QP's guess),
    runs where the first step is shorter than ``xtol``: the first solve's Hessian takes the
    ``last`` point's multipliers, which after an infeasible (elastic) subproblem are priced
    at DESIGN_ELASTIC and then fall by orders of magnitude a step; a Hessian that large
    makes a step short at a point that is not stationary (hs063 stopped after 6 steps,
    "infeasible_target", with the objective's gradient 0.3 off the constraints' span).

    It also runs where the first step holds limits whose gradients reach into the flat
    directions (:func:`_step`), and takes the floor off along them, as along the targets.
    The floor made the steps crawl to a degenerate minimum on a limit: min x^4 - (x + y)
    with x + y at most 1, from (1, -0.5), ended "max_steps_reached" after 100 evaluations,
    a millionth and a half from (0, 1); hs097 and hs098 from their published start ended at
    another vertex. Off along a limit, the floor no longer bounds the step away from it, so
    the second step stands only where its QP was solved and it still holds those limits;
    else the first step does, or, where that was short, a third solve as the second was
    before (from the first, with the floor)."""

    def solve(solves):
        source = _pick(solves.trips == 0, (last, bound_multipliers), (solves.first, solves.first_bound_multipliers))
        held = solves.held_limits & (solves.trips == 1)
        step, multipliers, (reaching, solved) = _step(jet, y, y_max, *source, weight, n_targets, True, radius, held)
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


def _null_space(matrix):
    """((n, n), (n,)): the right singular vectors of an (m + n, n) ``matrix`` as columns,
    and which of them span its null space (singular value below DESIGN_NULL_SPACE_RTOL of
    the largest)."""
    _, singular, vt = jnp.linalg.svd(matrix, full_matrices=False)
    return vt.T, singular <= DESIGN_NULL_SPACE_RTOL * jnp.max(singular, initial=0.0)


def _bend(jet, d, rows, fixed):
    """(n,) the second-order correction of a step d: the least-norm w with
    J_i w = -d^T H_i d / 2 on the constraint ``rows`` (m,) and w_j = 0 on the ``fixed``
    variables (n,), so that the arc y + a d + a^2 w keeps those rows where their
    linearisation puts them to second order in a (it follows a curved constraint)."""
    bent = jnp.where(rows, 0.5 * jnp.einsum("j,ijk,k->i", d, jet.H[1:], d), 0.0)
    matrix = _active_matrix(jet, rows, fixed)
    return -jnp.linalg.pinv(matrix, rtol=DESIGN_NULL_SPACE_RTOL) @ jnp.concatenate([bent, jnp.zeros(d.shape[0])])


def _strongly_active(step: _Step, bound_multipliers, n_targets):
    """((m,), (n,), (n,)) bool: the constraint rows that are strongly active at a step
    (every target, and the limits with a positive multiplier), and the variables on their
    lower and upper bounds with one."""
    lower, upper = jnp.split(bound_multipliers > DESIGN_ACTIVE_MULTIPLIER, 2)
    return (step.multipliers > DESIGN_ACTIVE_MULTIPLIER).at[:n_targets].set(True), lower, upper


def _least_curvature(jet, step: _Step, bound_multipliers, weight, approach, n_targets, face=None):
    """(e, v, w, u, wu): the least eigenvalue e of the Hessian of the Lagrangian on the
    null space of the strongly active constraints (targets, limits and bounds with a
    positive multiplier; and the rows (m,) and variables (n,) of ``face``, a pair of masks
    that :func:`_saddle_on_faces` holds too), relative to the Hessian's largest
    eigenvalue modulus (plus 1; about 2 where that null space is empty); the direction v
    (n,) to leave or probe the point along: e's eigenvector where e is negative beyond
    DESIGN_CURVATURE_TOL, else a combination of all the eigenvectors whose curvature is at
    most DESIGN_FLAT_CURVATURE, weighted 1, 2, 3, ... (a probe along the least eigenvector
    alone missed y^3 inside a disk beside a variable x that the objective ignores: it
    probed along x); the probe's second direction u (n,): the ``approach`` (the
    direction the steps came from where they came only linearly, else 0) on that null
    space, 0 where it is v's. The steps' approach to y^3's 0 leaves y a curvature of
    6 y, small but above the flat one's; mixed into v, a curved direction's quadratic
    rise hid a flat one's cubic fall, so u is probed apart. v and u are scaled to a
    largest entry of 1; w and wu (n,) are their second-order corrections on those
    constraints (:func:`_bend`)."""
    hessian = _lagrangian_hessian(jet, step.multipliers, weight)
    strong, lower, upper = _strongly_active(step, bound_multipliers, n_targets)
    fixed = lower | upper
    if face is not None:
        strong, fixed = strong | face[0], fixed | face[1]
    vectors, null = _null_space(_active_matrix(jet, strong, fixed))
    basis = vectors * null  # (n, n), columns outside the null space zeroed
    size = 1.0 + jnp.max(jnp.abs(jnp.linalg.eigvalsh(hessian)))
    # the zeroed columns get curvature 2 size, so that only the null space's count
    eigenvalues, vectors = jnp.linalg.eigh(basis.T @ hessian @ basis + jnp.diag(jnp.where(null, 0.0, 2.0 * size)))
    flat = (eigenvalues <= DESIGN_FLAT_CURVATURE * size) & (eigenvalues[0] >= -DESIGN_CURVATURE_TOL * size)
    weights = jnp.where(flat, 1.0 + jnp.arange(eigenvalues.shape[0]), 0.0).at[0].set(1.0)
    v = basis @ (vectors @ weights)
    v = v / jnp.maximum(jnp.max(jnp.abs(v)), TINY)
    u = basis @ (basis.T @ approach)
    u = u / jnp.maximum(jnp.max(jnp.abs(u)), TINY)
    parallel = jnp.abs(jnp.dot(u, v)) >= _PARALLEL * jnp.linalg.norm(u) * jnp.linalg.norm(v)
    u = jnp.where(parallel, 0.0, u)
    # both corrections from one pseudo-inverse: under vmap it depends on neither direction
    w, wu = jax.vmap(lambda d: _bend(jet, d, strong, fixed))(jnp.stack([v, u]))
    return eigenvalues[0] / size, v, w, u, wu


# The most weakly active rows and bounds whose faces :func:`_saddle_on_faces` goes through.
_FACE_ROWS = 4


def _saddle_on_faces(jet, step: _Step, bound_multipliers, weight, y, y_max, n_targets):
    """(decided, found, e, v, w) for a stationary point whose direction of negative
    curvature on the strongly active constraints' null space cannot leave it on either
    side, first order, because rows and bounds met with no multiplier (weakly active)
    block it: whether some direction leaves the point on the cone those constraints leave
    (``found``), and of those the one of least curvature (:func:`_least_curvature`'s e,
    v, w; v signed to leave). At (1, 0), a vertex of min -(x^2 + y^2) on x + y <= 1 in the
    box [0, 1]^2, the QP gives x's upper bound the whole multiplier: y is free on the null
    space, with curvature -2, but x + y <= 1 blocks +y and y >= 0 blocks -y, and the
    vertex, a strict minimum, was called "not_a_minimum".

    The least curvature on that cone lies on one of its faces, where some of the weak rows
    are held too, along the least eigenvector there; so each face's least eigenvector,
    either way, is tried against every row and bound (:func:`_room`, :func:`_limits_room`).
    Where one leaves with negative curvature the point is a saddle, where the least that
    leaves is flat it is probed along it (-(y^2 + x^4) under y <= x^2 at 0: y blocked, x
    flat, and f falls as -x^4), and where none leaves it is a minimum on the cone. Faces of
    at most _FACE_ROWS weak rows and bounds are gone through: with more, ``decided`` is
    False (where none is found, the point stays a saddle that cannot be left)."""
    n, m = y.shape[0], step.multipliers.shape[0]
    strong, lower, upper = _strongly_active(step, bound_multipliers, n_targets)
    # met with no slack (as _room and _limits_room read them) and no multiplier
    met = jnp.concatenate([jnp.zeros(n_targets, bool), jet.v[1 + n_targets :] >= 0.0])
    weak = jnp.concatenate([met & ~strong, ((y <= 0.0) & ~lower) | ((y >= y_max) & ~upper)])  # (m + n,)
    k = min(_FACE_ROWS, m + n)
    chosen = jnp.argsort(~weak, stable=True)[:k]  # the weak ones first
    subsets = (np.arange(2**k)[:, None] >> np.arange(k)) & 1 == 1
    faces = jnp.zeros((2**k, m + n), bool).at[:, chosen].set(subsets & weak[chosen])
    e, v, w, _, _ = jax.vmap(
        lambda face: _least_curvature(
            jet, step, bound_multipliers, weight, jnp.zeros(n), n_targets, (face[:m], face[m:])
        )
    )(faces)
    v = jnp.where(faces[:, m:] | lower | upper, 0.0, v)  # a held variable's rounding must not block its bound

    def leaves(d):
        return (_room(y, d, y_max) > 0.0) & (_limits_room(jet, d, n_targets) > 0.0)

    ahead, back = jax.vmap(leaves)(v), jax.vmap(leaves)(-v)
    least = jnp.argmin(jnp.where(ahead | back, e, jnp.inf))
    v = jnp.where(ahead[least], 1.0, -1.0) * v[least]
    return jnp.sum(weak) <= _FACE_ROWS, ahead[least] | back[least], e[least], v, w[least]


def _room_along(slack, rate):
    """The largest a in [0, 1] with slack - a rate >= 0 in every row that the direction
    raises (rate > 0); a row without slack (<= 0) leaves no room along it."""
    ratios = jnp.where(rate > 0, jnp.maximum(slack, 0.0) / jnp.where(rate > 0, rate, 1.0), jnp.inf)
    return jnp.clip(jnp.min(ratios, initial=jnp.inf), 0.0, 1.0)


def _room(y, v, y_max):
    """The largest a in [0, 1] with y + a v inside the box."""
    return _room_along(jnp.concatenate([y_max - y, y]), jnp.concatenate([v, -v]))


def _limits_room(jet, v, n_targets):
    """The largest a in [0, 1] with the limit rows (<= 0 when met), linearised at the jet, met
    at a v. A row whose rate along v is below DESIGN_NULL_SPACE_RTOL of its gradient's norm
    (times v's) counts as not raised: v lies in the null space of the strongly active rows,
    up to rounding, which must not choose a side."""
    gradients = jet.J[1 + n_targets :]
    rate = gradients @ v
    level = DESIGN_NULL_SPACE_RTOL * jnp.linalg.norm(gradients, axis=1) * jnp.linalg.norm(v)
    return _room_along(-jet.v[1 + n_targets :], jnp.where(rate > level, rate, 0.0))


# Phases of the search. Each iteration tries one point and evaluates the model's jet there
# once; the search ends at the first phase from CONVERGED on (and the loop goes on with
# the polish).
START, SEARCH, ESCAPE, PROBE, CONVERGED, STALLED, NOT_MINIMUM, NONFINITE_START = range(8)

# The probe of a flat stationary point tries the arc along its flat directions
# (:func:`_least_curvature`) at these fractions of a box width, each on both sides, before
# accepting it.
_PROBE_FIRST, _PROBE_SHRINK, _PROBE_LAST = 1.0, 1.0 / 8.0, 1.0 / 512.0
# Steps that shrink by less than this factor from one point to the next converge linearly
# (Newton's on x^3 by 1/2, on x^4 by 2/3). At 0.1, hs056's last steps (by 0.13, superlinear
# with the Hessian at the last point's multipliers) counted as linear, and the probe of its
# optimum took a point a box width away, lower in the merit but grossly infeasible.
_LINEAR_RATE = 0.25
# A probe's second direction within this cosine of its first adds nothing.
_PARALLEL = 0.99


class _State(eqx.Module):
    """The search's state (scaled variables). ``y`` is the accepted point, ``jet`` the
    model there, ``step`` the subproblem's answer at y; the search tries the point
    y + alpha direction, plus alpha^2 correction where ``bent``: ``direction`` is the
    step, or a direction of negative or zero curvature, and ``correction`` its second-order
    correction on the active constraints (:func:`_bend`; a step is bent where its whole
    length failed straight, ``straight`` then being the merit it reached, or from its
    first try where ``bend_first``, the last step having been bent); ``alpha`` the fraction
    tried next; the line search asks for a merit below the largest in the ``history``
    + ARMIJO (alpha slope + alpha^2 curvature), ``history`` holding the weighted objective
    and the violation of the last _HISTORY accepted points of the search (the first this
    one's), priced at the present penalty (along a direction that is no descent,
    ``merit`` alone). ``radius`` bounds the subproblem's step
    (:data:`_RADIUS_GROWTH`). ``nu`` is the merit's penalty, ``weight`` the objective's
    scale. ``second`` (0 where none) is the direction a probe tries once ``direction``
    has failed, with its ``second_correction``."""

    phase: Int[Array, ""]
    y: Float[Array, " n"]
    jet: Jet
    step: _Step
    bound_multipliers: Float[Array, " 2n"]
    direction: Float[Array, " n"]
    correction: Float[Array, " n"]
    alpha: Float[Array, ""]
    merit: Float[Array, ""]
    slope: Float[Array, ""]
    curvature: Float[Array, ""]
    nu: Float[Array, ""]
    bent: Bool[Array, ""]
    straight: Float[Array, ""]
    weight: Float[Array, ""]
    escapes: Int[Array, ""]
    nudged: Bool[Array, ""]
    steps: Int[Array, ""]
    radius: Float[Array, ""]
    history: Float[Array, "h 2"]
    bend_first: Bool[Array, ""]
    second: Float[Array, " n"]
    second_correction: Float[Array, " n"]


def _search_and_polish(problem: Problem, y0, theta, settings: Settings, y_max) -> "_Loop":
    """Sequential quadratic programming from y0, then the polish from where it ends (see
    the module docstring), as one loop whose trips each evaluate the model's jet once:
    at the point the search tries, then at Newton's iterates. One place in the program
    evaluates the model, so XLA compiles it once."""
    n, n_targets = y0.shape[0], len(problem.targets)
    m = max(n_targets + len(problem.limit_rows), 1)  # with _evaluate's row that never binds
    xtol = jnp.sqrt(settings.atol)

    def bend_operands(state):
        """:func:`_bend`'s operands for the step at the accepted point: its active rows."""
        return state.jet, state.step.d, _held_rows(state.step), state.step.at_lower | state.step.at_upper

    def accept(state, y, jet):
        """Take y as the new point: solve the subproblem there and choose what comes next."""
        searched = state.phase == SEARCH
        taken = jnp.max(jnp.abs(state.direction))
        radius = jnp.where(searched & (state.alpha < 1.0), state.alpha * taken, state.radius)
        reached = searched & (state.alpha == 1.0) & (taken >= 0.9 * state.radius)
        stuck = jnp.asarray(False)
        if problem.objective is None:
            # Without an objective the QP knows no curvature of the rows: next to the point
            # closest to a target that no point meets (sin x = 2 near pi / 2, x^2 = -1 at 0)
            # its steps overshot that point by the radius, to and fro, and the nonmonotone
            # merit took them: "max_steps_reached" after 100 evaluations. A step taken
            # uphill, beyond which the violation rises again (its gradient there points
            # along the step), overshot: it halves the radius, and one so taken at the
            # radius's floor leaves no shorter step to try: the point is stationary.
            # (Overshooting alone, downhill too, halved the radius along Powell's badly
            # scaled system, whose nearly met rows change sign from step to step: 60
            # steps where 19 did.) The radius grows only after a step that gained at least
            # _GROWTH_GAIN of the merit's decrease that its linearisation promised (on x^2's
            # way to 0 a step of half the distance gains 3/4 of it).
            rising = jax.grad(_violation)(jet.v[1:], n_targets) @ jet.J[1:]  # the violation's gradient in y
            gained = state.merit - _merit(jet, state.weight, state.nu, n_targets)
            overshot = searched & (gained < 0.0) & (jnp.dot(rising, state.direction) > 0.0)
            stuck = overshot & (state.alpha * taken <= _RADIUS_FLOOR * xtol)
            reached = reached & ~overshot & (gained >= -_GROWTH_GAIN * state.alpha * state.slope)
            radius = jnp.where(overshot, 0.5 * state.alpha * taken, radius)
        radius = jnp.maximum(jnp.where(reached, _RADIUS_GROWTH * state.radius, radius), _RADIUS_FLOOR * xtol)
        if problem.objective is not None:
            step, bound_multipliers = _settled_step(
                jet, y, y_max, state.step, state.bound_multipliers, state.weight, n_targets, radius, xtol
            )
        else:  # the Hessians are not used (see _jet): one solve
            step, bound_multipliers, _ = _step(
                jet, y, y_max, state.step, state.bound_multipliers, state.weight, n_targets, False, radius
            )
        # The penalty stays at least max(twice the multipliers, _PENALTY_FLOOR) and falls
        # halfway towards that at each point (Powell's update, with one penalty for all
        # rows, where SLSQP keeps one per row, and a floor): after an elastic step
        # (multipliers at DESIGN_ELASTIC) a penalty kept at 2e6 while the multipliers fell
        # to 2e-3 made the merit of hs069's curved targets' second-order violation (1e-9)
        # outweigh the objective's decrease: steps of 1e-3 to and fro, "max_steps_reached".
        # Without the floor the penalty fell with the vanishing multipliers of hs047's
        # degenerate minimum, and its probe took an infeasible point.
        need = jnp.maximum(2.0 * jnp.max(jnp.abs(step.multipliers), initial=0.0), _PENALTY_FLOOR)
        nu = jnp.maximum(need, 0.5 * (state.nu + need))
        parts = _merit_parts(jet, state.weight, n_targets)
        merit = _priced(parts, nu)
        gradient = state.weight * jet.J[0]
        # The merit's directional derivative along the step; never above 0, so that a
        # step which is no descent direction (an inexact subproblem) is taken only downhill.
        slope = jnp.dot(gradient, step.d) - nu * (_violation(jet.v[1:], n_targets) - step.linear_violation)
        slope = jnp.minimum(slope, 0.0)
        stationary = (jnp.max(jnp.abs(step.d)) <= xtol) | stuck
        linear = jnp.max(jnp.abs(step.d)) >= _LINEAR_RATE * jnp.max(jnp.abs(state.step.d))
        approach = jnp.where(linear, step.d, 0.0)
        # Only a stationary point's curvature is read: its SVD and eigenvalues run only there.
        curvature, v, w, u, wu = where_needed(
            stationary & (problem.objective is not None),
            lambda operands: _least_curvature(*operands, n_targets),
            (jet, step, bound_multipliers, state.weight, approach),
            (jnp.ones(()), jnp.zeros(n), jnp.zeros(n), jnp.zeros(n), jnp.zeros(n)),
        )

        def leaving(v):
            """(v, its room in the box, the most room either way in the box and the limits):
            leave a saddle downhill, or, where flat, towards the side with more room in the
            box and the limits, then in the box alone. At (0, 1), a vertex of
            min -(x^2 + 2 y^2) on x + y <= 1, y <= 1, whose limit holds with no multiplier,
            the box's room alone chose +x, across the limit; every escape failed and the
            point was called "not_a_minimum"."""
            v = jnp.where(jnp.dot(gradient, v) > 0.0, -v, v)
            box = jnp.stack([_room(y, v, y_max), _room(y, -v, y_max)])
            held = jnp.minimum(box, jnp.stack([_limits_room(jet, v, n_targets), _limits_room(jet, -v, n_targets)]))
            wider = (held[1] > held[0]) | ((held[1] == held[0]) & (box[1] > box[0]))
            flip = (jnp.dot(gradient, v) == 0.0) & wider
            return jnp.where(flip, -v, v), jnp.where(flip, box[1], box[0]), jnp.max(held)

        v, room, most = leaving(v)
        # Where weakly active rows block v both ways, the faces of the cone they leave give
        # the least curvature of a direction that leaves the point, signed to leave
        # (_saddle_on_faces); where none leaves, the point is a minimum on that cone.
        blocked = stationary & (curvature < -DESIGN_CURVATURE_TOL) & (most <= 0.0)
        decided, found, face_curvature, face_v, face_w = where_needed(
            blocked,
            lambda operands: _saddle_on_faces(*operands, n_targets),
            (jet, step, bound_multipliers, state.weight, y, y_max),
            (jnp.asarray(False), jnp.asarray(False), curvature, v, w),
        )
        on_face = blocked & found
        curvature = jnp.where(on_face, face_curvature, jnp.where(blocked & decided, 1.0, curvature))
        v, room = jnp.where(on_face, face_v, v), jnp.where(on_face, _room(y, face_v, y_max), room)
        w = jnp.where(on_face, face_w, w)
        saddle = stationary & (curvature < -DESIGN_CURVATURE_TOL)
        escape = saddle & (state.escapes < DESIGN_ESCAPES) & (room > 0.0)
        # A stationary point whose curvature is too small to tell a minimum (x^3 at 0, a
        # ridge of -x^4), or which the steps approached only linearly (as they approach a
        # degenerate point, where at a minimum with curvature Newton's steps shrink
        # quadratically), is probed on both sides before it is accepted (a stationary start
        # too: no steps tell how it was approached). Without an objective there is no
        # minimum to confirm, nor a direction to probe (every probe tried the point itself).
        flat = (curvature <= DESIGN_FLAT_CURVATURE) | linear
        probe = stationary & ~saddle & flat & (state.escapes < DESIGN_ESCAPES) & (problem.objective is not None)
        phase = jnp.select([escape, saddle, probe, stationary], [ESCAPE, NOT_MINIMUM, PROBE, CONVERGED], SEARCH)
        return eqx.tree_at(
            lambda s: (
                s.phase,
                s.y,
                s.jet,
                s.step,
                s.bound_multipliers,
                s.direction,
                s.correction,
                s.alpha,
                s.merit,
                s.slope,
                s.curvature,
                s.nu,
                s.bent,
                s.escapes,
                s.radius,
                s.history,
                s.bend_first,
                s.second,
                s.second_correction,
            ),
            state,
            (
                phase,
                y,
                jet,
                step,
                bound_multipliers,
                jnp.select([escape, probe], [room * v, v], step.d),
                jnp.select([escape, probe], [room**2 * w, w], jnp.zeros(n)),
                jnp.where(probe, _PROBE_FIRST, 1.0),
                merit,
                jnp.where(escape, jnp.dot(gradient, v), slope),
                jnp.where(escape, 0.5 * curvature, 0.0),
                nu,
                escape | probe,
                state.escapes + (escape | probe),
                radius,
                # a larger penalty would make the old points' merits lenient; a search restarts
                # its history then, and after an escape or a probe
                jnp.where((nu > state.nu) | ~searched, _NO_POINT, jnp.roll(state.history, 1, axis=0)).at[0].set(parts),
                searched & state.bent,
                jnp.where(probe, u, 0.0),
                jnp.where(probe, wu, 0.0),
            ),
        )

    def prepare(state, polishing):
        """(state, trial): the point that the search tries next. After a step that needed
        bending, the next is bent from its first try (curved constraints stay curved:
        trying it straight first costs an evaluation a step)."""
        alpha = state.alpha
        bend_now = ~polishing & (state.phase == SEARCH) & ~state.bent & (alpha == 1.0) & state.bend_first
        if problem.objective is not None:
            correction = where_needed(
                bend_now, lambda operands: _bend(*operands), bend_operands(state), state.correction
            )
            state = eqx.tree_at(
                lambda s: (s.bent, s.correction, s.straight),
                state,
                (
                    state.bent | (bend_now & jnp.any(correction != 0.0)),
                    correction,
                    jnp.where(bend_now, jnp.inf, state.straight),
                ),
            )
        trial = state.y + alpha * state.direction + jnp.where(state.bent, alpha**2, 0.0) * state.correction
        return state, jnp.where(state.phase == START, state.y, jnp.clip(trial, 0.0, y_max))

    def update(state, trial, jet):
        """The search's next state, where the model's jet at ``trial`` is ``jet``."""
        start = state.phase == START
        alpha = state.alpha
        finite = jnp.all(jnp.isfinite(jet.v)) & jnp.all(jnp.isfinite(jet.J)) & jnp.all(jnp.isfinite(jet.H))
        state = eqx.tree_at(lambda s: s.steps, state, state.steps + 1)

        # START: a start where the model is flat in every direction (the centre of a
        # symmetric design) offers no step at all: move it once a little into the box, by
        # a different amount per variable; otherwise scale the objective and accept it
        # (to a unit gradient, counted no smaller than DESIGN_GRADIENT_FLOOR times the
        # Hessian: next to a stationary point 1 / |gradient| left the polish only rounding).
        flat = start & ~state.nudged & jnp.all(jet.J == 0.0)
        inward = jnp.where(trial > 0.5 * y_max, -1.0, 1.0)
        nudge = inward * DESIGN_START_NUDGE * y_max * (1.0 + jnp.arange(n)) / n
        nudged = eqx.tree_at(lambda s: (s.y, s.nudged), state, (trial + nudge, jnp.asarray(True)))
        size = jnp.maximum(jnp.linalg.norm(jet.J[0]), DESIGN_GRADIENT_FLOOR * jnp.linalg.norm(jet.H[0]))
        scaled = eqx.tree_at(lambda s: s.weight, state, safe_div(1.0, size, at_zero=1.0))
        accepted = accept(_pick(start, scaled, state), trial, jet)
        not_started = eqx.tree_at(lambda s: s.phase, state, jnp.asarray(NONFINITE_START))

        # SEARCH, ESCAPE: Armijo's test on the merit, else a shorter step. PROBE: a merit
        # lower by more than rounding, else the other side, then a shorter arc, and the
        # point stands (CONVERGED) after the shortest.
        probing = state.phase == PROBE
        merit = _merit(jet, state.weight, state.nu, n_targets)
        # nonmonotone only in the search and along a descent direction (the history's
        # first entry is this point's merit)
        merits = _priced(state.history, state.nu)
        reference = jnp.where((state.phase == SEARCH) & (state.slope < 0.0), jnp.max(merits), state.merit)
        wanted = reference + _ARMIJO * (alpha * state.slope + alpha**2 * state.curvature)
        wanted = jnp.where(probing, state.merit - _ROUNDING * (1.0 + jnp.abs(state.merit)), wanted)
        good = finite & (merit <= wanted)
        # A whole step that failed straight is tried once more bent (the Maratos effect: a
        # step along a curved constraint that the merit rejects for its second-order
        # violation); the shorter steps then stay bent where bending lowered the merit
        # (``straight`` holds the straight step's), else they go straight. A step bent from
        # its first try (``bend_first``) stays bent.
        # The correction is worked out only here, where a whole step failed: at every
        # accepted point its pseudo-inverse would cost a batched sweep 1.7 times its time.
        # Without an objective there are no Hessians (see _jet), and the steps go straight.
        may_bend = (state.phase == SEARCH) & ~state.bent & (alpha == 1.0) & ~good & (problem.objective is not None)
        correction = where_needed(may_bend, lambda operands: _bend(*operands), bend_operands(state), state.correction)
        bend = may_bend & jnp.any(correction != 0.0)
        next_alpha = jnp.where(probing, jnp.where(alpha > 0.0, -alpha, -alpha * _PROBE_SHRINK), 0.5 * alpha)
        next_alpha = jnp.where(bend, alpha, next_alpha)
        keep = state.bent & ((alpha < 1.0) | (merit < state.straight))
        bent = jnp.where(state.phase == SEARCH, bend | keep, state.bent)
        straight = jnp.where(bend, merit, state.straight)
        shorter = eqx.tree_at(
            lambda s: (s.alpha, s.bent, s.straight, s.correction), state, (next_alpha, bent, straight, correction)
        )
        given_up = jnp.select([state.phase == ESCAPE, probing], [NOT_MINIMUM, CONVERGED], STALLED)
        failed = eqx.tree_at(lambda s: s.phase, shorter, given_up)
        too_short = jnp.abs(next_alpha) < jnp.where(probing, _PROBE_LAST, _SHORTEST_STEP)
        # A probe that found nothing along its direction tries its second, if it has one.
        turned = eqx.tree_at(
            lambda s: (s.direction, s.correction, s.alpha, s.second, s.second_correction),
            shorter,
            (state.second, state.second_correction, jnp.asarray(_PROBE_FIRST), jnp.zeros(n), jnp.zeros(n)),
        )
        failed = _pick(probing & jnp.any(state.second != 0.0), turned, failed)
        searched = _pick(good, accepted, _pick(too_short, failed, shorter))
        return _pick(start, _pick(flat, nudged, _pick(finite, accepted, not_started)), searched)

    blank_jet = Jet(jnp.zeros(1 + m), jnp.zeros((1 + m, n)), jnp.zeros((1 + m, n, n)), jnp.zeros(len(problem.outputs)))
    no = lambda size: jnp.zeros(size, bool)  # noqa: E731
    state = _State(
        phase=jnp.asarray(START),
        y=y0,
        jet=blank_jet,
        step=_Step(
            jnp.zeros(n),
            jnp.zeros(m),
            jnp.zeros(()),
            no(m - n_targets),
            no(n),
            no(n),
            _no_slack_rows(n, n_targets, m - n_targets),
        ),
        bound_multipliers=jnp.zeros(2 * n),
        direction=jnp.zeros(n),
        correction=jnp.zeros(n),
        alpha=jnp.asarray(1.0),
        merit=jnp.zeros(()),
        slope=jnp.zeros(()),
        curvature=jnp.zeros(()),
        nu=jnp.asarray(_PENALTY_FLOOR),
        bent=jnp.asarray(False),
        straight=jnp.asarray(0.0),
        weight=jnp.asarray(1.0),
        escapes=jnp.asarray(0),
        nudged=jnp.asarray(False),
        steps=jnp.asarray(0),
        radius=jnp.asarray(jnp.inf),
        history=_NO_POINT,
        bend_first=jnp.asarray(False),
        second=jnp.zeros(n),
        second_correction=jnp.zeros(n),
    )
    newton = _newton(settings)

    def body(loop):
        polishing, stepping = loop.polishing, loop.polishing & ~loop.polish.done
        prepared, trial = prepare(loop.search, polishing)
        # Under vmap every lane runs each trip (a finished lane's state is kept), and a
        # lane's model error (as NaN) reaches the whole batch: a finished lane evaluates
        # the model where its search stopped, not at Newton's untried point, and the search's
        # update, which runs if any lane searches, gets a polishing lane's own finite jet.
        jet = _jet(problem, jnp.where(stepping, loop.polish.z[:n], trial), theta)
        searched = where_needed(
            ~polishing,
            lambda operands: update(*operands),
            (prepared, trial, _pick(polishing, loop.search.jet, jet)),
            loop.search,
        )
        ended = ~polishing & ((searched.phase >= CONVERGED) | (searched.steps >= settings.max_steps))
        equations = _equations(problem, searched, y_max)
        polish = _pick(ended, _polish_start(equations, searched, newton), loop.polish)
        # Newton's first step is from the search's last point, whose jet the search has
        # (where it accepted a point; else the next trip evaluates the model there first).
        accepted = (searched.phase != START) & (searched.phase != NONFINITE_START)
        polish = where_needed(
            stepping | (ended & accepted),
            lambda operands: _newton_step(equations, newton, *operands, settings.max_steps),
            (polish, _pick(polishing, jet, searched.jet)),
            polish,
        )
        return _Loop(searched, polish, polishing | ended)

    start = _Loop(state, _polish_start(_equations(problem, state, y_max), state, newton), jnp.asarray(False))
    return jax.lax.while_loop(lambda loop: ~loop.polish.done, body, start)


def _pick(condition, new, old):
    """``new`` where ``condition`` holds, else ``old``, leaf by leaf."""
    return jax.tree.map(lambda a, b: jnp.where(condition, a, b), new, old)


class _Active(eqx.Module):
    """The active set of the polish: limit rows held as equations, variables fixed on a bound."""

    limits: Bool[Array, " l"]
    at_lower: Bool[Array, " n"]
    at_upper: Bool[Array, " n"]

    @property
    def fixed(self):
        """(n,) the variables held on a bound."""
        return self.at_lower | self.at_upper

    def fixed_residual(self, y, y_max):
        """(n,) each fixed variable's distance from its bound, 0 for the free ones."""
        return jnp.where(self.at_lower, y, jnp.where(self.at_upper, y - y_max, 0.0))


class _KKT(eqx.Module):
    """The KKT residual of an active set (the polish's equations with an objective): at
    z = (y, multipliers), stationarity of the Lagrangian on the free variables, the
    fixed variables' distance to their bound, the targets and active limit rows, and the
    inactive rows' multipliers, from the model's :class:`Jet` at y (its derivative in z
    from the model's Hessians)."""

    problem: Problem
    weight: Float[Array, ""]
    active: _Active
    equations: Bool[Array, " m"]
    y_max: Float[Array, " n"]

    def rows(self, z, jet):
        """The residual at z from the model's rows and their Jacobian (with the objective's) in ``jet``."""
        n = self.y_max.shape[0]
        y, lam = z[:n], z[n:]
        stationarity = self.weight * jet.J[0] + jet.J[1:].T @ lam
        r_y = jnp.where(self.active.fixed, self.active.fixed_residual(y, self.y_max), stationarity)
        return jnp.concatenate([r_y, jnp.where(self.equations, jet.v[1:], lam)])

    def tangent(self, jet, z, dz):
        """(n + m,) the residual's derivative along dz (n + m,) at z, where the model's
        :class:`Jet` is ``jet``."""
        n = self.y_max.shape[0]
        lam, dy, dlam = z[n:], dz[:n], dz[n:]
        d_stationarity = _lagrangian_hessian(jet, lam, self.weight) @ dy + jet.J[1:].T @ dlam
        return jnp.concatenate(
            [jnp.where(self.active.fixed, dy, d_stationarity), jnp.where(self.equations, jet.J[1:] @ dy, dlam)]
        )

    def unknowns(self, y, multipliers):
        """(n + m,) z at y (n,) with the held rows' ``multipliers`` (m,)."""
        return jnp.concatenate([y, jnp.where(self.equations, multipliers, 0.0)])


class _Feasibility(eqx.Module):
    """The polish's equations without an objective: the targets and active limit rows,
    and the fixed variables' distance to their bound, from the model's :class:`Jet` at y
    (its values and Jacobian)."""

    problem: Problem
    active: _Active
    equations: Bool[Array, " m"]
    y_max: Float[Array, " n"]

    def rows(self, y, jet):
        """The residual at y from the model's rows in ``jet``."""
        return jnp.concatenate([jnp.where(self.equations, jet.v[1:], 0.0), self.active.fixed_residual(y, self.y_max)])

    def tangent(self, jet, y, dy):
        """The residual's derivative along dy (n,) at y, where the model's :class:`Jet` is ``jet``."""
        return jnp.concatenate([jnp.where(self.equations, jet.J[1:] @ dy, 0.0), jnp.where(self.active.fixed, dy, 0.0)])

    def unknowns(self, y, multipliers):
        """(n,) the unknowns at y (n,): y itself (no multipliers)."""
        return y


def _rows_in(problem, jet, theta):
    """The model's :class:`Jet` ``jet`` with its rows read again from its outputs in theta
    (targets' values and limits' bounds)."""
    c, _ = _scaled_rows(problem, dict(zip(problem.outputs, jet.outputs)), theta)
    return eqx.tree_at(lambda j: j.v, jet, jnp.concatenate([jet.v[:1], c]))


def _in_theta(equations, z, jet, theta):
    """The model's :class:`Jet` ``jet`` at y = z[:n], with what the rows of ``equations``
    read of it as functions of theta, for derivatives in theta: without fixed inputs
    theta moves only the targets' and limits' bounds (the rows c, from the outputs); with
    them it moves the model, whose values (and, for the KKT residual, first derivatives,
    so that their derivative in theta is a mixed second derivative) are evaluated again."""
    problem, n = equations.problem, len(equations.problem.variables)
    if not problem.fixed_names:
        return _rows_in(problem, jet, theta)
    if problem.objective is None:  # the feasibility rows read the values alone
        v, outputs = _values(problem, z[:n], theta)
        return eqx.tree_at(lambda j: (j.v, j.outputs), jet, (v, outputs))
    J, (v, outputs) = _first_jet(problem, z[:n], theta)
    return eqx.tree_at(lambda j: (j.v, j.J, j.outputs), jet, (v, J, outputs))


# optimistix's implicit adjoint, with the polish's linear solver
_ADJOINT = optx.ImplicitAdjoint(linear_solver=LUOrSVD())


def _implicit_derivatives(equations, z, jet, theta, usable):
    """(len(z), p) d z / d theta at a root z of the polish's ``equations``, where the
    model's :class:`Jet` is ``jet`` (the polish's last): the tangents that optimistix's
    implicit adjoint gives a root find's answer, asked of it at the root, of the
    equations to first order about z
    (:func:`_linearised`), so that the model is not evaluated again, nor traced again,
    unless it depends on theta (fixed inputs). Forward mode through the polish's loop
    itself would trace it whole under JAX's jvp and vmap, and with it the model.

    ``usable``: False where z or the equations there are not finite. The equations
    are then zero (so are the derivatives, which the caller masks): lineax checks the
    implicit solve's answer with an equinox error, which, traced as NaN (see
    :func:`_errors_as_nan`), turned every member of a vmapped batch to NaN as soon as one
    member's answer was not finite, the derivatives of a sweep's good points with it."""

    def root_of(theta):
        return _ADJOINT.apply(_given_root, _linearised, (equations, theta, z, jet, usable), frozenset())[0]

    return jax.jacfwd(root_of)(theta)


def _solvable(equations, z, jet, theta, dz):
    """(p,) bool: whether the linear system that the implicit derivatives dz (len(z), p)
    solve at the root z has a solution in each column of theta that is a target's value or
    a limit's bound (the others: True). Held rows that are dependent (a limit whose two
    bounds are equal, a limit given twice) leave none for a bound moved alone, and the
    least-squares answer, which splits the move between the rows, is no derivative: a
    pinned limit's two sides got 0.25 each where raising the upper one alone moves the
    optimum by 0.5 (and lowering it leaves no design)."""
    problem = equations.problem
    n_rows = len(problem.targets) + len(problem.limit_rows)

    moved = jax.jacfwd(lambda bounds: equations.rows(z, _rows_in(problem, jet, theta.at[:n_rows].set(bounds))))(
        theta[:n_rows]
    )  # (len(z), rows)
    reached = jax.vmap(lambda d: equations.tangent(jet, z, d), in_axes=1, out_axes=1)(dz[:, :n_rows])
    size = jnp.max(jnp.abs(moved), axis=0, initial=0.0) + jnp.max(jnp.abs(reached), axis=0, initial=0.0)
    solvable = jnp.max(jnp.abs(reached + moved), axis=0, initial=0.0) <= DESIGN_SOLVABLE_RTOL * size
    return jnp.concatenate([solvable, jnp.ones(theta.shape[0] - n_rows, bool)])


def _given_root(inputs):
    return inputs[2], None


def _linearised(root, _, inputs):
    """The equations to first order in the root about z: exact derivatives at z, in the
    root from the model's jet there, in theta from :func:`_in_theta`. (``inputs`` ends
    with what optimistix's adjoint appends.)"""
    equations, theta, z, jet, usable = inputs[:5]
    return jnp.where(
        usable, equations.rows(z, _in_theta(equations, z, jet, theta)) + equations.tangent(jet, z, root - z), 0.0
    )


def _about(equations, z, jet):
    """fn(root, args) -> (the polish's ``equations`` to first order in the root about z,
    where the model's :class:`Jet` is ``jet``; no aux): what Newton's step from z solves,
    as optimistix's Newton takes it."""
    return lambda root, _: (equations.rows(z, jet) + equations.tangent(jet, z, root - z), None)


def _equations(problem: Problem, search: _State, y_max):
    """The polish's equations on the active set of the search's last subproblem: the KKT
    system with an objective, else the feasibility equations."""
    step = search.step
    active = _Active(step.active_limits, step.at_lower, step.at_upper)
    held = _held_rows(step)
    if problem.objective is None:
        return _Feasibility(problem, active, held, y_max)
    return _KKT(problem, search.weight, active, held, y_max)


def _newton(settings: Settings):
    """The polish's root finder: optimistix's Newton, to a tenth of the design's tolerance
    on its residual and on its step relative to (1 + |z|) (from the search's point
    typically one or two steps), its linear systems through LU, else an SVD (LUOrSVD: the
    feasibility equations are not square, in general; with more unknowns than equations
    Newton through an SVD is Gauss-Newton with minimum-norm steps)."""
    return optx.Newton(rtol=settings.rtol * 0.1, atol=settings.rtol * 0.1, linear_solver=LUOrSVD())


class _Polish(eqx.Module):
    """The polish's state: ``z`` the point where Newton evaluates the model next,
    ``evaluated`` the last point where it did, ``jet`` the model's :class:`Jet` there,
    ``newton`` optimistix's Newton state (its ``f`` the equations' residual at
    ``evaluated``), ``done`` where Newton has stopped."""

    z: Float[Array, " u"]
    evaluated: Float[Array, " u"]
    jet: Jet
    newton: eqx.Module
    done: Bool[Array, ""]


def _polish_at(equations, z, jet, newton):
    """The polish's state before its first step, at z, where the model's :class:`Jet` is
    ``jet`` (or where it will be evaluated first)."""
    state = newton.init(
        _about(equations, z, jet), z, None, {}, jax.eval_shape(equations.rows, z, jet), None, frozenset()
    )
    return _Polish(z, z, jet, state, jnp.asarray(False))


def _polish_start(equations, search: _State, newton):
    """The polish's state before its first step on ``equations`` (:func:`_equations` of
    the search): at the search's point and multipliers."""
    return _polish_at(equations, equations.unknowns(search.y, search.step.multipliers), search.jet, newton)


def _newton_step(equations, newton, polish: _Polish, jet, max_steps):
    """The polish after Newton's step from its point z, where the model's :class:`Jet` is
    ``jet``. Stepped as optimistix's interactive use of a solver (its ``step`` and
    ``terminate``) inside the solver's loop, so that the search and the polish evaluate the
    model at one place of the program; the steps and stopping rule of
    ``optimistix.root_find`` (which stops at a point that is not finite too), and a stop
    at a residual that is not finite, where no step can lead."""
    z, fn = polish.z, _about(equations, polish.z, jet)
    z_next, state, _ = newton.step(fn, z, None, {}, polish.newton, frozenset())
    stop, _ = newton.terminate(fn, z, None, {}, state, frozenset())
    finite = jnp.all(jnp.isfinite(z)) & jnp.all(jnp.isfinite(state.f))
    done = stop | (state.step >= max_steps) | ~finite
    return _Polish(z_next, z, jet, state, done)


class _Loop(eqx.Module):
    """The state of :func:`_search_and_polish`: the search's, the polish's, and whether
    the search has ended and the polish runs."""

    search: _State
    polish: _Polish
    polishing: Bool[Array, ""]


def _core(problem: Problem, y0, theta, settings: Settings) -> CoreSolution:
    """The search, the polish, the implicit derivatives and the status."""
    n, n_targets = len(problem.variables), len(problem.targets)
    lower, upper, scale, _, _ = problem_arrays(problem)
    y_max = (upper - lower) / scale
    tol = settings.rtol

    loop = _search_and_polish(problem, jax.lax.stop_gradient(y0), theta, settings, y_max)
    search, polish = loop.search, loop.polish
    # the polish's answer is the last point where it evaluated the model, with its jet
    equations, z, polished = _equations(problem, search, y_max), polish.evaluated, polish.jet
    # the search's point and its multipliers, of the rows held there (the others' are the
    # QP's leftovers, below its activity threshold)
    y_start, multipliers_start = search.y, jnp.where(equations.equations, search.step.multipliers, 0.0)
    active = equations.active
    residual = jnp.max(jnp.abs(polish.newton.f), initial=0.0)
    y = z[:n]
    multipliers = z[n:] if problem.objective is not None else jnp.zeros_like(multipliers_start)
    usable = jnp.isfinite(residual) & jnp.all(jnp.isfinite(z))
    usable = usable & jnp.all(jnp.stack([jnp.all(jnp.isfinite(leaf)) for leaf in jax.tree.leaves(polished)]))
    if theta.shape[0]:
        dz = _implicit_derivatives(equations, z, polished, theta, usable)
        dy = jnp.where(_solvable(equations, z, polished, theta, dz), dz[:n], jnp.nan)
    else:
        dy = jnp.zeros((n, 0))
    outputs, c = polished.outputs, polished.v[1:]
    # The polish refines the search's point; one that ends outside the box or far away
    # found another solution of the equations, and the search's point stands, as it does
    # where the model is not finite at the polish's point, and where the polish breaks a
    # row that the search's point meets (in an experiment with another QP Hessian, Newton's
    # residual on the badly scaled hs106 stalled 1.9e-10 outside a limit that the search's
    # point held to 6e-16: "limit_violated"). With an objective, a polish that went further
    # stands where it met its equations to the design's tolerance at an objective no higher
    # than the search's point's, its held limits' and bounds' multipliers of the right sign
    # (to sqrt(rtol)): on 1e10 (x + y - 1)^2 + (x - y - 0.2)^2 the search, whose objective
    # (scaled to its gradient at the start) fell below rounding, stopped 0.04 from the
    # minimum, and the polish's exact step there, 0.009 of a box width, was dropped.
    near = jnp.max(jnp.abs(y - y_start)) <= DESIGN_POLISH_REACH
    if problem.objective is not None:
        pull = search.weight * polished.J[0] + polished.J[1:].T @ multipliers  # a fixed variable's bound's multiplier
        signed = jnp.all(jnp.where(equations.equations[n_targets:], multipliers[n_targets:], 0.0) >= -jnp.sqrt(tol))
        signed = signed & jnp.all(jnp.where(active.at_lower, pull, 0.0) >= -jnp.sqrt(tol))
        signed = signed & jnp.all(jnp.where(active.at_upper, pull, 0.0) <= jnp.sqrt(tol))
        near = near | ((residual <= tol) & (polished.v[0] <= search.jet.v[0]) & signed)
    kept = (
        usable
        & jnp.all((y >= -DESIGN_ON_CONSTRAINT) & (y <= y_max + DESIGN_ON_CONSTRAINT))
        & near
        & (~jnp.any(_broken(c, n_targets, tol)) | jnp.any(_broken(search.jet.v[1:], n_targets, tol)))
    )
    y = jnp.where(kept, jnp.clip(y, 0.0, y_max), y_start)
    outputs = jnp.where(kept, outputs, search.jet.outputs)
    c = jnp.where(kept, c, search.jet.v[1:])

    # Stationarity is a gradient condition: met to sqrt(rtol), as the optimum's value is, or
    # to its own rounding (y's, through the Lagrangian's Hessian) where that is larger, as
    # after a start on a plateau, whose small gradient scales the objective up: max
    # exp(-(x - 1)^2) from x = -4 (gradient 3e-10) met it at x = 1 to 1.3e-5, with a Hessian
    # of 3e11, and was called "max_steps_reached". Where the polish is not kept, at the
    # search's point, which then stands.
    at_search = equations.rows(equations.unknowns(y_start, multipliers_start), search.jet)
    residual = jnp.where(kept, residual, jnp.max(jnp.abs(at_search), initial=0.0))
    rounding = jnp.zeros(())
    if problem.objective is not None:
        hessian = jnp.where(
            kept,
            _lagrangian_hessian(polished, multipliers, search.weight),
            _lagrangian_hessian(search.jet, multipliers_start, search.weight),
        )
        rounding = jnp.finfo(y.dtype).eps * (1.0 + jnp.max(jnp.abs(y))) * jnp.linalg.norm(hessian)
    kkt_met = (residual <= jnp.maximum(jnp.sqrt(tol), rounding)) & (search.phase == CONVERGED)
    targets_broken, limits_broken = _broken(c, n_targets, tol)
    finite = jnp.all(jnp.isfinite(outputs)) & jnp.all(jnp.isfinite(y)) & (search.phase != NONFINITE_START)
    inner_failed = outputs[problem.outputs.index(problem.converged)] < 0.5 if problem.converged is not None else False
    status = DesignStatus.successful
    for failed, item in reversed(
        [
            (~finite, DesignStatus.nonfinite),
            (inner_failed, DesignStatus.mechanics_not_converged),
            # A search cut short by max_steps says so, not that a target is out of reach.
            (search.phase < CONVERGED, DesignStatus.max_steps_reached),
            (targets_broken, DesignStatus.infeasible_target),
            (limits_broken, DesignStatus.limit_violated),
            (search.phase == NOT_MINIMUM, DesignStatus.not_a_minimum),
            (~kkt_met, DesignStatus.max_steps_reached),
        ]
    ):
        status = DesignStatus.where(failed, item, status)
    # Derivatives of the optimum exist only at one: NaN (null in JSON) where the status is not
    # successful (a point that breaks a target or a limit, a saddle, a search cut short), where
    # the polish was not kept or its implicit solve failed; never a plain 0 that reads as
    # "insensitive", nor a number that reads as the sensitivity of a design that is not one.
    derivatives = jnp.where((status == DesignStatus.successful) & kept & jnp.isfinite(dy), scale[:, None] * dy, jnp.nan)
    m = len(problem.targets) + len(problem.limit_rows)  # without _evaluate's row that never binds
    return CoreSolution(
        x=lower + scale * y,
        multipliers=jnp.where(kept, multipliers, multipliers_start)[:m],
        outputs=outputs,
        residuals=c[:m],
        # Active: held as an equation or binding (a limit that meets a bound there,
        # degenerate), and never a limit that is violated.
        active_limits=((active.limits | (jnp.abs(c[n_targets:]) <= tol)) & (c[n_targets:] <= tol))[: m - n_targets],
        at_lower=active.at_lower,
        at_upper=active.at_upper,
        derivatives=derivatives,
        status=status._value,
        steps=search.steps,
    )


def _broken(c, n_targets, tol):
    """(2,) bool: a target broken, a limit broken, in the scaled rows c (beyond ``tol``)."""
    return jnp.stack([jnp.any(jnp.abs(c[:n_targets]) > tol), jnp.any(c[n_targets:] > tol)])


def _packed(problem, y0, theta, settings):
    """The core's solution as one float64 vector, read back from the device in one go."""
    return jnp.concatenate(
        [jnp.ravel(leaf).astype(jnp.float64) for leaf in jax.tree.leaves(_core(problem, y0, theta, settings))]
    )


def _unpack(problem, packed):
    """CoreSolution of numpy arrays from :func:`_packed`'s vector(s) (leading batch axes kept)."""
    host = _host(problem)
    parts = {name: packed[..., start:stop] for name, (start, stop) in host.layout.items()}
    batch, n, p = packed.shape[:-1], len(problem.variables), len(host.theta)
    return CoreSolution(
        x=parts["x"],
        multipliers=parts["multipliers"],
        outputs=parts["outputs"],
        residuals=parts["residuals"],
        active_limits=parts["active_limits"] > 0.5,
        at_lower=parts["at_lower"] > 0.5,
        at_upper=parts["at_upper"] > 0.5,
        derivatives=parts["derivatives"].reshape(*batch, n, p),
        status=parts["status"][..., 0].astype(int),
        steps=parts["steps"][..., 0].astype(int),
    )


def _split(tree):
    """(key, arrays) of a pytree: its array leaves are traced; its structure and other
    leaves (the model, Python numbers) key the compiled program, as in eqx.filter_jit,
    at a fraction of its cost per call."""
    leaves, treedef = jax.tree.flatten(tree)
    is_array = tuple(eqx.is_array(leaf) for leaf in leaves)
    static = tuple(None if array else leaf for array, leaf in zip(is_array, leaves))
    return (treedef, is_array, static), [leaf for array, leaf in zip(is_array, leaves) if array]


class _Host(NamedTuple):
    """What solving a problem needs of it outside the compiled core, found once per
    problem object (:func:`per_problem`): its arrays (numpy, :func:`problem_arrays`), its
    variables' own starts (scaled) and theta on the device, its structure and array
    leaves (:func:`_split`, the leaves on the device: numpy leaves would be copied there
    at every call), and where each part of the packed solution lies."""

    arrays: tuple
    y0: Array
    theta: Array
    key: tuple
    leaves: list
    layout: dict


@per_problem
def _host(problem):
    arrays = problem_arrays(problem, np)
    for array in arrays:  # shared by every solve of the problem
        array.flags.writeable = False
    theta = arrays[4]
    key, leaves = _split(problem)
    n, m, k = len(problem.variables), len(problem.targets) + len(problem.limit_rows), len(problem.outputs)
    sizes = {
        "x": n,
        "multipliers": m,
        "outputs": k,
        "residuals": m,
        "active_limits": m - len(problem.targets),
        "at_lower": n,
        "at_upper": n,
        "derivatives": n * len(theta),
        "status": 1,
        "steps": 1,
    }
    stops = np.cumsum(list(sizes.values())).tolist()
    layout = {name: (stop - size, stop) for (name, size), stop in zip(sizes.items(), stops)}
    return _Host(
        arrays,
        jax.device_put(_start(problem, None, arrays)),
        jax.device_put(theta),
        key,
        jax.device_put(leaves),
        layout,
    )


@functools.lru_cache(maxsize=64)
def _compiled(key, batched):
    """The jitted core of one structure of (problem, settings), ``key`` a pair of
    :func:`_split` keys: (arrays, y0, theta) -> packed solution, ``arrays`` the pair of
    their array leaves, vmapped over y0 and theta if ``batched``."""

    def run(arrays, y0, theta):
        problem, settings = (_joined(part_key, part) for part_key, part in zip(key, arrays))
        return _packed(problem, y0, theta, settings)

    return jax.jit(jax.vmap(run, in_axes=(None, 0, 0)) if batched else run, compiler_options=compiler_options())


def _joined(key, arrays):
    """The pytree that :func:`_split` split into ``key`` and ``arrays``."""
    treedef, is_array, static = key
    arrays = iter(arrays)
    return jax.tree.unflatten(treedef, [next(arrays) if array else leaf for array, leaf in zip(is_array, static)])


def _structure(problem, settings):
    """(key, arrays) of (problem, settings) for :func:`_compiled`."""
    host, (settings_key, settings_leaves) = _host(problem), _split(settings)
    return (host.key, settings_key), (host.leaves, settings_leaves)


@contextlib.contextmanager
def _errors_as_nan():
    """While the core is traced and lowered, equinox's runtime errors become NaN: the
    linear solves of optimistix's implicit adjoint (lineax raises on a non-finite
    answer), a soft part's saturation solve. The core reports NaN as a status
    ("nonfinite") or as NaN derivatives, so it never raises; and a runtime error is a
    host callback, which keeps a program out of JAX's persistent compilation cache, so
    that the command compiled the solver afresh on every run. Two private names of
    equinox (0.13): where they are missing, errors stay errors and the cache misses, which
    tests/test_cli.py notices."""
    names = ("EQX_ON_ERROR", "branched_error_if_impl_jit")
    if not all(hasattr(_equinox_errors, name) for name in names):
        yield
        return
    saved = [getattr(_equinox_errors, name) for name in names]
    # the unjitted check reads EQX_ON_ERROR when traced; the jitted one would reuse a
    # trace made outside this block
    _equinox_errors.EQX_ON_ERROR = "nan"
    _equinox_errors.branched_error_if_impl_jit = _equinox_errors.branched_error_if_impl
    try:
        yield
    finally:
        for name, value in zip(names, saved):
            setattr(_equinox_errors, name, value)


def _run(problem, y0, theta, settings):
    """The packed solution as a numpy array, from the cached compiled core."""
    key, arrays = _structure(problem, settings)
    with _errors_as_nan(), gc_paused():
        return np.asarray(_compiled(key, False)(arrays, y0, theta))


@functools.lru_cache(maxsize=16)
def settings_of(rtol, atol, max_steps):
    if not max_steps >= 1:
        raise ValueError(f"max_steps must be at least 1, got {max_steps!r}")
    for name, value in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return Settings(np.asarray(rtol, np.float64), np.asarray(atol, np.float64), int(max_steps))


def _start(problem: Problem, start, arrays):
    """Scaled start y0 from the variables' starts, overridden by ``start`` {name: SI}."""
    lower, upper, scale, y_start, _ = arrays
    if not start:  # the variables' own starts, checked inside their bounds on construction
        return (y_start - lower) / scale
    start = dict(start)
    unknown = sorted(set(start) - {v.name for v in problem.variables})
    if unknown:
        raise ValueError(f"start: unknown variable {unknown[0]!r}")
    values = []
    for j, v in enumerate(problem.variables):
        value = np.asarray(start.get(v.name, y_start[j]), np.float64)
        if not np.all(np.isfinite(value) & (value >= lower[j]) & (value <= upper[j])):
            raise ValueError(f"{v.name}: start {start[v.name]!r} outside the bounds [{lower[j]!r}, {upper[j]!r}]")
        values.append(value)
    return (np.stack(np.broadcast_arrays(*values), axis=-1) - lower) / scale


def solve(
    problem: Problem,
    *,
    start: dict | None = None,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
) -> DesignResult:
    """Solve a design problem; never raises for non-convergence (see ``status``).

    Args:
        problem: the variables, model, targets, limits and objective (SI).
        start: {variable: value (SI)} overriding the variables' own starts.
        rtol: tolerance on scaled residuals: a target is met when
            |achieved - value| <= rtol * scale (scale defaults to |value|); limits alike.
        atol: convergence tolerance on steps of the variables scaled to their bound width.
        max_steps: the most model evaluations of the search (line-search trials
            included), and the most Newton steps of the polish.

    Returns:
        A :class:`DesignResult`: status (a :class:`DesignStatus` name: "successful",
        "nonfinite", "mechanics_not_converged", "infeasible_target", "limit_violated",
        "not_a_minimum" or "max_steps_reached"), parameters, achieved
        targets and limits, active bounds and limits, steps, seconds, and the implicit
        derivatives of the parameters with respect to the target values and active limit
        bounds (NaN where they do not exist or could not be computed: a status other
        than "successful", an optimum that the polish did not refine, or a model whose
        derivative there is infinite).
    """
    settings, host = settings_of(rtol, atol, max_steps), _host(problem)
    y0, theta = (host.y0 if not start else _start(problem, start, host.arrays)), host.theta
    began = time.perf_counter()
    packed = _run(problem, y0, theta, settings)
    seconds = time.perf_counter() - began
    return DesignResult.from_core(problem, _unpack(problem, packed), host.arrays[4], seconds, settings.rtol)


def solve_batch(problem, y0, thetas, settings, *, chunk=None, progress=None, continuation=False):
    """Solve ``problem`` from each start y0 (points, n) for each theta (points, p): the
    flat :class:`CoreSolution` of numpy arrays and the wall time (s).

    On a CPU, a problem whose model runs loops of its own (an iterative solve, such as an
    axisymmetric dome's path: :func:`_iterative`) and whose first point takes longer than
    DESIGN_POINT_SECONDS to solve is solved a point per call of the program that
    :func:`solve` compiles, on parallel threads (:func:`_one_by_one`). Any other goes in
    chunks of at most ``chunk`` points (default DESIGN_CHUNK), so that memory stays
    bounded, each chunk vmapped and split over every local device (``jax.sharding``;
    :func:`_in_chunks`). Under ``jax.distributed`` (more than one process) each process
    solves its share of the points and every process gets the whole result.
    ``progress``: True, False, or None (a bar when stderr is a terminal and the batch
    takes more than a second). ``continuation``: where the points go one at a time, start
    points from their predecessor's predicted optimum (see :func:`_one_by_one`).
    """
    began = time.perf_counter()
    count = thetas.shape[0]
    processes, index = jax.process_count(), jax.process_index()
    share = -(-count // processes)
    mine = slice(index * share, min((index + 1) * share, count))
    y0, thetas = np.asarray(y0, np.float64)[mine], np.asarray(thetas, np.float64)[mine]
    key, arrays = _structure(problem, settings)
    bar = (
        tqdm(
            total=share,
            unit="design",
            delay=1.0,
            disable=None if progress is None else not progress,
            file=sys.stderr,
            leave=False,
        )
        if index == 0
        else None
    )
    packed = None
    try:
        if len(y0) and jax.default_backend() == "cpu" and _iterative(problem):
            stage("compiling the solver for one point at a time (first call; later runs load it from the cache)")
            with _errors_as_nan(), gc_paused():
                program = _compiled(key, False).lower(arrays, y0[0], thetas[0]).compile()
            first_began = time.perf_counter()
            first = np.asarray(program(arrays, y0[0], thetas[0]))
            if time.perf_counter() - first_began > DESIGN_POINT_SECONDS:
                packed = _one_by_one(_host(problem), program, arrays, first, y0, thetas, bar, continuation)
        if packed is None:
            packed = _in_chunks(key, arrays, y0, thetas, share, chunk, bar)
    finally:
        if bar is not None:
            bar.close()
    if processes > 1:
        with _stdout_to_stderr():  # gloo announces its connections on stdout (fd 1)
            packed = multihost_utils.process_allgather(_padded(packed, share), tiled=True)[:count]
    return _unpack(problem, packed), time.perf_counter() - began


@per_problem
def _iterative(problem):
    """Whether the problem's model runs while loops of its own (an iterative solve, such
    as an axisymmetric dome's path), read from one trace of its values."""
    host = _host(problem)
    shapes = [jax.ShapeDtypeStruct(np.shape(a), jnp.float64) for a in (host.y0, host.theta)]
    with _errors_as_nan():
        return has_loops(functools.partial(_values, problem), *shapes)


def usable_cores():
    """The number of CPU cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _one_by_one(host, program, arrays, first, y0, thetas, bar, continuation):
    """The packed solutions (points, width) of the points (y0, thetas), ``first`` that of
    the first point, solved a point per call of ``program`` (:func:`solve`'s, compiled)
    on a thread per usable core, fewer where their working memory together would pass
    DESIGN_BATCH_MEMORY; ``host`` the problem's :class:`_Host`.

    Vmapped lanes run in lock-step: every loop of a batched program turns until its
    slowest lane is done, at each level of the nested loops of a dome's path solve. A
    batch of 20 axisymmetric default designs took 27 s, twice the 13 s of its points
    solved one after another, and 2 threads solve them in 7.3 s (2-core development
    machine, 2026-11-28; scratch scripts timing the solver's parts). A call releases the
    interpreter while it runs, so the threads run their points side by side.

    With ``continuation`` the points go in runs of DESIGN_CHAIN, one run per thread at a
    time (the progress bar moves a point at a time): the first of a run starts from its
    y0, each next from the optimum that the point before predicts to first order with
    its implicit derivatives (where that point is successful and has them), and where a
    point so started is not successful it is solved again from its y0. The runs depend
    on the points' order (and, under ``jax.distributed``, on each process's share), not
    on the threads. Without, every point starts from its y0. Interrupted (Ctrl-C), the threads
    stop after the point each is solving."""
    memory = program.memory_analysis()
    per_point = None if memory is None else memory.temp_size_in_bytes
    workers = usable_cores() if not per_point else min(usable_cores(), max(1, DESIGN_BATCH_MEMORY // per_point))
    lower, upper, scale = host.arrays[:3]
    n, p = y0.shape[1], thetas.shape[1]
    x_at, derivatives_at, status_at = (slice(*host.layout[name]) for name in ("x", "derivatives", "status"))

    def solved(i, start):
        return np.asarray(program(arrays, start, thetas[i]))

    def successful(packed):
        return packed is not None and packed[status_at][0] == STATUS_NAMES.index("successful")

    def predicted(before, i):
        """Point i's start from the solution ``before`` of point i - 1, or None."""
        change = thetas[i] - thetas[i - 1]
        moved = change != 0.0
        derivatives = before[derivatives_at].reshape(n, p)[:, moved]
        if not successful(before) or not np.all(np.isfinite(derivatives)):
            return None
        x = before[x_at] + derivatives @ change[moved]
        return np.clip((x - lower) / scale, 0.0, (upper - lower) / scale)

    def run(head):
        packed = [first if head == 0 else solved(head, y0[head])]
        moved(1)
        for i in range(head + 1, min(head + length, len(y0))):
            if stopping:  # the main thread was interrupted (Ctrl-C): its answer is not wanted
                break
            start = predicted(packed[-1], i)
            result = None if start is None else solved(i, start)
            packed.append(result if successful(result) else solved(i, y0[i]))
            moved(1)
        return packed

    def moved(points):
        if bar is not None:
            bar.update(points)

    length = DESIGN_CHAIN if continuation else 1
    heads = range(0, len(y0), length)
    packed, stopping = [], []
    pool = ThreadPoolExecutor(max(1, min(workers, len(heads))))
    try:
        for results in pool.map(run, heads):
            packed += results
    except BaseException:
        stopping.append(True)  # the threads stop after their current point
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    return np.stack(packed)


def _in_chunks(key, arrays, y0, thetas, share, chunk, bar):
    """The packed solutions (points, width) of the points (y0, thetas) in vmapped chunks,
    each split over every local device (see :func:`solve_batch`)."""
    devices = jax.local_devices()
    # equal chunks, each a multiple of the device count: one compiled shape, little padding
    # (a batch that fits one chunk is padded to a power of two, so that sweeps of nearby
    # sizes share one compiled program)
    # (and at least about DESIGN_PROGRESS_STEPS chunks where the points allow, so that the
    # progress bar moves during a sweep of a few points)
    limit = chunk or DESIGN_CHUNK
    wanted = -(-share // DESIGN_PROGRESS_STEPS)
    size = min(1 << max(wanted - 1, 0).bit_length(), limit) if wanted <= limit else -(-share // -(-share // limit))
    size = -(-size // len(devices)) * len(devices)
    sharding = (
        NamedSharding(Mesh(np.array(devices), ("points",)), PartitionSpec("points")) if len(devices) > 1 else None
    )
    run, size = _batch_program(key, arrays, size, y0.shape[1], thetas.shape[1], sharding)
    packed = []
    for start in range(0, max(share, 1), size):
        part = [_padded(a[start : start + size], size) for a in (y0, thetas)]
        if sharding is not None:
            part = [jax.device_put(a, sharding) for a in part]
        packed.append(np.asarray(run(arrays, *part))[: max(0, min(size, y0.shape[0] - start))])
        if bar is not None:
            bar.update(packed[-1].shape[0])
    return np.concatenate(packed)


_PROGRAMS = {}  # (structure, chunk size, columns, devices) -> compiled batch program


def _batch_program(key, arrays, size, n, p, sharding):
    """(compiled program, chunk size) for chunks of ``size`` points, or of fewer where its
    working memory would pass DESIGN_BATCH_MEMORY (an axisymmetric dome's solve takes
    about 100 MB per point): read from XLA's memory analysis of the compiled program."""
    devices = 1 if sharding is None else sharding.mesh.size
    while True:
        entry = (key, size, n, p, devices)
        if entry not in _PROGRAMS:
            stage(
                f"compiling the solver for batches of {size} point{'s' if size > 1 else ''} "
                "(first call; later runs load it from the cache)"
            )
            if len(_PROGRAMS) >= 64:
                _PROGRAMS.clear()
            shape = lambda columns: jax.ShapeDtypeStruct((size, columns), jnp.float64, sharding=sharding)  # noqa: E731
            with _errors_as_nan(), gc_paused():
                _PROGRAMS[entry] = _compiled(key, True).lower(arrays, shape(n), shape(p)).compile()
        program = _PROGRAMS[entry]
        memory = program.memory_analysis()
        need = None if memory is None else memory.temp_size_in_bytes * devices
        if need is None or need <= DESIGN_BATCH_MEMORY or size <= devices:
            return program, size
        size = max(devices, int(size * DESIGN_BATCH_MEMORY / need) // devices * devices)


@contextlib.contextmanager
def _stdout_to_stderr():
    """File descriptor 1 sent to stderr for a while: for messages of C++ libraries that
    would break a reader of stdout (a JSON document)."""
    sys.stdout.flush()
    saved = os.dup(1)
    os.dup2(2, 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _padded(array, size):
    """``array`` (k, ...) cut or padded to (size, ...) by repeating its last row (a zero
    row where it is empty)."""
    if array.shape[0] >= size:
        return array[:size]
    last = array[-1:] if array.shape[0] else np.zeros((1, *array.shape[1:]), array.dtype)
    return np.concatenate([array, np.repeat(last, size - array.shape[0], axis=0)])


def multistart(
    problem: Problem,
    starts: dict,
    *,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
) -> DesignSweep:
    """Solve ``problem`` from a batch of starts {variable: (batch,) values (SI)} at once.

    Variables missing from ``starts`` start at their own start. Returns a
    :class:`DesignSweep` with one solution per start.
    """
    batch = {np.shape(value) for value in starts.values()}
    if len(batch) != 1 or len(next(iter(batch))) != 1:
        raise ValueError(f"starts: give one (batch,) array per variable, got shapes {sorted(batch)}")
    arrays = _host(problem).arrays
    y0 = _start(problem, starts, arrays)
    y0 = np.broadcast_to(y0, (next(iter(batch))[0], len(problem.variables)))
    thetas = np.repeat(arrays[4][None, :], y0.shape[0], axis=0)
    solution, seconds = solve_batch(problem, y0, thetas, settings_of(rtol, atol, max_steps))
    return DesignSweep.from_core(problem, solution, thetas, seconds)
