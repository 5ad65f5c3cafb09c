"""The design solver's thresholds: :class:`SQP`, every one a field with its default."""

import dataclasses

import equinox as eqx


class SQP(eqx.Module):
    """The design solver (sequential quadratic programming, then a Newton polish; see
    :mod:`magdesign.design._sqp`) and its thresholds, passed as
    ``solve(problem, solver=SQP(...))`` (also to ``multistart`` and ``sweep``). The
    defaults are the solver's; a changed field compiles a program of its own. The
    tolerances of a solve (rtol, atol, max_steps) are arguments of ``solve``.

    Every threshold acts on dimensionless quantities: variables scaled to their bound width
    (a box of width 1), constraint rows scaled by their target or limit, the objective
    scaled to a unit gradient at the start, so that multipliers are O(1)-O(100).

    Attributes:
        elastic: the cost per unit of an elastic slack of the QP (a target or limit row
            relaxed where its linearisation cannot be met): far above any multiplier, so
            that a linearisation that can be met is met exactly.
        elastic_rounding: a row's QP multiplier within this (relative) of ``elastic`` is
            the elastic price: the row's slack is in use, and the row is not held.
        hessian_floor: the smallest eigenvalue modulus of the QP's Hessian, relative to its
            largest (plus 1): bounds a step where the model is flat (to 1e4 box widths, so
            that the QP's own 1e-12 residuals move it by 1e-8 at most). It is taken off
            along the targets' gradients, and along the limits that a first solve holds
            with a multiplier above ``held_multiplier``, where their linearisation fixes
            the step.
        held_multiplier: see ``hessian_floor``: a smaller multiplier holds its limit too
            weakly to stand in for the floor.
        kept_curvature: a curvature of either sign whose modulus is above this (relative,
            as ``hessian_floor``) keeps its modulus, so that a degenerate minimum's
            vanishing curvature (x^4 at 0) and a gently concave direction beside a stiff
            one get Newton's steps, not gradient steps that crawl.
        dependent_met: where the rows and bounds that the last step held are dependent
            (more than their rank) at a point that meets every row within this (l1), the
            Hessian is made definite on their null space apart from the rest, where the
            moduli of curvatures of both signs would otherwise add up.
        active_multiplier: a limit row or bound is active where its QP multiplier exceeds
            this and its slack (with an objective; also where the step ends on it within
            ``rounded``, weakly active).
        on_constraint: without an objective, a row or bound is active where the step ends
            within this of it; a polished point this far outside the box is rejected.
        rounded: the step ends on a limit or bound (weakly active) within this, its
            rounding.
        null_space_rtol: the active constraints' null space: directions whose singular
            value is below this, relative to the largest, are free (rows are O(1)
            gradients, so this separates a dependent row from rounding by decades either
            way); also the pseudo-inverses' cut-off, the regulariser of the gradients on
            the Hessian's flat directions, and the least share of a limit's squared
            gradient on those directions for a second solve to hold it.
        curvature_tol: negative curvature of the Lagrangian on the active constraints' null
            space below -curvature_tol (relative to its largest curvature, plus 1) makes a
            stationary point no minimum.
        escapes: the most escapes (along negative curvature) and probes of a search.
        flat_curvature: a stationary point whose least curvature is below this (relative,
            as ``curvature_tol``) is probed on both sides before it is accepted (x^3 at 0
            has zero curvature).
        linear_rate: steps that shrink by less than this factor from one point to the next
            converge linearly, as they do to a degenerate point: it is probed too.
        probe_first, probe_shrink, probe_last: a probe tries the arc along its direction at
            ``probe_first`` box widths, each on both sides, shrinking by ``probe_shrink``
            down to ``probe_last``, before it accepts the point.
        parallel: a probe's second direction within this cosine of its first adds nothing.
        face_rows: the most weakly active rows and bounds whose faces the search goes
            through to find a direction that leaves a blocked saddle.
        gradient_floor: the objective's scale (1 / its gradient's norm at the start) counts
            a gradient no smaller than this times its Hessian's norm there: next to a
            minimum (a sweep's predicted start) the gradient is rounding.
        start_nudge: the fraction of a variable's bound width by which a start where the
            model is flat in every direction (no gradient, so no step) moves into the box:
            enough to leave an exactly symmetric point, too little to change which optimum
            is found nearby.
        armijo: Armijo's sufficient-decrease fraction of the line search.
        shortest_step: the shortest fraction of a step that the line search tries.
        rounding: a probe's merit counts as lower only below this times (1 + |merit|).
        met_row: scaled rows within this of their target or limit count as met in the merit
            function (far below the tolerance on them, above their rounding), so that their
            rounding noise cannot drown the objective's decrease near a solution.
        history: the line search compares a step's merit with the largest of the last
            ``history`` accepted points' (nonmonotone: Grippo, Lampariello and Lucidi,
            "A nonmonotone line search technique for Newton's method", 1986), so that a
            curved constraint's second-order violation does not stop the steps.
        penalty_floor: the merit's penalty starts at, and never falls below, this.
        radius_growth, radius_floor: the step's radius (an inf-norm trust region on the
            subproblem): none until the line search first shortens a step, then the length
            it shortened the last one to, grown by ``radius_growth`` after each whole step
            that reaches it, never below ``radius_floor`` times the step tolerance.
        growth_gain: without an objective, the radius grows only after a step that gained
            at least this fraction of the merit's decrease that its linearisation promised.
        polish_reach: the polish's root further than this from the search's point (box
            width 1) is another solution of the equations, and the search's point stands,
            unless (with an objective) the root meets the equations to the tolerance at an
            objective no higher, its multipliers of the right sign.
        solvable_rtol: the implicit derivatives with respect to a target's value or a
            limit's bound exist where the linear system they solve has a solution: its
            residual at the least-squares answer within this (relative to its terms).
        chunk: the most points per compiled batch of a sweep (memory), with the per-call
            overhead kept small.
        batch_memory: the most working memory (bytes, XLA's estimate for the compiled
            batch) a chunk, or the threads of a point-per-call sweep together, may take.
        point_seconds: a model with loops of its own whose single solve takes longer than
            this (s) is swept a point per call on parallel threads, not in vmapped batches
            whose lanes wait for the slowest.
        chain: such a sweep solves its points in runs of this many, each after the first
            of a run started from the optimum that the point before predicts with its
            implicit derivatives (continuation).
    """

    elastic: float = 1e6
    elastic_rounding: float = 1e-6
    hessian_floor: float = 1e-4
    held_multiplier: float = 1e-4
    kept_curvature: float = 1e-8
    dependent_met: float = 1e-5
    active_multiplier: float = 1e-8
    on_constraint: float = 1e-9
    rounded: float = 1e-15
    null_space_rtol: float = 1e-9
    curvature_tol: float = 1e-7
    escapes: int = 4
    flat_curvature: float = 1e-6
    linear_rate: float = 0.25
    probe_first: float = 1.0
    probe_shrink: float = 1.0 / 8.0
    probe_last: float = 1.0 / 512.0
    parallel: float = 0.99
    face_rows: int = 4
    gradient_floor: float = 1e-6
    start_nudge: float = 1e-3
    armijo: float = 1e-4
    shortest_step: float = 1e-12
    rounding: float = 1e-13
    met_row: float = 1e-13
    history: int = 8
    penalty_floor: float = 1.0
    radius_growth: float = 2.0
    radius_floor: float = 10.0
    growth_gain: float = 0.75
    polish_reach: float = 1e-4
    solvable_rtol: float = 1e-6
    chunk: int = 4096
    batch_memory: int = 1 << 30
    point_seconds: float = 0.02
    chain: int = 8

    def in_program(self) -> "SQP":
        """This solver with the fields that only the host reads for batches (``chunk``,
        ``batch_memory``, ``point_seconds``, ``chain``) at their defaults: what keys a
        compiled program, so that those fields compile no program of their own."""
        return dataclasses.replace(self, **{name: getattr(_DEFAULT, name) for name in _HOST_FIELDS})


_HOST_FIELDS = ("chunk", "batch_memory", "point_seconds", "chain")
_DEFAULT = SQP()
