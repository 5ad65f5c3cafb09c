"""Sweeps: a design solved at every point of a grid or list of inputs, in compiled batches.

A swept key is anything a design's optimum depends on: a target's value (its output's
name, "compliance"), a limit's bound ("field_max.upper"), or a scene parameter that the
problem holds fixed ("mechanics.outer_radius", for a problem whose model is a
:class:`~magdesign.spec.design.SceneModel`, or one of the problem's own ``fixed``
inputs). Every point is a full solve with its status, parameters, outputs and the
implicit derivatives of its optimum with respect to each of those inputs.
"""

import itertools
import math
from collections.abc import Mapping

import numpy as np
from jaxtyping import ArrayLike

from magdesign.design.problem import Problem, source_of
from magdesign.design.report import DesignSweep
from magdesign.design.solve import DESIGN_ATOL, DESIGN_RTOL, SQP, batch_inputs, settings_of, solve_batch
from magdesign.scene import parameters
from magdesign.spec.sizes import check_fits

# Copies of a sweep's records (inputs, outputs, parameters and their derivatives per point)
# held at once: the batches' results, their joined arrays and the DesignSweep's own.
SWEEP_COPIES = 4
# Above this many points a sweep warns that it is long (every point is a solve).
SLOW_SWEEP = 100_000


def sweepable(problem: Problem) -> dict[str, float]:
    """{key: value now (SI)} of every input a sweep of ``problem`` can vary: its target
    values, limit bounds, fixed inputs and (for a scene model) the scene parameters that
    are not variables."""
    keys = {t.output: float(t.value) for t in problem.targets}
    keys.update(
        {
            f"{problem.limits[i].output}.{side}": float(getattr(problem.limits[i], side))
            for i, side in problem.limit_rows
        }
    )
    scene = getattr(problem.model, "scene", None)
    if scene is not None:
        variables = {v.name for v in problem.variables}
        keys.update({name: float(value) for name, value in parameters(scene).items() if name not in variables})
    keys.update({name: float(value) for name, value in zip(problem.fixed_names, problem.fixed_values)})
    return keys


def with_fixed(problem: Problem, names) -> Problem:
    """``problem`` with the model inputs ``names`` (scene parameters) held as fixed inputs
    at their present values, so that a batch can vary them."""
    now = sweepable(problem)
    fixed = dict(zip(problem.fixed_names, problem.fixed_values))
    fixed.update({name: now[name] for name in names if name not in fixed})
    return Problem(
        problem.model,
        problem.variables,
        problem.targets,
        problem.limits,
        problem.objective,
        report=dict(problem.report_units),
        converged=problem.converged,
        fixed=fixed,
    )


def points_of(over: Mapping[str, ArrayLike], grid: bool) -> tuple[dict[str, np.ndarray], tuple[int, ...]]:
    """({key: (points,) values}, shape): the grid of ``over``'s values (its axes in the
    order of ``over``) or, with ``grid=False``, its values taken together point by point."""
    values = {key: np.atleast_1d(np.asarray(v, np.float64)) for key, v in over.items()}
    for key, v in values.items():
        if v.ndim != 1 or v.size < 1:
            raise ValueError(f"{key}: expected a non-empty list of values, got shape {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{key}: values must be finite")
    if grid:
        shape = tuple(v.size for v in values.values())
        columns = zip(*itertools.product(*values.values())) if values else []
        return {key: np.fromiter(column, np.float64) for key, column in zip(values, columns)}, shape
    sizes = {v.size for v in values.values()}
    if len(sizes) > 1:
        raise ValueError(f"grid=False takes lists of one length, got lengths {sorted(sizes)}")
    return values, (sizes.pop(),)


