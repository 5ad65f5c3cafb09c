"""The search: its phases and state (:class:`SearchState`), and the functions that move
it, each a module-level function of the problem, the settings and the state: the point
to try next (:func:`prepare`), the line search on the merit with its escapes and probes
(:func:`update`), and the subproblem at an accepted point with the choice of what comes
next (:func:`accept`). :mod:`magdesign.design._sqp.loop` steps them in one loop with the
polish."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

from magdesign._numerics import safe_div
from magdesign.design._qp import where_needed
from magdesign.design._sqp.curvature import _bend, _least_curvature, _limits_room, _room, _saddle_on_faces
from magdesign.design._sqp.jet import Jet, Settings, _pick
from magdesign.design._sqp.merit import _merit, _merit_parts, _priced, _violation
from magdesign.design._sqp.sqp import SQP
from magdesign.design._sqp.step import _held_rows, _no_slack_rows, _settled_step, _Step, _step
from magdesign.design.problem import Problem

# Phases of the search. Each iteration tries one point and evaluates the model's jet there
# once; the search ends at the first phase from CONVERGED on (and the loop goes on with
# the polish).
START, SEARCH, ESCAPE, PROBE, CONVERGED, STALLED, NOT_MINIMUM, NONFINITE_START = range(8)


class SearchState(eqx.Module):
    """The search's state (scaled variables). ``y`` is the accepted point, ``jet`` the
    model there, ``step`` the subproblem's answer at y; the search tries the point
    y + alpha direction, plus alpha^2 correction where ``bent``: ``direction`` is the
    step, or a direction of negative or zero curvature, and ``correction`` its second-order
    correction on the active constraints (:func:`_bend`; a step is bent where its whole
    length failed straight, ``straight`` then being the merit it reached, or from its
    first try where ``bend_first``, the last step having been bent); ``alpha`` the fraction
    tried next; the line search asks for a merit below the largest in the ``history``
    + ARMIJO (alpha slope + alpha^2 curvature), ``history`` holding the weighted objective
    and the violation of the last sqp.history accepted points of the search (the first this
    one's), priced at the present penalty (along a direction that is no descent,
    ``merit`` alone). ``radius`` bounds the subproblem's step
    (``SQP.radius_growth``). ``nu`` is the merit's penalty, ``weight`` the objective's
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


def _empty_history(sqp: SQP):
    """(sqp.history, 2) a history that holds no point (see :class:`SearchState`)."""
    return np.stack([np.full(sqp.history, -np.inf), np.zeros(sqp.history)], axis=1)


def search_start(problem: Problem, y0, settings: Settings) -> SearchState:
    """The search's state before its first trip, at y0 (n,) (scaled): phase START, no
    jet yet (a blank one), no step, the penalty at its floor, an empty history."""
    n, n_targets, sqp = y0.shape[0], len(problem.targets), settings.sqp
    m = max(n_targets + len(problem.limit_rows), 1)  # with _evaluate's row that never binds
    blank_jet = Jet(jnp.zeros(1 + m), jnp.zeros((1 + m, n)), jnp.zeros((1 + m, n, n)), jnp.zeros(len(problem.outputs)))
    no = lambda size: jnp.zeros(size, bool)  # noqa: E731
    return SearchState(
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
        nu=jnp.asarray(sqp.penalty_floor),
        bent=jnp.asarray(False),
        straight=jnp.asarray(0.0),
        weight=jnp.asarray(1.0),
        escapes=jnp.asarray(0),
        nudged=jnp.asarray(False),
        steps=jnp.asarray(0),
        radius=jnp.asarray(jnp.inf),
        history=_empty_history(sqp),
        bend_first=jnp.asarray(False),
        second=jnp.zeros(n),
        second_correction=jnp.zeros(n),
    )


def _bend_operands(state: SearchState):
    """:func:`_bend`'s operands for the step at the accepted point: its active rows."""
    return state.jet, state.step.d, _held_rows(state.step), state.step.at_lower | state.step.at_upper


