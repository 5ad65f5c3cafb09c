"""The core: the solver's loop (:mod:`magdesign.design._sqp.loop`) and its
:func:`postprocess`, which checks the polish's answer against the search's and gives the
implicit derivatives and the status, as one jitted, vmappable function."""

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from magdesign.design._sqp.jet import Settings, _lagrangian_hessian, problem_arrays
from magdesign.design._sqp.loop import SQPState, run
from magdesign.design._sqp.polish import _equations, _implicit_derivatives, _solvable
from magdesign.design._sqp.search import CONVERGED, NONFINITE_START, NOT_MINIMUM
from magdesign.design.problem import Problem
from magdesign.design.status import status_code


class CoreSolution(NamedTuple):
    """What the core returns (arrays; a leading batch axis under vmap). ``outputs`` holds
    the model outputs named by ``Problem.outputs``; m counts targets and limit rows. A
    NamedTuple, not an eqx.Module: the host builds one per solve, and constructing a
    Module costs about half of :func:`_unpack`'s time."""

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


def _core(problem: Problem, y0, theta, settings: Settings) -> CoreSolution:
    """The solver from y0 (n,) (scaled) with theta (p,) (SI): its loop (:func:`init`, then
    :func:`step` until :func:`terminate`: :func:`run`), then :func:`postprocess`."""
    lower, upper, scale, _, _ = problem_arrays(problem)
    state = run(problem, jax.lax.stop_gradient(y0), theta, settings, (upper - lower) / scale)
    return postprocess(problem, theta, settings, state)


def postprocess(problem: Problem, theta, settings: Settings, state: SQPState) -> CoreSolution:
    """The solution from the loop's last state: the polished root where it stands (else
    the search's point), the implicit derivatives in theta (p,) there, and the status."""
    n, n_targets = len(problem.variables), len(problem.targets)
    lower, upper, scale, _, _ = problem_arrays(problem)
    y_max = (upper - lower) / scale
    tol, sqp = settings.rtol, settings.sqp
    search, polish = state.search, state.polish
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
        dy = jnp.where(_solvable(equations, z, polished, theta, dz, sqp=sqp), dz[:n], jnp.nan)
    else:
        dy = jnp.zeros((n, 0))
    outputs, c = polished.outputs, polished.v[1:]
    # The polish refines the search's point; one that ends outside the box or far away
    # has found another solution of the equations, and the search's point stands, as it
    # does where the model is not finite at the polish's point, and where the polish breaks
    # a row that the search's point meets (with another QP Hessian, Newton's residual on the
    # badly scaled hs106 stalls 1.9e-10 outside a limit that the search's point holds to
    # 6e-16: "limit_violated"). With an objective, a polish that goes further stands where it
    # meets its equations to the design's tolerance at an objective no higher than the
    # search's point's, its held limits' and bounds' multipliers of the right sign (to
    # sqrt(rtol)): on 1e10 (x + y - 1)^2 + (x - y - 0.2)^2 the search, whose objective
    # (scaled to its gradient at the start) falls below rounding, stops 0.04 from the
    # minimum, and the polish's exact step there (0.009 of a box width, beyond
    # sqp.polish_reach) stands by this rule.
    near = jnp.max(jnp.abs(y - y_start)) <= sqp.polish_reach
    if problem.objective is not None:
        pull = search.weight * polished.J[0] + polished.J[1:].T @ multipliers  # a fixed variable's bound's multiplier
        signed = jnp.all(jnp.where(equations.equations[n_targets:], multipliers[n_targets:], 0.0) >= -jnp.sqrt(tol))
        signed = signed & jnp.all(jnp.where(active.at_lower, pull, 0.0) >= -jnp.sqrt(tol))
        signed = signed & jnp.all(jnp.where(active.at_upper, pull, 0.0) <= jnp.sqrt(tol))
        near = near | ((residual <= tol) & (polished.v[0] <= search.jet.v[0]) & signed)
    kept = (
        usable
        & jnp.all((y >= -sqp.on_constraint) & (y <= y_max + sqp.on_constraint))
        & near
        & (~jnp.any(_broken(c, n_targets, tol)) | jnp.any(_broken(search.jet.v[1:], n_targets, tol)))
    )
    y = jnp.where(kept, jnp.clip(y, 0.0, y_max), y_start)
    outputs = jnp.where(kept, outputs, search.jet.outputs)
    c = jnp.where(kept, c, search.jet.v[1:])

    # Stationarity is a gradient condition: met to sqrt(rtol), as the optimum's value is, or
    # to its own rounding (y's, through the Lagrangian's Hessian) where that is larger, as
    # after a start on a plateau, whose small gradient scales the objective up: max
    # exp(-(x - 1)^2) from x = -4 (gradient 3e-10) meets it at x = 1 only to 1.3e-5, with a
    # Hessian of 3e11, which sqrt(rtol) alone would call "max_steps_reached". Where the
    # polish is not kept, at the search's point, which then stands.
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
    status = jnp.asarray(status_code("successful"))
    for failed, name in reversed(
        [
            (~finite, "nonfinite"),
            (inner_failed, "mechanics_not_converged"),
            # A search cut short by max_steps says so, not that a target is out of reach.
            (search.phase < CONVERGED, "max_steps_reached"),
            (targets_broken, "infeasible_target"),
            (limits_broken, "limit_violated"),
            (search.phase == NOT_MINIMUM, "not_a_minimum"),
            (~kkt_met, "max_steps_reached"),
        ]
    ):
        status = jnp.where(failed, status_code(name), status)
    # Derivatives of the optimum exist only at one: NaN (null in JSON) where the status is not
    # successful (a point that breaks a target or a limit, a saddle, a search cut short), where
    # the polish was not kept or its implicit solve failed; never a plain 0 that reads as
    # "insensitive", nor a number that reads as the sensitivity of a design that is not one.
    derivatives = jnp.where(
        (status == status_code("successful")) & kept & jnp.isfinite(dy), scale[:, None] * dy, jnp.nan
    )
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
        status=status,
        steps=search.steps,
    )


def _broken(c, n_targets, tol):
    """(2,) bool: a target broken, a limit broken, in the scaled rows c (beyond ``tol``)."""
    return jnp.stack([jnp.any(jnp.abs(c[:n_targets]) > tol), jnp.any(c[n_targets:] > tol)])