def sweep(
    problem: Problem,
    over: Mapping[str, ArrayLike] | str,
    values: ArrayLike | None = None,
    *,
    grid: bool = True,
    start: dict | None = None,
    rtol: float = DESIGN_RTOL,
    atol: float = DESIGN_ATOL,
    max_steps: int = 100,
    chunk: int | None = None,
    progress: bool | None = None,
    over_units: dict | None = None,
    continuation: bool = True,
    solver: SQP | None = None,
) -> DesignSweep:
    """Solve ``problem`` at every point of a grid (or list) of its inputs, in compiled,
    chunked batches split over the local devices, or, for a model with slow loops of its own
    on a CPU, a point per call on a thread per core, as a continuation (see ``continuation``
    and :func:`~magdesign.design.solve.solve_batch`).

    Args:
        problem: the design problem.
        over: {key: (k,) values (SI)}, each key one of :func:`sweepable`'s; or one key,
            with ``values`` (the older ``sweep(problem, "compliance", values)``).
        grid: True: every combination, shape (k1, k2, ...); False: the lists (all of one
            length) taken together, point by point, shape (k,).
        start, rtol, atol, max_steps, solver: as in :func:`~magdesign.design.solve`; one
            start for every point.
        chunk: the most points per compiled batch (memory); default ``SQP.chunk``. Not
            used where the points go one at a time.
        progress: a progress bar: True, False, or None (when stderr is a terminal and the
            sweep takes more than a second).
        over_units: display units of the swept keys, for tables.
        continuation: where the points go one at a time, start each (but the first of
            every ``SQP.chain``) from the optimum that the point before predicts with its
            implicit derivatives, and solve it again from ``start`` where that fails
            (fewer steps a point; a problem with several optima may then find another);
            False: every point from ``start``. Not used in batches.

    Returns:
        A :class:`DesignSweep` with arrays of the grid's shape; a point that fails has its
        status, never an exception.

    Raises:
        ValueError: a key that cannot be swept, values that are not finite; a
            :class:`~magdesign.units.SpecError` for a problem built from a spec where a
            swept scene parameter fails a check its spec value would fail
            (:func:`magdesign.spec.sweep.check_swept`).
    """
    if isinstance(over, str):
        over = {over: values}
    known = sweepable(problem)
    variables = {v.name for v in problem.variables}
    for key in over:
        if key in variables:
            raise ValueError(f"{key}: a variable of the problem (free); sweep a target, a limit bound or a fixed input")
        if key not in known:
            raise ValueError(f"{key}: not a sweepable input of the problem; expected one of {', '.join(known)}")
    count = math.prod(np.size(v) for v in over.values()) if grid else max(map(np.size, over.values()), default=0)
    record = len(sweepable(problem)) + len(problem.outputs) + len(problem.variables) * (len(sweepable(problem)) + 3)
    check_fits(
        f"{count} sweep points",
        count * record,
        factor=SWEEP_COPIES,
        what="the points' records",
        slow=(SLOW_SWEEP * record, f"each of the {count} points is a full solve"),
    )
    points, shape = points_of(over, grid)
    source = source_of(problem)
    if source is not None:  # every swept scene parameter passes the checks of a spec value
        from magdesign.spec.sweep import check_swept  # the sweep grammar imports this module

        check_swept(source, over, grid)
    rows = [t.output for t in problem.targets] + [
        f"{problem.limits[i].output}.{side}" for i, side in problem.limit_rows
    ]
    problem = with_fixed(problem, [key for key in points if key not in rows])
    columns = rows + list(problem.fixed_names)
    y0, thetas = batch_inputs(problem, start, int(np.prod(shape)))
    for key, column in points.items():
        thetas[:, columns.index(key)] = column
    units = {t.output: t.unit for t in problem.targets}
    units.update({f"{lim.output}.{side}": lim.unit for lim in problem.limits for side in lim.sides})
    units.update(over_units or {})
    solution, seconds = solve_batch(
        problem,
        y0,
        thetas,
        settings_of(rtol, atol, max_steps, solver),
        chunk=chunk,
        progress=progress,
        continuation=continuation,
    )
    return DesignSweep.from_core(
        problem, solution, thetas, seconds, over=points, shape=shape, over_units={key: units.get(key) for key in points}
    )
