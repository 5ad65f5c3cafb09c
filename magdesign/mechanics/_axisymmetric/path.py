"""The force-travel path of the axisymmetric dome.

The path followers (:func:`follow_travels`, :func:`first_crossings`) step the plate travel
adaptively from the undeformed dome with a secant predictor, each step one
:func:`~magdesign.mechanics._axisymmetric.equilibrium.newton` solve with the travel held;
a force level that a step carried is solved with the force held from the cubic Hermite
interpolant from the step's start (or a lighter level already solved in that step) to the
step's end, whose tangents come from Newton's last Hessian. Neither follower is
differentiated: their equilibria are, implicitly
(:func:`~magdesign.mechanics._axisymmetric.equilibrium.implicit`).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax

from magdesign.mechanics import _blocks
from magdesign.mechanics._axisymmetric.equilibrium import NEWTON_MAX_ITER, _control, _factor, newton

# Path following: steps at most, and the Newton iterations at or below which a step doubles
# and from which on it halves. A step that needed many iterations is not repeated at the same
# length: the next one, as long, is likely to fail after PATH_NEWTON_MAX_ITER.
PATH_MAX_STEPS = 80
PATH_NEWTON_MAX_ITER = 20
PATH_EASY_ITER = 8
PATH_HARD_ITER = 12
# A failed step is retried at a quarter of its length until it is shorter than this
# fraction of the wall: then the path has met a snap (the equilibrium with the travel held
# ceases to exist, as where the apex of a thin dome inverts and leaves the plate), and the
# next step jumps: Newton descends the potential from the last state, with up to
# SNAP_MAX_ITER iterations, to the equilibrium the dome snaps to at a travel this much
# further. A failed jump ends the path.
SNAP_STEP = 1e-2
SNAP_MAX_ITER = 200
# Bisections of the interval of a path step that find where its Hermite interpolated
# force meets a level (2^-50: the travel to rounding).
HERMITE_BISECTIONS = 50


class Path(eqx.Module):
    """A point of a followed force-travel path: the state y (size,) at travel y[-1] (m),
    its plate force (N), its tangent dy/dd (size,) and stiffness dF/dd (N/m) along the
    path, the state before it (for the secant predictor), the next travel step (m), and
    the count of steps tried. ``cut``: the last step tried failed (and ``step`` was cut to a
    quarter of it); ``failed``: a snap's jump did not converge; ``shift``: the index of the
    Levenberg shift its steps last needed (0: none yet; see :func:`newton`)."""

    y: jax.Array
    force: jax.Array
    tangent: jax.Array
    stiffness: jax.Array
    previous: jax.Array
    step: jax.Array
    count: jax.Array
    cut: jax.Array
    failed: jax.Array
    shift: jax.Array

    def can_go_on(self, max_travel):
        return ~self.failed & (self.count < PATH_MAX_STEPS) & (self.y[-1] < max_travel)


def _tangent(mesh, H):
    """(dy/dd (size,), dF/dd (N/m)) along the travel-held equilibria through a state whose
    Hessian is H: the unknowns' rows of the tangent system with the travel moving, t[-1] = 1."""
    mask = mesh.mask(False)
    column = H.last_column(mesh.layout)
    tangent = -_blocks.solve(mesh.layout, _factor(mesh, H.restricted(mesh.layout, mask))[0], mask * column)
    tangent = tangent.at[-1].set(1.0)
    return tangent, column @ tangent


def _start_path(mesh, step):
    """The undeformed dome as the start of a path, with first travel step ``step`` (m);
    its tangent and stiffness zero, not worked out (see :func:`first_crossings`)."""
    zero = jnp.zeros(mesh.size)
    return Path(
        zero,
        jnp.zeros(()),
        zero,
        jnp.zeros(()),
        zero,
        jnp.asarray(step, float),
        jnp.asarray(0),
        jnp.asarray(False),
        jnp.asarray(False),
        jnp.asarray(0),
    )


def _path_guess(path, goal, thickness):
    """(guess state, its travel, Newton iterations allowed, jump) of the next step towards
    the travel ``goal``: the secant prediction at min(d + step, goal). The first step, from
    the undeformed dome with the plate pressed in (no secant yet), may take a full solve's
    iterations; a jump (see SNAP_STEP: only after failed steps, so a short step asked for
    at a light load is a plain step) starts from the last state."""
    y = path.y
    d = y[-1]
    jump = path.cut & (path.step < SNAP_STEP * thickness)
    d_new = jnp.minimum(d + jnp.where(jump, SNAP_STEP * thickness, path.step), goal)
    last = d - path.previous[-1]
    ratio = jnp.where((last > 0) & ~jump, (d_new - d) / jnp.where(last > 0, last, 1.0), 0.0)
    guess = (y + ratio * (y - path.previous)).at[-1].set(d_new)
    max_iter = jnp.where(jump, SNAP_MAX_ITER, jnp.where(d > 0, PATH_NEWTON_MAX_ITER, NEWTON_MAX_ITER))
    return guess, d_new, max_iter, jump


