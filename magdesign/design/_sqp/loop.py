"""The solver's loop in the manner of optimistix's solvers: :func:`init` gives the
:class:`SQPState` at the start, :func:`step` takes one trip, :func:`terminate` says
whether the loop is done (:func:`run` steps from :func:`init` until then), and
:func:`~magdesign.design._sqp.core.postprocess` reads the solution off the last state.
Each trip evaluates the model's jet once: at the point the search tries
(:mod:`magdesign.design._sqp.search`), then, once the search has ended, at Newton's
iterate of the polish (:mod:`magdesign.design._sqp.polish`). One place in the program
evaluates the model, so XLA compiles it once."""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Int

from magdesign.design._qp import where_needed
from magdesign.design._sqp.jet import Settings, _jet, _pick
from magdesign.design._sqp.polish import PolishState, _equations, _newton, _newton_step, _polish_start
from magdesign.design._sqp.search import (
    CONVERGED,
    NONFINITE_START,
    NOT_MINIMUM,
    START,
    SearchState,
    prepare,
    search_start,
    update,
)
from magdesign.design.problem import Problem
from magdesign.design.status import status_code


class SQPState(eqx.Module):
    """The solver's state between trips of its loop (scaled variables; a leading batch
    axis under vmap).

    Attributes:
        search: the search's state; its ``phase`` is where the search is (START, SEARCH,
            ESCAPE, PROBE) or how it ended (CONVERGED, STALLED, NOT_MINIMUM,
            NONFINITE_START; see :mod:`magdesign.design._sqp.search`).
        polish: the polish's state (Newton's, on the equations of the search's last
            active set); its ``done`` ends the loop.
        polishing: the phase after the search: True once the search has ended and the
            polish steps.
    """

    search: SearchState
    polish: PolishState
    polishing: Bool[Array, ""]


def init(problem: Problem, y0, settings: Settings, y_max) -> SQPState:
    """The state before the first trip, from y0 (n,) (scaled to the box [0, y_max] (n,)):
    the search at START, the polish not started."""
    search = search_start(problem, y0, settings)
    polish = _polish_start(_equations(problem, search, y_max), search, _newton(settings))
    return SQPState(search, polish, jnp.asarray(False))


def step(problem: Problem, theta, settings: Settings, y_max, state: SQPState) -> SQPState:
    """One trip of the loop, with ``theta`` (p,) the target values, limit bounds and fixed
    inputs (SI): the search's trial point, or the polish's Newton iterate,
    where the model's jet is evaluated once; the search's next state (while it runs), the
    polish started where the search ends, and Newton's step (while the polish runs, and on
    the trip the search ends at an accepted point, from the search's own jet)."""
    n, newton = y_max.shape[0], _newton(settings)
    polishing, stepping = state.polishing, state.polishing & ~state.polish.done
    prepared, trial = prepare(problem, settings, y_max, state.search, polishing)
    # Under vmap every lane runs each trip (a finished lane's state is kept), and a
    # lane's model error (as NaN) reaches the whole batch: a finished lane evaluates
    # the model where its search stopped, not at Newton's untried point, and the search's
    # update, which runs if any lane searches, gets a polishing lane's own finite jet.
    jet = _jet(problem, jnp.where(stepping, state.polish.z[:n], trial), theta)
    searched = where_needed(
        ~polishing,
        lambda operands: update(problem, settings, y_max, *operands),
        (prepared, trial, _pick(polishing, state.search.jet, jet)),
        state.search,
    )
    ended = ~polishing & ((searched.phase >= CONVERGED) | (searched.steps >= settings.max_steps))
    equations = _equations(problem, searched, y_max)
    polish = _pick(ended, _polish_start(equations, searched, newton), state.polish)
    # Newton's first step is from the search's last point, whose jet the search has
    # (where it accepted a point; else the next trip evaluates the model there first).
    accepted = (searched.phase != START) & (searched.phase != NONFINITE_START)
    polish = where_needed(
        stepping | (ended & accepted),
        lambda operands: _newton_step(equations, newton, *operands, settings.max_steps),
        (polish, _pick(polishing, jet, searched.jet)),
        polish,
    )
    return SQPState(searched, polish, polishing | ended)


def terminate(state: SQPState) -> tuple[Bool[Array, ""], Int[Array, ""]]:
    """(done, status code): whether the loop is done (the polish has stopped), and the
    status that the search's end gives ("nonfinite" where no start was finite,
    "not_a_minimum", "max_steps_reached" where the search was cut short, else
    "successful"); :func:`~magdesign.design._sqp.core.postprocess` gives the final one,
    from the polished point."""
    phase = state.search.phase
    status = jnp.select(
        [phase == NONFINITE_START, phase == NOT_MINIMUM, phase < CONVERGED],
        [status_code("nonfinite"), status_code("not_a_minimum"), status_code("max_steps_reached")],
        status_code("successful"),
    )
    return state.polish.done, status


def run(problem: Problem, y0, theta, settings: Settings, y_max) -> SQPState:
    """The loop's last state: :func:`init` at y0 (n,), then :func:`step` until
    :func:`terminate` says done."""
    return jax.lax.while_loop(
        lambda state: ~terminate(state)[0],
        lambda state: step(problem, theta, settings, y_max, state),
        init(problem, y0, settings, y_max),
    )
