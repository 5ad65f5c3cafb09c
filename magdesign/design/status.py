"""The design solver's outcomes: :class:`DesignStatus` and its names by code."""

import equinox as eqx


class DesignStatus(eqx.Enumeration):
    """The design solver's outcomes. The solver gives the first that applies, in the order
    nonfinite, mechanics_not_converged, max_steps_reached (a search cut short), then
    infeasible_target, limit_violated, not_a_minimum, max_steps_reached (a search that
    stalled, or ended at a point not stationary to the tolerance: the polish's, or the
    search's own where the polish is not kept), successful."""

    successful = "every target met, every limit held, a local optimum to first and second order"
    nonfinite = "the model gave NaN or inf at the start or at the end"
    mechanics_not_converged = "a solver inside the model (e.g. the dome's) did not converge at the end"
    infeasible_target = "a target is not met: the search ended where the violation is least nearby (see violated)"
    limit_violated = "a limit is broken at the end (see violated)"
    not_a_minimum = "a stationary point that the objective can leave along a direction of negative curvature"
    max_steps_reached = "the search or its polish did not reach a stationary point in max_steps"


# The statuses' names by code (the order of DesignStatus's members), the one source of the
# names in JSON, tables and exit codes. equinox lists an enumeration's members only
# privately, so they are named here again; tests/design/test_problem_collection.py checks
# that the two agree.
STATUS_NAMES = (
    "successful",
    "nonfinite",
    "mechanics_not_converged",
    "infeasible_target",
    "limit_violated",
    "not_a_minimum",
    "max_steps_reached",
)


def status_code(name: str) -> int:
    """The code of the status ``name`` (a :class:`DesignStatus` member's name): its index in
    STATUS_NAMES, as the solver's core returns it."""
    return STATUS_NAMES.index(name)
