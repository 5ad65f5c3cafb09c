"""The design solver: bounded, constrained, exact, with implicit derivatives.

optimistix's least-squares and minimise solvers take no bounds, so the search is ours;
it works on variables scaled to their bound width, y = (x - lower) / scale in [0, y_max]:

1. feasibility: projected Levenberg-Marquardt (Gauss-Newton) on the scaled target
   residuals and limit violations, variables clipped to their box;
2. with an objective: projected damped Newton on the objective (scaled to a unit
   gradient) plus a quadratic penalty of phase 1's residuals; this finds which limits and
   bounds are active;
3. exact polish (active set): Newton on the KKT system of the targets, the active limits
   as equations and the active bounds as fixed variables, then a check of the
   multipliers' signs, the inactive limits and the box, repeated while the set changes.

At the solution the KKT residual R(z, theta) = 0 holds for z = (y, multipliers) and theta =
(target values, limit bounds), so the implicit function theorem gives
dz/dtheta = -R_z^+ R_theta (pseudo-inverse, which is the minimum-norm answer where no
objective picks one point of a manifold of solutions).

Everything after the Python-level unpacking is one jitted, vmappable function of a fixed
problem structure; the outcome is a status code, never an exception. The three phases run
as one loop (see :func:`_core`) whose body evaluates the model's jet (values, Jacobian,
Hessians) once, at the point it proposes: the model is traced once in the whole program,
so XLA compiles one copy of the model, not one per phase, and the outputs and the implicit
derivatives reuse the last jet.
"""

import functools
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from magdesign._numerics import (
    DESIGN_ACTIVE_TOL,
    DESIGN_ATOL,
    DESIGN_DAMPING_MAX,
    DESIGN_DAMPING_START,
    DESIGN_PENALTY,
    DESIGN_RTOL,
    DESIGN_START_NUDGE,
    safe_div,
)
from magdesign.design.problem import Problem
from magdesign.design.report import STATUS_NAMES, DesignResult, DesignSweep

# Status codes of the core, indices into STATUS_NAMES.
(SUCCESSFUL, INFEASIBLE_TARGET, LIMIT_VIOLATED, MAX_STEPS_REACHED, NONFINITE, MECHANICS_NOT_CONVERGED) = range(6)
_DAMPING_DOWN = 3.0
_DAMPING_UP = 4.0
# Rounds of the active-set polish: each adds or drops constraints found wrong by the last.
_ACTIVE_SET_ROUNDS = 4
# Inner rounds of a penalty step that settle which limit rows the step will violate.
_HINGE_ROUNDS = 3


class Settings(eqx.Module):
    """Solver settings: tolerances on scaled quantities and the steps allowed per phase."""

    rtol: Float[Array, ""]
    atol: Float[Array, ""]
    max_steps: int = eqx.field(static=True)


class CoreSolution(eqx.Module):
    """What the core returns (arrays; a leading batch axis under vmap). ``outputs`` holds
    the model outputs named by ``Problem.outputs``; m counts targets and limit rows."""

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

    theta stacks the target values, then each limit row's bound (SI). ``xp`` is jnp
    inside traced code and numpy outside, where it is much cheaper than eager jnp.
    """
    stack = lambda values: xp.stack([xp.asarray(v, xp.float64) for v in values]) if values else xp.zeros((0,))  # noqa: E731
    variables = problem.variables
    theta = [t.value for t in problem.targets] + [getattr(problem.limits[i], side) for i, side in problem.limit_rows]
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
    outputs = problem.model({v.name: x[i] for i, v in enumerate(problem.variables)})
    missing = [name for name in problem.outputs if name not in outputs]
    if missing:
        raise ValueError(f"{missing[0]}: not an output of the model (outputs: {sorted(outputs)})")
    n_targets = len(problem.targets)
    rows = [(outputs[t.output] - theta[k]) / t.scale for k, t in enumerate(problem.targets)]
    for k, (i, side) in enumerate(problem.limit_rows):
        limit = problem.limits[i]
        excess = outputs[limit.output] - theta[n_targets + k]
        rows.append((excess if side == "upper" else -excess) / limit.scale)
    c = jnp.stack(rows) if rows else jnp.zeros((0,))
    objective = problem.objective
    if objective is None:
        f = jnp.zeros(())
    else:
        f = (1.0 if objective.sense == "min" else -1.0) * objective.weight * outputs[objective.output]
    return outputs, c, f


def _violation(c, n_targets):
    """Penalty residuals: the target residuals and the limit rows' excess over 0."""
    return jnp.concatenate([c[:n_targets], jnp.maximum(c[n_targets:], 0.0)])