def _path_update(params, path, y_new, force_new, tangent_new, ok, iterations, jump, shift):
    """The path after Newton's answer to :func:`_path_guess`: a converged step is taken
    (the next step doubles if it was easy, halves if it was hard; after a jump the secant
    starts afresh); a failed one is refused and the step cut to a quarter.
    ``force_new``: the plate force (N) at ``y_new``; ``tangent_new``: (dy/dd, dF/dd) at
    ``y_new`` (:func:`_tangent`), or None, which keeps the path's tangent (a path whose
    tangents are not read); ``shift``: Newton's last Levenberg shift index, for the next."""
    factor = jnp.where(iterations <= PATH_EASY_ITER, 2.0, jnp.where(iterations >= PATH_HARD_ITER, 0.5, 1.0))
    step = jnp.where(ok, jnp.maximum(path.step, SNAP_STEP * params[1]) * factor, path.step / 4)
    tangent, stiffness = (
        (path.tangent, path.stiffness)
        if tangent_new is None
        else jax.tree.map(lambda new, old: jnp.where(ok, new, old), tangent_new, (path.tangent, path.stiffness))
    )
    return Path(
        y=jnp.where(ok, y_new, path.y),
        force=jnp.where(ok, force_new, path.force),
        tangent=tangent,
        stiffness=stiffness,
        previous=jnp.where(ok, jnp.where(jump, y_new, path.y), path.previous),
        step=step,
        count=path.count + 1,
        cut=~ok,
        failed=~ok & jump,
        shift=shift,
    )


def _hermite_guess(before: Path, after: Path, level):
    """A state under the plate force ``level`` (N) between two points of a path with
    before.force < level <= after.force: the cubic Hermite interpolants of the force and
    the state in the travel, from their values and tangents at both ends, the force's
    inverted by bisection (a path step spans up to half the wall, over which a straight
    line between the states is far from equilibrium and makes Newton damp its steps)."""
    h = after.y[-1] - before.y[-1]

    def at(s, v0, t0, v1, t1):
        return (
            (2 * s**3 - 3 * s**2 + 1) * v0
            + (s**3 - 2 * s**2 + s) * h * t0
            + (3 * s**2 - 2 * s**3) * v1
            + (s**3 - s**2) * h * t1
        )

    def halve(_, bracket):
        low, high = bracket
        middle = 0.5 * (low + high)
        below = at(middle, before.force, before.stiffness, after.force, after.stiffness) < level
        return jnp.where(below, middle, low), jnp.where(below, high, middle)

    low, high = lax.fori_loop(0, HERMITE_BISECTIONS, halve, (jnp.zeros(()), jnp.ones(())))
    return at(0.5 * (low + high), before.y, before.tangent, after.y, after.tangent)


def follow_travels(mesh, params, travels, step):
    """Converged states (n, size) at each of ``travels`` (n,) (m, increasing from > 0),
    following the path from the undeformed dome with first step ``step`` (m); whether
    each was reached, and whether the path failed (at a snap) before it. Each travel may
    take PATH_MAX_STEPS steps. Not differentiated (see :func:`implicit`)."""

    def advance(path, goal):
        guess, d_new, max_iter, jump = _path_guess(path, goal, params[1])
        mask, held, force = _control(mesh, False, d_new)
        y, ok, iterations, _, reaction, shift = newton(mesh, mask, held, force, params, guess, max_iter, path.shift)
        return _path_update(params, path, y, reaction, None, ok, iterations, jump, shift)

    def to(path, goal):
        path = eqx.tree_at(lambda p: p.count, path, jnp.asarray(0))
        path = lax.while_loop(lambda p: (p.y[-1] < goal) & p.can_go_on(jnp.inf), lambda p: advance(p, goal), path)
        return path, (path.y, path.y[-1] >= goal, path.failed)

    _, (states, reached, failed) = lax.scan(to, _start_path(mesh, step), travels)
    return states, reached, failed


class Crossings(eqx.Module):
    """The equilibria under force levels (k,) found on a followed path: ``states``
    (k, size), ``found`` (the path carried the level), ``converged`` (its force-held solve
    did), and the path's end: ``failed`` (a step did not converge), ``at_end`` (it reached
    the largest travel). A level the path never carried holds the path's last state and
    force (``forces``), itself an equilibrium under that force."""

    states: jax.Array
    forces: jax.Array
    found: jax.Array
    converged: jax.Array
    failed: jax.Array
    at_end: jax.Array