def _leaving(v, gradient, y, y_max, jet, n_targets, *, sqp: SQP):
    """(v, its room in the box, the most room either way in the box and the limits):
    leave a saddle downhill, or, where flat, towards the side with more room in the
    box and the limits, then in the box alone. At (0, 1), a vertex of
    min -(x^2 + 2 y^2) on x + y <= 1, y <= 1, whose limit holds with no multiplier,
    the box's room alone would choose +x, across the limit, where every escape fails
    and the point reads "not_a_minimum"."""
    v = jnp.where(jnp.dot(gradient, v) > 0.0, -v, v)
    box = jnp.stack([_room(y, v, y_max), _room(y, -v, y_max)])
    held = jnp.minimum(
        box, jnp.stack([_limits_room(jet, v, n_targets, sqp=sqp), _limits_room(jet, -v, n_targets, sqp=sqp)])
    )
    wider = (held[1] > held[0]) | ((held[1] == held[0]) & (box[1] > box[0]))
    flip = (jnp.dot(gradient, v) == 0.0) & wider
    return jnp.where(flip, -v, v), jnp.where(flip, box[1], box[0]), jnp.max(held)


def accept(problem: Problem, settings: Settings, y_max, state: SearchState, y, jet: Jet) -> SearchState:
    """Take y (n,) as the new point, where the model's :class:`Jet` is ``jet``: solve the
    subproblem there and choose what comes next."""
    n, n_targets, sqp = y.shape[0], len(problem.targets), settings.sqp
    xtol = jnp.sqrt(settings.atol)
    no_point = _empty_history(sqp)
    searched = state.phase == SEARCH
    taken = jnp.max(jnp.abs(state.direction))
    radius = jnp.where(searched & (state.alpha < 1.0), state.alpha * taken, state.radius)
    reached = searched & (state.alpha == 1.0) & (taken >= 0.9 * state.radius)
    stuck = jnp.asarray(False)
    if problem.objective is None:
        # Without an objective the QP knows no curvature of the rows: next to the point
        # closest to a target that no point meets (sin x = 2 near pi / 2, x^2 = -1 at 0)
        # its steps overshoot that point by the radius, to and fro, and the nonmonotone
        # merit takes them, up to "max_steps_reached". A step taken uphill, beyond which
        # the violation rises again (its gradient there points along the step), has
        # overshot: it halves the radius, and one so taken at the radius's floor leaves
        # no shorter step to try: the point is stationary. (A step downhill does not
        # halve it: along Powell's badly scaled system, whose nearly met rows change
        # sign from step to step, halving on every overshoot takes 60 steps where this
        # takes 19.) The radius grows only after a step that gained at least
        # sqp.growth_gain of the merit's decrease that its linearisation promised (on x^2's
        # way to 0 a step of half the distance gains 3/4 of it).
        rising = jax.grad(_violation)(jet.v[1:], n_targets, sqp=sqp) @ jet.J[1:]  # the violation's gradient in y
        gained = state.merit - _merit(jet, state.weight, state.nu, n_targets, sqp=sqp)
        overshot = searched & (gained < 0.0) & (jnp.dot(rising, state.direction) > 0.0)
        stuck = overshot & (state.alpha * taken <= sqp.radius_floor * xtol)
        reached = reached & ~overshot & (gained >= -sqp.growth_gain * state.alpha * state.slope)
        radius = jnp.where(overshot, 0.5 * state.alpha * taken, radius)
    radius = jnp.maximum(jnp.where(reached, sqp.radius_growth * state.radius, radius), sqp.radius_floor * xtol)
    if problem.objective is not None:
        step, bound_multipliers = _settled_step(
            jet, y, y_max, state.step, state.bound_multipliers, state.weight, n_targets, radius, xtol, sqp=sqp
        )
    else:  # the Hessians are not used (see _jet): one solve
        step, bound_multipliers, _ = _step(
            jet, y, y_max, state.step, state.bound_multipliers, state.weight, n_targets, False, radius, sqp=sqp
        )
    # The penalty stays at least max(twice the multipliers, sqp.penalty_floor) and falls
    # halfway towards that at each point (Powell's update, with one penalty for all
    # rows, where SLSQP keeps one per row, and a floor): after an elastic step
    # (multipliers at sqp.elastic) a penalty kept at 2e6 while the multipliers fall
    # to 2e-3 would make the merit of hs069's curved targets' second-order violation
    # (1e-9) outweigh the objective's decrease (steps of 1e-3 to and fro, to
    # "max_steps_reached").
    # Without the floor the penalty falls with the vanishing multipliers of hs047's
    # degenerate minimum, and its probe takes an infeasible point.
    need = jnp.maximum(2.0 * jnp.max(jnp.abs(step.multipliers), initial=0.0), sqp.penalty_floor)
    nu = jnp.maximum(need, 0.5 * (state.nu + need))
    parts = _merit_parts(jet, state.weight, n_targets, sqp=sqp)
    merit = _priced(parts, nu)
    gradient = state.weight * jet.J[0]
    # The merit's directional derivative along the step; never above 0, so that a
    # step which is no descent direction (an inexact subproblem) is taken only downhill.
    slope = jnp.dot(gradient, step.d) - nu * (_violation(jet.v[1:], n_targets, sqp=sqp) - step.linear_violation)
    slope = jnp.minimum(slope, 0.0)
    stationary = (jnp.max(jnp.abs(step.d)) <= xtol) | stuck
    linear = jnp.max(jnp.abs(step.d)) >= sqp.linear_rate * jnp.max(jnp.abs(state.step.d))
    approach = jnp.where(linear, step.d, 0.0)
    # Only a stationary point's curvature is read: its SVD and eigenvalues run only there.
    curvature, v, w, u, wu = where_needed(
        stationary & (problem.objective is not None),
        lambda operands: _least_curvature(*operands, n_targets, sqp=sqp),
        (jet, step, bound_multipliers, state.weight, approach),
        (jnp.ones(()), jnp.zeros(n), jnp.zeros(n), jnp.zeros(n), jnp.zeros(n)),
    )

    v, room, most = _leaving(v, gradient, y, y_max, jet, n_targets, sqp=sqp)
    # Where weakly active rows block v both ways, the faces of the cone they leave give
    # the least curvature of a direction that leaves the point, signed to leave
    # (_saddle_on_faces); where none leaves, the point is a minimum on that cone.
    blocked = stationary & (curvature < -sqp.curvature_tol) & (most <= 0.0)
    decided, found, face_curvature, face_v, face_w = where_needed(
        blocked,
        lambda operands: _saddle_on_faces(*operands, n_targets, sqp=sqp),
        (jet, step, bound_multipliers, state.weight, y, y_max),
        (jnp.asarray(False), jnp.asarray(False), curvature, v, w),
    )
    on_face = blocked & found
    curvature = jnp.where(on_face, face_curvature, jnp.where(blocked & decided, 1.0, curvature))
    v, room = jnp.where(on_face, face_v, v), jnp.where(on_face, _room(y, face_v, y_max), room)
    w = jnp.where(on_face, face_w, w)
    saddle = stationary & (curvature < -sqp.curvature_tol)
    escape = saddle & (state.escapes < sqp.escapes) & (room > 0.0)
    # A stationary point whose curvature is too small to tell a minimum (x^3 at 0, a
    # ridge of -x^4), or which the steps approached only linearly (as they approach a
    # degenerate point, where at a minimum with curvature Newton's steps shrink
    # quadratically), is probed on both sides before it is accepted (a stationary start
    # too: no steps tell how it was approached). Without an objective there is no
    # minimum to confirm, nor a direction to probe (every probe would try the point itself).
    flat = (curvature <= sqp.flat_curvature) | linear
    probe = stationary & ~saddle & flat & (state.escapes < sqp.escapes) & (problem.objective is not None)
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
            jnp.where(probe, sqp.probe_first, 1.0),
            merit,
            jnp.where(escape, jnp.dot(gradient, v), slope),
            jnp.where(escape, 0.5 * curvature, 0.0),
            nu,
            escape | probe,
            state.escapes + (escape | probe),
            radius,
            # a larger penalty would make the old points' merits lenient; a search restarts
            # its history then, and after an escape or a probe
            jnp.where((nu > state.nu) | ~searched, no_point, jnp.roll(state.history, 1, axis=0)).at[0].set(parts),
            searched & state.bent,
            jnp.where(probe, u, 0.0),
            jnp.where(probe, wu, 0.0),
        ),
    )