class Jet(eqx.Module):
    """The model at one scaled point y, m constraint rows and n variables.

    ``v`` = (weighted objective f, constraint rows c...) (1 + m,), scaled as in
    :func:`_evaluate`; ``J`` (1 + m, n) and ``H`` (1 + m, n, n) its first and second
    derivatives in y; ``outputs`` (k,) the model outputs named by ``Problem.outputs`` (SI).
    """

    v: Float[Array, " 1+m"]
    J: Float[Array, "1+m n"]
    H: Float[Array, "1+m n n"]
    outputs: Float[Array, " k"]


def _jet(problem, y, theta) -> Jet:
    """The :class:`Jet` at y from one trace of the model (forward over forward mode)."""

    def values(y):
        outputs, c, f = _evaluate(problem, y, theta)
        v = jnp.concatenate([f[None], c])
        return v, (v, jnp.stack([outputs[name] for name in problem.outputs]))

    def first(y):
        J, (v, outputs) = jax.jacfwd(values, has_aux=True)(y)
        return J, (J, v, outputs)

    if problem.objective is None:
        # Without an objective every multiplier is 0 at the solution, so the Lagrangian's
        # curvature (multipliers times H) vanishes: first derivatives suffice, and tracing
        # no second ones keeps models with costly kernels quick to compile.
        J, (_, v, outputs) = first(y)
        return Jet(v, J, jnp.zeros((*J.shape, y.shape[0])), outputs)

    H, (J, v, outputs) = jax.jacfwd(first, has_aux=True)(y)
    return Jet(v, J, H, outputs)


def _merit(jet, weight, penalty, n_targets):
    """The penalty merit w f + penalty/2 |violation(c)|^2 at a jet, and its gradient in y."""
    violation = _violation(jet.v[1:], n_targets)
    value = weight * jet.v[0] + 0.5 * penalty * jnp.dot(violation, violation)
    return value, weight * jet.J[0] + penalty * jet.J[1:].T @ violation


def _penalty_step(jet, y, y_max, weight, penalty, damping, relative_damping, n_targets):
    """A step of ``min w f(y) + penalty/2 |violation(c(y))|^2`` over 0 <= y <= y_max.

    The step minimises the model: f to second order, c linearised (Gauss-Newton), plus
    damping. The hinge max(0, c + J d) of a limit row is kept piecewise exact by a few
    inner rounds that include exactly the rows the step is predicted to violate: without
    them a step from the feasible side cannot see a limit coming and overshoots it, and
    the search creeps along the kink. Variables on a bound whose merit gradient points out
    of the box are frozen. The damping is relative to the largest curvature in least
    squares (Marquardt) and absolute with an objective, whose gradient is scaled to 1
    while the penalty curvature is huge. Returns the step (n,).
    """
    _, gradient = _merit(jet, weight, penalty, n_targets)
    f_grad, f_hess, c, J = weight * jet.J[0], weight * jet.H[0], jet.v[1:], jet.J[1:]
    free = ~(((y <= 0.0) & (gradient > 0.0)) | ((y >= y_max) & (gradient < 0.0)))
    both_free = free[:, None] & free[None, :]
    is_target = jnp.arange(c.shape[0]) < n_targets

    def hinge_round(rows, _):
        J_rows = jnp.where(rows[:, None], J, 0.0)
        H = f_hess + penalty * J_rows.T @ J_rows
        curvature = jnp.where(relative_damping, jnp.max(jnp.abs(jnp.diag(H))) + 1.0, 1.0)
        A = jnp.where(both_free, H, 0.0) + jnp.diag(jnp.where(free, damping * curvature, 1.0))
        rhs = jnp.where(free, f_grad + penalty * J_rows.T @ jnp.where(rows, c, 0.0), 0.0)
        delta = jnp.linalg.solve(A, -rhs)
        delta = jnp.where(jnp.isfinite(delta) & free, delta, 0.0)
        return is_target | (c + J @ delta > 0.0), delta

    _, deltas = jax.lax.scan(hinge_round, is_target | (c > 0.0), None, length=_HINGE_ROUNDS)
    return deltas[-1]


