"""The design solver's entry points: :func:`solve` one design, :func:`multistart` one
from many starts at once, and :func:`solve_batch` (what :func:`~magdesign.design.sweep`

runs) for many points of a problem.

The solver itself, sequential quadratic programming with a Newton polish and implicit
derivatives, lives in :mod:`magdesign.design._sqp` (its docstring says what it does, its
README how the pieces fit). This module also re-exports what the sweep and the CLI take
from the package: :func:`solve_batch`, :func:`batch_inputs`, :func:`settings_of`,
:func:`usable_cores` and :class:`SQP`.
"""

import time

import numpy as np

from magdesign.design._sqp.batch import solve_batch as solve_batch
from magdesign.design._sqp.batch import usable_cores as usable_cores
from magdesign.design._sqp.program import _host, _run, _start, _unpack
from magdesign.design._sqp.program import batch_inputs as batch_inputs
from magdesign.design._sqp.program import settings_of as settings_of
from magdesign.design._sqp.sqp import SQP as SQP
from magdesign.design.problem import Problem
from magdesign.design.report import DesignResult, DesignSweep

# Default tolerances of the design solver (solve's rtol and atol; its other
# thresholds are the fields of magdesign.design._sqp.sqp.SQP). Both act on dimensionless
# quantities: variables scaled to their bound width, residuals scaled by their target.
# Default tolerance on scaled target and limit residuals: 1e-10 leaves a margin of 10 below
# the 1e-9 relative accuracy the designs are checked to; the final Newton polish stops
# at a tenth of it (its quadratic convergence usually takes it to rounding).
DESIGN_RTOL = 1e-10
# Default step tolerance in scaled variables: a converged step in a [0, 1] box.
DESIGN_ATOL = 1e-13


def solve(
    problem: Problem,
    *,
    start: dict | None = None,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
    solver: SQP | None = None,
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
        solver: the solver's thresholds (:class:`SQP`); None: its defaults.

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
    settings, host = settings_of(rtol, atol, max_steps, solver), _host(problem)
    y0, theta = (host.y0 if not start else _start(problem, start, host.arrays)), host.theta
    began = time.perf_counter()
    packed = _run(problem, y0, theta, settings)
    seconds = time.perf_counter() - began
    return DesignResult.from_core(problem, _unpack(problem, packed), host.arrays[4], seconds, settings.rtol)


def multistart(
    problem: Problem,
    starts: dict,
    *,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
    solver: SQP | None = None,
) -> DesignSweep:
    """Solve ``problem`` from a batch of starts {variable: (batch,) values (SI)} at once.

    Variables missing from ``starts`` start at their own start; rtol, atol, max_steps and
    ``solver`` as in :func:`solve`. Returns a
    :class:`DesignSweep` with one solution per start.
    """
    batch = {np.shape(value) for value in starts.values()}
    if len(batch) != 1 or len(next(iter(batch))) != 1:
        raise ValueError(f"starts: give one (batch,) array per variable, got shapes {sorted(batch)}")
    y0, thetas = batch_inputs(problem, starts, next(iter(batch))[0])
    solution, seconds = solve_batch(problem, y0, thetas, settings_of(rtol, atol, max_steps, solver))
    return DesignSweep.from_core(problem, solution, thetas, seconds)