def prepare(problem: Problem, settings: Settings, y_max, state: SearchState, polishing):
    """(state, trial): the point that the search tries next. After a step that needed
    bending, the next is bent from its first try (curved constraints stay curved:
    trying it straight first costs an evaluation a step)."""
    sqp = settings.sqp
    alpha = state.alpha
    bend_now = ~polishing & (state.phase == SEARCH) & ~state.bent & (alpha == 1.0) & state.bend_first
    if problem.objective is not None:
        correction = where_needed(
            bend_now, lambda operands: _bend(*operands, sqp=sqp), _bend_operands(state), state.correction
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


def update(problem: Problem, settings: Settings, y_max, state: SearchState, trial, jet: Jet) -> SearchState:
    """The search's next state, where the model's jet at ``trial`` is ``jet``."""
    n, n_targets, sqp = trial.shape[0], len(problem.targets), settings.sqp
    start = state.phase == START
    alpha = state.alpha
    finite = jnp.all(jnp.isfinite(jet.v)) & jnp.all(jnp.isfinite(jet.J)) & jnp.all(jnp.isfinite(jet.H))
    state = eqx.tree_at(lambda s: s.steps, state, state.steps + 1)

    # START: a start where the model is flat in every direction (the centre of a
    # symmetric design) offers no step at all: move it once a little into the box, by
    # a different amount per variable; otherwise scale the objective and accept it
    # (to a unit gradient, counted no smaller than sqp.gradient_floor times the
    # Hessian: next to a stationary point 1 / |gradient| leaves the polish only rounding).
    flat = start & ~state.nudged & jnp.all(jet.J == 0.0)
    inward = jnp.where(trial > 0.5 * y_max, -1.0, 1.0)
    nudge = inward * sqp.start_nudge * y_max * (1.0 + jnp.arange(n)) / n
    nudged = eqx.tree_at(lambda s: (s.y, s.nudged), state, (trial + nudge, jnp.asarray(True)))
    size = jnp.maximum(jnp.linalg.norm(jet.J[0]), sqp.gradient_floor * jnp.linalg.norm(jet.H[0]))
    scaled = eqx.tree_at(lambda s: s.weight, state, safe_div(1.0, size, at_zero=1.0))
    accepted = accept(problem, settings, y_max, _pick(start, scaled, state), trial, jet)
    not_started = eqx.tree_at(lambda s: s.phase, state, jnp.asarray(NONFINITE_START))

    # SEARCH, ESCAPE: Armijo's test on the merit, else a shorter step. PROBE: a merit
    # lower by more than rounding, else the other side, then a shorter arc, and the
    # point stands (CONVERGED) after the shortest.
    probing = state.phase == PROBE
    merit = _merit(jet, state.weight, state.nu, n_targets, sqp=sqp)
    # nonmonotone only in the search and along a descent direction (the history's
    # first entry is this point's merit)
    merits = _priced(state.history, state.nu)
    reference = jnp.where((state.phase == SEARCH) & (state.slope < 0.0), jnp.max(merits), state.merit)
    wanted = reference + sqp.armijo * (alpha * state.slope + alpha**2 * state.curvature)
    wanted = jnp.where(probing, state.merit - sqp.rounding * (1.0 + jnp.abs(state.merit)), wanted)
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
    correction = where_needed(
        may_bend, lambda operands: _bend(*operands, sqp=sqp), _bend_operands(state), state.correction
    )
    bend = may_bend & jnp.any(correction != 0.0)
    next_alpha = jnp.where(probing, jnp.where(alpha > 0.0, -alpha, -alpha * sqp.probe_shrink), 0.5 * alpha)
    next_alpha = jnp.where(bend, alpha, next_alpha)
    keep = state.bent & ((alpha < 1.0) | (merit < state.straight))
    bent = jnp.where(state.phase == SEARCH, bend | keep, state.bent)
    straight = jnp.where(bend, merit, state.straight)
    shorter = eqx.tree_at(
        lambda s: (s.alpha, s.bent, s.straight, s.correction), state, (next_alpha, bent, straight, correction)
    )
    given_up = jnp.select([state.phase == ESCAPE, probing], [NOT_MINIMUM, CONVERGED], STALLED)
    failed = eqx.tree_at(lambda s: s.phase, shorter, given_up)
    too_short = jnp.abs(next_alpha) < jnp.where(probing, sqp.probe_last, sqp.shortest_step)
    # A probe that finds nothing along its direction tries its second, if it has one.
    turned = eqx.tree_at(
        lambda s: (s.direction, s.correction, s.alpha, s.second, s.second_correction),
        shorter,
        (state.second, state.second_correction, jnp.asarray(sqp.probe_first), jnp.zeros(n), jnp.zeros(n)),
    )
    failed = _pick(probing & jnp.any(state.second != 0.0), turned, failed)
    searched = _pick(good, accepted, _pick(too_short, failed, shorter))
    return _pick(start, _pick(flat, nudged, _pick(finite, accepted, not_started)), searched)