def _kkt(z, active, jet, y_max, f_weight, n_targets):
    """KKT residual R of the active set and its Jacobian dR/dz, z = (y, multipliers).

    Rows: stationarity of the Lagrangian on free variables (fixed ones: y - bound), then
    the targets and active limit rows as equations (inactive ones: multiplier = 0).
    Returns (R, dR/dz, stationarity, c).
    """
    active_limits, at_lower, at_upper = active
    v, J, H = jet.v, jet.J, jet.H
    n = y_max.shape[0]
    y, multipliers = z[:n], z[n:]
    c, J_c = v[1:], J[1:]
    m = c.shape[0]
    stationarity = f_weight * J[0] + J_c.T @ multipliers
    hessian = f_weight * H[0] + jnp.einsum("i,ijk->jk", multipliers, H[1:])
    fixed = at_lower | at_upper
    equations = jnp.concatenate([jnp.ones(n_targets, bool), active_limits])
    r_y = jnp.where(at_lower, y, jnp.where(at_upper, y - y_max, stationarity))
    r_c = jnp.where(equations, c, multipliers)
    top = jnp.concatenate([jnp.where(fixed[:, None], jnp.eye(n), hessian), jnp.where(fixed[:, None], 0.0, J_c.T)], 1)
    bottom = jnp.concatenate(
        [jnp.where(equations[:, None], J_c, 0.0), jnp.where(equations[:, None], 0.0, jnp.eye(m))], 1
    )
    return jnp.concatenate([r_y, r_c]), jnp.concatenate([top, bottom]), stationarity, c


def _theta_slopes(problem):
    """dc/dtheta of each constraint row (diagonal): -1/scale for targets and upper
    limits, +1/scale for lower limits."""
    slopes = [-1.0 / t.scale for t in problem.targets] + [
        (-1.0 if side == "upper" else 1.0) / problem.limits[i].scale for i, side in problem.limit_rows
    ]
    return jnp.stack(slopes) if slopes else jnp.zeros((0,))


def _pick(condition, new, old):
    """``new`` where ``condition`` holds, else ``old``, leaf by leaf."""
    return jax.tree.map(lambda a, b: jnp.where(condition, a, b), new, old)


# Phases of the core's loop; each iteration proposes a point, evaluates the model's jet
# there once, and then accepts or refuses it and moves between phases. RESTART takes the
# start back after a non-finite end; the loop stops at DONE or FAILED (that restart done).
START, FEASIBILITY, PENALTY, NEWTON, REEVALUATE, RESTART, DONE, FAILED = range(8)
# Which proposal and update each phase uses: 0 penalty step, 1 KKT Newton step, 2 stay.
_BRANCH_OF_PHASE = (2, 0, 0, 1, 2, 2, 2, 2)


class _State(eqx.Module):
    """The core's loop state (scaled variables; m constraint rows, l limit rows).

    ``z`` = (y, multipliers) with ``jet`` the model's jet at y. ``weight`` of the objective is 0 until the
    penalty phase scales it to a unit gradient. ``count`` counts the steps of the current
    phase (or Newton round), ``steps`` those of all phases; ``active_limits``, ``at_lower``,
    ``at_upper`` are the active set of the Newton rounds, ``changed`` whether the last
    round changed it, ``rounds`` the rounds so far.
    """

    phase: Int[Array, ""]
    z: Float[Array, " n+m"]
    jet: Jet
    weight: Float[Array, ""]
    damping: Float[Array, ""]
    count: Int[Array, ""]
    steps: Int[Array, ""]
    active_limits: Bool[Array, " l"]
    at_lower: Bool[Array, " n"]
    at_upper: Bool[Array, " n"]
    changed: Bool[Array, ""]
    rounds: Int[Array, ""]


