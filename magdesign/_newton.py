"""Newton's method with a backtracking line search, as one compiled ``lax.while_loop``: the
loop of the saturating soft body (:mod:`magdesign.fields.soft`) and of the dome's
equilibrium (:mod:`magdesign.mechanics._axisymmetric.equilibrium`).

The caller gives the method its parts: when to stop and what to carry (``linearise``), the
Newton direction and the line search's test (``direction``: its own linear solve, whether a
dense LU or a shifted block Cholesky) and the merit that the search measures (``measure``:
|residual|^2 or a potential). The loop owns the order of the work: each turn tests the
point it stands on, then, unless the solve ends there, finds the direction and halves the
step from 1 until the caller's test passes or the step is 2^-``halvings``, and takes that
step (a search that reaches the shortest step still takes it, and says so: ``gave_up``).
One evaluation of each part sits in the compiled loop, whatever the number of turns.

Derivatives of a solution are the caller's (implicit-function rules): the loop is not
differentiated.
"""

import jax
import jax.numpy as jnp
from jax import lax

# Halvings of a line search's step at most: its shortest step is 2^-HALVINGS of Newton's.
HALVINGS = 30


def backtrack(measure, too_long, x, direction, base, known=True, halvings=HALVINGS):
    """The line search along ``x + alpha direction``, alpha = 1, 1/2, 1/4, ...: (alpha, the
    merit at that point, the merit at x).

    Args:
        measure: x -> the merit there (a pytree: the value and what the caller keeps of it).
        too_long: (alpha, merit at the trial, merit at x) -> True while the step is to be
            halved again (the caller's sufficient-decrease test).
        x: the point (any shape), and ``direction`` the full step from it (same shape).
        base: the merit at x, or a placeholder of its structure where ``known`` is False:
            then the loop measures x itself first, so that the compiled loop still holds
            one evaluation of ``measure``.
        known: whether ``base`` holds the merit at x (a bool, may be traced).
        halvings: the search stops at alpha = 2^-halvings whatever ``too_long`` says.
    """

    def alpha_of(k):  # k = -1: x itself; 0, 1, 2, ...: alpha = 2^-k
        return jnp.where(k < 0, 0.0, jnp.ldexp(1.0, -jnp.maximum(k, 0)))

    def going(search):
        k, trial, base = search
        alpha = alpha_of(k)
        return (k < 0) | (too_long(alpha, trial, base) & (alpha > 2.0**-halvings))

    def shorter(search):
        k, trial, base = search
        k = k + 1
        value = measure(jnp.where(k < 0, x, x + alpha_of(k) * direction))
        keep = lambda old, new: jnp.where(k < 0, old, new)  # noqa: E731
        return k, jax.tree.map(keep, trial, value), jax.tree.map(keep, value, base)

    start = (jnp.where(known, -1, -2), base, base)
    k, trial, base = lax.while_loop(going, shorter, start)
    return alpha_of(k), trial, base


def newton(linearise, direction, measure, x, measured, state, known=True, halvings=HALVINGS):
    """Newton's method with a backtracking line search from ``x``: (the last point, the
    merit there, the caller's state, whether the last search reached its shortest step).

    Args:
        linearise: (x, merit at x, whether the last search reached its shortest step,
            state) -> (done, linearisation, state): evaluated at every point, the last
            included; ``done`` ends the solve at x (converged, or out of iterations).
        direction: (x, linearisation, state) -> (full step, ``too_long`` of
            :func:`backtrack` for it, state); evaluated only where the solve goes on.
        measure: x -> the merit at x, as in :func:`backtrack`.
        x: the start; ``measured`` the merit there (``known``: see :func:`backtrack`).
        state: what the caller carries from turn to turn (a pytree of arrays).
        halvings: as in :func:`backtrack`.
    """

    def turn(carry):
        x, measured, known, gave_up, state, _ = carry
        done, linear, state = linearise(x, measured, gave_up, state)

        def step():
            full, too_long, moved = direction(x, linear, state)
            alpha, trial, _ = backtrack(measure, too_long, x, full, measured, known, halvings)
            return x + alpha * full, trial, jnp.asarray(True), alpha <= 2.0**-halvings, moved

        x, measured, known, gave_up, state = lax.cond(
            done, lambda: (x, measured, jnp.asarray(known), gave_up, state), step
        )
        return x, measured, known, gave_up, state, done

    start = (x, measured, jnp.asarray(known), jnp.asarray(False), state, jnp.asarray(False))
    x, measured, _, gave_up, state, _ = lax.while_loop(lambda carry: ~carry[-1], turn, start)
    return x, measured, state, gave_up