def first_crossings(mesh, params, levels, max_travel, step):
    """The equilibria at the first crossing of each of ``levels`` (k,) (N, > 0) on the path
    followed from the undeformed dome (first step ``step``, m) up to the travel
    ``max_travel`` (m). The first loop turn linearises the undeformed dome for its tangent
    (a Newton call with no step, not a step of the path); each later turn makes one Newton
    solve: a step of the path with the travel held, or, once a step has carried a level,
    that level's solve with the force held, from the cubic Hermite interpolant of the
    step's two ends (their states, forces and tangents along the path), the lower end
    moving up to each level solved below the next; so one compiled Newton serves all
    three. Not differentiated (see :func:`implicit`)."""
    k = levels.shape[0]
    blank = jnp.zeros((k, mesh.size))
    on_level = lambda mask, now, old: jnp.where(mask.reshape((k,) + (1,) * (now.ndim - 1)), now, old)  # noqa: E731

    def cond(carry):
        path, _, found, solved, _, _ = carry
        return jnp.any(found & ~solved) | (~jnp.all(found) & path.can_go_on(max_travel))

    def body(carry):
        # The path does not move while levels it crossed are pending: they all lie
        # between ``before`` and ``path``.
        path, before, found, solved, c, started = carry
        # The first turn works out the undeformed dome's tangent: its linearisation at
        # travel 0, no Newton step (so the compiled loop holds the one linearisation).
        starting = ~started
        pending = found & ~solved
        level = jnp.argmax(pending)
        solving = pending[level]
        guess, d_new, max_iter, jump = _path_guess(path, max_travel, params[1])
        guess = jnp.where(solving, _hermite_guess(before, path, levels[level]), guess)
        max_iter = jnp.where(solving, NEWTON_MAX_ITER, jnp.where(starting, 0, max_iter))
        d_new = jnp.where(starting, 0.0, d_new)
        mask, held, force = _control(mesh, solving, jnp.where(solving, levels[level], d_new))
        y, ok, iterations, H, reaction, shift = newton(mesh, mask, held, force, params, guess, max_iter, path.shift)
        just = jnp.arange(k) == level
        # A solved level's state, inside the step, is a closer lower end for the levels
        # still pending above it: their Hermite guesses span less of the step, and each
        # level needs fewer Newton iterations than from the step's start.
        still = pending & ~just
        above = jnp.all(jnp.where(still, levels >= levels[level], True))
        closer = solving & ok & jnp.any(still) & above & (y[-1] > before.y[-1]) & (y[-1] < path.y[-1])
        tangent = lax.cond(
            starting | (ok & (~solving | closer)), lambda: _tangent(mesh, H), lambda: (path.tangent, path.stiffness)
        )

        c = eqx.tree_at(
            lambda c: (c.states, c.converged),
            c,
            (
                on_level(just & solving, jnp.broadcast_to(y, blank.shape), c.states),
                jnp.where(just & solving, ok, c.converged),
            ),
        )
        new = _path_update(params, path, y, reaction, tangent, ok & ~solving, iterations, jump, shift)
        new = jax.tree.map(lambda a, b: jnp.where(solving, b, a), new, path)
        with_tangent = eqx.tree_at(lambda p: (p.tangent, p.stiffness), path, tangent)
        new = jax.tree.map(lambda a, b: jnp.where(starting, a, b), with_tangent, new)
        crossed = ~starting & ~solving & ok & ~found & (new.force >= levels)
        before = jax.tree.map(lambda a, b: jnp.where(jnp.any(crossed), a, b), path, before)
        solved_point = eqx.tree_at(lambda p: (p.y, p.force, p.tangent, p.stiffness), before, (y, reaction, *tangent))
        before = jax.tree.map(lambda a, b: jnp.where(closer, a, b), solved_point, before)
        return new, before, found | crossed, solved | (just & solving), c, jnp.asarray(True)

    none = jnp.zeros(k, bool)
    c = Crossings(blank, levels, none, none, jnp.asarray(False), jnp.asarray(False))
    start = _start_path(mesh, step)
    path, _, found, _, c, _ = lax.while_loop(cond, body, (start, start, none, none, c, jnp.asarray(False)))
    return Crossings(
        states=on_level(found, c.states, jnp.broadcast_to(path.y, blank.shape)),
        forces=jnp.where(found, levels, path.force),
        found=found,
        converged=jnp.where(found, c.converged, ~path.failed),
        failed=path.failed,
        at_end=path.y[-1] >= max_travel,
    )