def _core(problem: Problem, y0, theta, settings: Settings) -> CoreSolution:
    """The whole search as one loop over phases: START (evaluate y0), FEASIBILITY
    (penalty 1, relative damping), PENALTY (with an objective: penalty DESIGN_PENALTY,
    objective scaled to a unit gradient; only its active set is wanted, so it stops at a
    coarser step, sqrt(atol)), then NEWTON rounds on the KKT system of an active set,
    each followed by the set's update and, where the update clips y into the box,
    REEVALUATE; a non-finite end takes the start back (RESTART, then FAILED). Each
    iteration proposes a point by a small phase-dependent step that never calls the model,
    evaluates the jet there (the model's only trace), then accepts or refuses the point
    and moves between phases. Steps count those of FEASIBILITY, PENALTY and NEWTON."""
    n, n_targets, n_limits = len(problem.variables), len(problem.targets), len(problem.limit_rows)
    m = n_targets + n_limits
    has_objective = problem.objective is not None
    lower, upper, scale, _, _ = problem_arrays(problem)
    y_max = (upper - lower) / scale
    atol, tol = settings.atol, settings.rtol

    def phase_penalty(state):
        feasibility = state.phase == FEASIBILITY
        return jnp.where(feasibility, 1.0, DESIGN_PENALTY), feasibility

    def propose_penalty(state):
        penalty, feasibility = phase_penalty(state)
        y = state.z[:n]
        delta = _penalty_step(state.jet, y, y_max, state.weight, penalty, state.damping, feasibility, n_targets)
        return state.z.at[:n].set(jnp.clip(y + delta, 0.0, y_max)), jnp.concatenate([delta, jnp.zeros(m)]), jnp.asarray(True)

    def propose_newton(state):
        active = (state.active_limits, state.at_lower, state.at_upper)
        r, jacobian, _, _ = _kkt(state.z, active, state.jet, y_max, state.weight, n_targets)
        delta = -(jnp.linalg.solve(jacobian, r) if has_objective else jnp.linalg.pinv(jacobian) @ r)
        ok = jnp.all(jnp.isfinite(delta))
        delta = jnp.where(ok, delta, 0.0)
        return state.z + delta, delta, ok

    def stay(state):
        z = jnp.where(state.phase == RESTART, jnp.concatenate([y0, jnp.zeros(m)]), state.z)
        return z, jnp.zeros(n + m), jnp.asarray(True)

    def finish(z):
        return jnp.where(jnp.all(jnp.isfinite(z)), DONE, RESTART)

    def enter_newton(state):
        # At the penalty minimiser grad f + P J^T violation = 0: P violation estimates the
        # multipliers (0 without an objective, where no multiplier is needed).
        y, c = state.z[:n], state.jet.v[1:]
        violation = _violation(c, n_targets)
        multipliers = DESIGN_PENALTY * violation * has_objective
        gradient = state.weight * state.jet.J[0] + DESIGN_PENALTY * state.jet.J[1:].T @ violation
        return eqx.tree_at(
            lambda s: (s.phase, s.z, s.count, s.active_limits, s.at_lower, s.at_upper),
            state,
            (
                jnp.asarray(NEWTON),
                jnp.concatenate([y, multipliers]),
                jnp.asarray(0),
                c[n_targets:] > -DESIGN_ACTIVE_TOL,
                (y <= 0.0) & (gradient > 0.0),
                (y >= y_max) & (gradient < 0.0),
            ),
        )

    def after_penalty(state, z, delta, ok, jet):
        penalty, feasibility = phase_penalty(state)
        value, gradient = _merit(state.jet, state.weight, penalty, n_targets)
        value_trial, _ = _merit(jet, state.weight, penalty, n_targets)
        # A step that is no descent direction (possible while the damping has not yet made
        # an indefinite Hessian positive definite) is refused like one that fails.
        accept = (value_trial < value) & (jnp.dot(gradient, delta[:n]) < 0.0)
        damping = jnp.where(accept, state.damping / _DAMPING_DOWN, state.damping * _DAMPING_UP)
        xtol = jnp.where(feasibility, atol, jnp.sqrt(atol))
        count = state.count + 1
        finished = (jnp.max(jnp.abs(delta)) <= xtol) | (damping > DESIGN_DAMPING_MAX) | (count >= settings.max_steps)
        z, jet = _pick(accept, (z, jet), (state.z, state.jet))
        state = eqx.tree_at(
            lambda s: (s.z, s.jet, s.damping, s.count, s.steps), state, (z, jet, damping, count, state.steps + 1)
        )
        # With an objective scaled to a unit gradient, damping 1 bounds a step to about the box.
        penalty_start = eqx.tree_at(
            lambda s: (s.phase, s.weight, s.damping, s.count),
            state,
            (
                jnp.asarray(PENALTY),
                safe_div(1.0, jnp.linalg.norm(jet.J[0]), at_zero=1.0),
                jnp.asarray(1.0),
                jnp.asarray(0),
            ),
        )
        to_penalty = finished & feasibility & has_objective
        return _pick(to_penalty, penalty_start, _pick(finished, enter_newton(state), state))

    def after_newton(state, z, delta, ok, jet):
        count = state.count + 1
        going_on = eqx.tree_at(lambda s: (s.z, s.jet, s.count, s.steps), state, (z, jet, count, state.steps + 1))
        # The round ends: check the multipliers' signs, the inactive limits and the box.
        active = (state.active_limits, state.at_lower, state.at_upper)
        _, _, stationarity, c = _kkt(z, active, jet, y_max, state.weight, n_targets)
        y, multipliers = z[:n], z[n:]
        fixed = state.at_lower | state.at_upper
        new_limits = jnp.where(state.active_limits, multipliers[n_targets:] >= -tol, c[n_targets:] > tol)
        new_lower = jnp.where(state.at_lower, stationarity >= -tol, ~fixed & (y < 0.0))
        new_upper = jnp.where(state.at_upper, stationarity <= tol, ~fixed & (y > y_max))
        changed = (
            jnp.any(new_limits != state.active_limits)
            | jnp.any(new_lower != state.at_lower)
            | jnp.any(new_upper != state.at_upper)
        )
        clipped = jnp.clip(y, 0.0, y_max)
        rounds = state.rounds + 1
        z = z.at[:n].set(clipped)
        next_phase = jnp.where(
            jnp.any(clipped != y), REEVALUATE, jnp.where(changed & (rounds < _ACTIVE_SET_ROUNDS), NEWTON, finish(z))
        )
        round_end = eqx.tree_at(
            lambda s: (s.phase, s.z, s.count, s.active_limits, s.at_lower, s.at_upper, s.changed, s.rounds),
            going_on,
            (next_phase, z, jnp.asarray(0), new_limits, new_lower, new_upper, changed, rounds),
        )
        small = jnp.max(jnp.abs(delta[:n]), initial=0.0) <= atol
        return _pick(~ok | small | (count >= settings.max_steps), round_end, going_on)

    def after_stay(state, z, delta, ok, jet):
        # START goes on to FEASIBILITY, RESTART ends, REEVALUATE to the next round or the end.
        going_on = state.changed & (state.rounds < _ACTIVE_SET_ROUNDS)
        phase = jnp.select(
            [state.phase == START, state.phase == RESTART, going_on], [FEASIBILITY, FAILED, NEWTON], finish(z)
        )
        moved_on = eqx.tree_at(lambda s: (s.phase, s.z, s.jet, s.count), state, (phase, z, jet, jnp.asarray(0)))
        # A start where the model is flat in every direction (the centre of a symmetric
        # design, the bottom of a parabola to be maximised) offers no step at all: move it
        # once a little into the box, by a different amount per variable, and start again.
        flat = (state.phase == START) & (state.count == 0) & jnp.all(jet.J == 0.0)
        inward = jnp.where(z[:n] > 0.5 * y_max, -1.0, 1.0)
        nudge = inward * DESIGN_START_NUDGE * y_max * (1.0 + jnp.arange(n)) / n
        restarted = eqx.tree_at(lambda s: (s.z, s.count), state, (z.at[:n].add(nudge), jnp.asarray(1)))
        return _pick(flat, restarted, moved_on)

    def body(state):
        branch = jnp.asarray(_BRANCH_OF_PHASE)[state.phase]
        z, delta, ok = jax.lax.switch(branch, [propose_penalty, propose_newton, stay], state)
        jet = _jet(problem, z[:n], theta)
        return jax.lax.switch(branch, [after_penalty, after_newton, after_stay], state, z, delta, ok, jet)

    k = len(problem.outputs)
    blank = Jet(jnp.zeros(1 + m), jnp.zeros((1 + m, n)), jnp.zeros((1 + m, n, n)), jnp.zeros(k))
    no = lambda size: jnp.zeros(size, bool)  # noqa: E731
    state = _State(
        phase=jnp.asarray(START),
        z=jnp.concatenate([y0, jnp.zeros(m)]),
        jet=blank,
        weight=jnp.zeros(()),
        damping=jnp.asarray(DESIGN_DAMPING_START),
        count=jnp.asarray(0),
        steps=jnp.asarray(0),
        active_limits=no(n_limits),
        at_lower=no(n),
        at_upper=no(n),
        changed=jnp.asarray(True),
        rounds=jnp.asarray(0),
    )
    state = jax.lax.while_loop(lambda s: s.phase < DONE, body, state)

    finite, z, jet = state.phase == DONE, state.z, state.jet
    active = (state.active_limits, state.at_lower, state.at_upper)
    y, multipliers = z[:n], z[n:]
    r, r_z, _, c = _kkt(z, active, jet, y_max, state.weight, n_targets)
    # Implicit function theorem on R(z, theta) = 0; R depends on theta only through the
    # equation rows, each c_i linearly in its own theta_i.
    equations = jnp.concatenate([jnp.ones(n_targets, bool), state.active_limits])
    r_theta = jnp.concatenate([jnp.zeros((n, m)), jnp.diag(jnp.where(equations, _theta_slopes(problem), 0.0))])
    dz = -jnp.linalg.pinv(r_z) @ r_theta
    derivatives = jnp.where(jnp.isfinite(dz[:n]), scale[:, None] * dz[:n], 0.0)

    # Stationarity is a gradient condition: met to sqrt(rtol), as the optimum's value is.
    kkt_met = ~state.changed & (jnp.max(jnp.abs(r), initial=0.0) <= jnp.sqrt(tol))
    inner_failed = (
        jet.outputs[problem.outputs.index(problem.converged)] < 0.5 if problem.converged is not None else False
    )
    status = jnp.select(
        [
            ~finite,
            inner_failed,
            jnp.any(jnp.abs(c[:n_targets]) > tol),
            jnp.any(c[n_targets:] > tol),
            ~kkt_met,
        ],
        [NONFINITE, MECHANICS_NOT_CONVERGED, INFEASIBLE_TARGET, LIMIT_VIOLATED, MAX_STEPS_REACHED],
        SUCCESSFUL,
    )
    return CoreSolution(
        x=lower + scale * y,
        multipliers=multipliers,
        outputs=jet.outputs,
        residuals=c,
        active_limits=state.active_limits,
        at_lower=state.at_lower,
        at_upper=state.at_upper,
        derivatives=derivatives,
        status=status,
        steps=state.steps,
    )


def _packed(problem, y0, theta, settings):
    """The core's solution as one float64 vector, read back from the device in one go."""
    return jnp.concatenate([jnp.ravel(leaf).astype(jnp.float64) for leaf in jax.tree.leaves(_core(problem, y0, theta, settings))])


def _unpack(problem, packed):
    """CoreSolution of numpy arrays from :func:`_packed`'s vector(s) (leading batch axes kept)."""
    n, m, k = len(problem.variables), len(problem.targets) + len(problem.limit_rows), len(problem.outputs)
    sizes = {"x": n, "multipliers": m, "outputs": k, "residuals": m, "active_limits": m - len(problem.targets),
             "at_lower": n, "at_upper": n, "derivatives": n * m, "status": 1, "steps": 1}
    parts, start = {}, 0
    for name, size in sizes.items():
        parts[name] = packed[..., start : start + size]
        start += size
    batch = packed.shape[:-1]
    return CoreSolution(
        x=parts["x"],
        multipliers=parts["multipliers"],
        outputs=parts["outputs"],
        residuals=parts["residuals"],
        active_limits=parts["active_limits"] > 0.5,
        at_lower=parts["at_lower"] > 0.5,
        at_upper=parts["at_upper"] > 0.5,
        derivatives=parts["derivatives"].reshape(*batch, n, m),
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


@functools.lru_cache(maxsize=64)
def _compiled(key, batched):
    """The jitted core of one problem structure: (arrays, y0, theta) -> packed solution,
    vmapped over y0 and theta if ``batched``."""
    treedef, is_array, static = key

    def run(arrays, y0, theta):
        arrays = iter(arrays)
        leaves = [next(arrays) if array else leaf for array, leaf in zip(is_array, static)]
        problem, settings = jax.tree.unflatten(treedef, leaves)
        return _packed(problem, y0, theta, settings)

    return jax.jit(jax.vmap(run, in_axes=(None, 0, 0)) if batched else run)


def _run(problem, y0, theta, settings, *, batched=False):
    """The packed solution(s) as a numpy array, from the cached compiled core."""
    key, arrays = _split((problem, settings))
    return np.asarray(_compiled(key, batched)(arrays, y0, theta))


@functools.lru_cache(maxsize=16)
def _settings(rtol, atol, max_steps):
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
        max_steps: the most steps of each phase (feasibility, penalty, Newton polish).

    Returns:
        A :class:`DesignResult`: status ("successful", "infeasible_target",
        "limit_violated", "max_steps_reached", "nonfinite" or
        "mechanics_not_converged"), parameters, achieved
        targets and limits, active bounds and limits, steps, seconds, and the implicit
        derivatives of the parameters with respect to the target values and active limit
        bounds.
    """
    settings = _settings(rtol, atol, max_steps)
    arrays = problem_arrays(problem, np)
    y0, theta = _start(problem, start, arrays), arrays[4]
    began = time.perf_counter()
    packed = _run(problem, y0, theta, settings)
    seconds = time.perf_counter() - began
    return DesignResult.from_core(problem, _unpack(problem, packed), theta, seconds, settings.rtol)


def _solve_batch(problem, y0, theta, settings):
    began = time.perf_counter()
    packed = _run(problem, y0, theta, settings, batched=True)
    return _unpack(problem, packed), time.perf_counter() - began


def sweep(
    problem: Problem,
    target: str,
    values: Float[ArrayLike, " batch"],
    *,
    start: dict | None = None,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
) -> DesignSweep:
    """Solve ``problem`` for each value (SI) of one target, in one vmapped batch.

    Args:
        problem: the design problem; ``target`` names one of its targets (its output).
        values: (batch,) the target values to solve for (SI).
        start, rtol, atol, max_steps: as in :func:`solve`; the same start for every value.

    Returns:
        A :class:`DesignSweep` of (batch,) arrays, with the implicit derivatives.
    """
    names = [t.output for t in problem.targets]
    if target not in names:
        raise ValueError(f"target: {target!r} is not a target of the problem (targets: {names})")
    values = np.atleast_1d(np.asarray(values, np.float64))
    arrays = problem_arrays(problem, np)
    thetas = np.repeat(arrays[4][None, :], values.shape[0], axis=0)
    thetas[:, names.index(target)] = values
    y0 = np.broadcast_to(_start(problem, start, arrays), (values.shape[0], len(problem.variables)))
    solution, seconds = _solve_batch(problem, y0, thetas, _settings(rtol, atol, max_steps))
    return DesignSweep.from_core(problem, solution, thetas, seconds)


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
    arrays = problem_arrays(problem, np)
    y0 = _start(problem, starts, arrays)
    y0 = np.broadcast_to(y0, (next(iter(batch))[0], len(problem.variables)))
    thetas = np.repeat(arrays[4][None, :], y0.shape[0], axis=0)
    solution, seconds = _solve_batch(problem, y0, thetas, _settings(rtol, atol, max_steps))
    return DesignSweep.from_core(problem, solution, thetas, seconds)
