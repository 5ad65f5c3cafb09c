"""Pictures of design results: a solved design (each target, limit and objective output
along each variable, through the solution) and a sweep (the optimum over the swept keys)."""

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from magdesign._files import replaced
from magdesign._numerics import ROUNDING_SPREAD
from magdesign._progress import stage
from magdesign.scene import MECHANICS_CONVERGED
from magdesign.units import convert

SLICE_POINTS = 101


def _in_unit(values, unit):
    return convert(values, unit) if unit else values


def plot_design(problem, result, path):
    """Write a PNG grid: rows are the targets, limits and objective; columns the variables.

    Each panel slices one output along one variable over its bounds, the other variables
    held at the solution; dashed lines mark the target value or limit bound, the dotted
    line the solved value of the variable.
    """
    rows = [(t.output, "target", {"": t.value}) for t in problem.targets]
    rows += [(lim.output, "limit", {side: getattr(lim, side) for side in lim.sides}) for lim in problem.limits]
    if problem.objective is not None:
        rows.append((problem.objective.output, f"objective ({problem.objective.sense})", {}))
    solution = {name: jnp.asarray(value) for name, value in result.parameters.items()}
    figure = Figure(figsize=(4.2 * len(problem.variables), 2.8 * len(rows)))
    axes = figure.subplots(len(rows), len(problem.variables), squeeze=False)
    for column, variable in enumerate(problem.variables):
        stage(f"{path}: the model at {SLICE_POINTS} values of {variable.name} over its bounds")
        grid = jnp.linspace(variable.lower, variable.upper, SLICE_POINTS)
        sliced = jax.vmap(lambda x: problem.model({**solution, variable.name: x}))(grid)
        x_unit = result.units.get(variable.name)
        for row, (output, kind, levels) in enumerate(rows):
            y_unit = result.units.get(output)
            axis = axes[row, column]
            axis.plot(_in_unit(grid, x_unit), _in_unit(sliced[output], y_unit), color="C0")
            for side, level in levels.items():
                axis.axhline(_in_unit(float(level), y_unit), color="C3", linestyle="--", label=f"{kind} {side}".strip())
            axis.axvline(_in_unit(result.parameters[variable.name], x_unit), color="k", linestyle=":", label="design")
            axis.set_xlabel(f"{variable.name} ({x_unit or 'SI'})")
            axis.set_ylabel(f"{output} ({y_unit or 'SI'})")
            axis.set_title(kind, fontsize=9)
            axis.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8)
    figure.suptitle(f"magdesign solve: {result.status}")
    figure.tight_layout()
    with replaced(path) as temporary:
        figure.savefig(temporary, dpi=110)


def _label(name, unit):
    return f"{name} ({unit or 'SI'})"


def _span(values):
    """(low, high) for an axis of values that are one number up to rounding
    (ROUNDING_SPREAD), which would otherwise show their noise; else None."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return None
    middle, spread = float(np.median(finite)), float(np.ptp(finite))
    if spread > ROUNDING_SPREAD * abs(middle) or (middle == 0.0 and spread > 0.0):
        return None
    pad = 0.01 * abs(middle) or 1.0
    return middle - pad, middle + pad


def plot_sweep(result, path):
    """Write a PNG of a 1-D or 2-D :class:`~magdesign.design.DesignSweep`: one panel per
    variable (and per objective or limited output after them).

    1-D: the optimum's value against the swept key, with its implicit derivative drawn
    as a short tangent at each solved point. 2-D: a heat map with contours over the
    grid. Points that did not solve are left out of the curves and maps and marked with
    their status.
    """
    keys = list(result.over)
    if len(keys) not in (1, 2):
        raise ValueError(f"a sweep picture shows 1 or 2 swept keys, got {len(keys)}")
    units = result.units
    panels = list(result.parameters) + [
        name for name in result.outputs if name not in result.targets and name != MECHANICS_CONVERGED
    ]
    columns = min(3, len(panels))
    rows = -(-len(panels) // columns)
    figure = Figure(figsize=(4.4 * columns, 3.4 * rows))
    axes = figure.subplots(rows, columns, squeeze=False).ravel()
    solved = result.successful
    failed_statuses = sorted(set(result.status[~solved].ravel()))
    x = _in_unit(result.over[keys[0]], units.get(keys[0]))
    for axis, name in zip(axes, panels):
        values = result.parameters.get(name, result.outputs.get(name))
        shown = np.where(solved, _in_unit(values, units.get(name)), float("nan"))
        span = _span(shown)
        if len(keys) == 1:
            axis.plot(x[solved], shown[solved], "o-", color="C0", markersize=3, label="optimum")
            if name in result.parameters and keys[0] in result.derivatives:
                slope = (
                    result.derivatives[keys[0]][name]
                    * _in_unit(1.0, units.get(name))
                    / _in_unit(1.0, units.get(keys[0]))
                )
                half = 0.3 * (x.max() - x.min()) / max(len(x) - 1, 1)
                for xi, yi, si in zip(x[solved], shown[solved], slope[solved]):
                    axis.plot([xi - half, xi + half], [yi - si * half, yi + si * half], color="C1", linewidth=1.5)
                axis.plot([], [], color="C1", label="implicit derivative")
            y_failed = np.where(solved, float("nan"), _in_unit(values, units.get(name)))
            for k, status in enumerate(failed_statuses):
                where = result.status == status
                axis.plot(x[where], y_failed[where], "x", color=f"C{k + 3}", label=status)
            if span is not None:
                axis.set_ylim(*span)
            axis.set_xlabel(_label(keys[0], units.get(keys[0])))
            axis.set_ylabel(_label(name, units.get(name)))
            axis.legend(fontsize=7)
        else:
            y = _in_unit(result.over[keys[1]], units.get(keys[1]))
            limits = dict(zip(("vmin", "vmax"), span)) if span is not None else {}
            mesh = axis.pcolormesh(x, y, shown, shading="nearest", cmap="viridis", **limits)
            figure.colorbar(mesh, ax=axis, label=_label(name, units.get(name)))
            if np.isfinite(shown).sum() >= 4 and span is None:
                lines = axis.contour(x, y, shown, colors="white", linewidths=0.8)
                axis.clabel(lines, fontsize=7)
            for k, status in enumerate(failed_statuses):
                where = result.status == status
                axis.plot(x[where], y[where], "x", color=f"C{k + 3}", label=status)
            if failed_statuses:
                axis.legend(fontsize=7)
            if span is not None:
                axis.text(
                    0.5,
                    0.5,
                    f"{np.nanmedian(shown):.6g} {units.get(name) or ''} at every solved point",
                    transform=axis.transAxes,
                    ha="center",
                    fontsize=8,
                    color="white",
                )
            axis.set_xlabel(_label(keys[0], units.get(keys[0])))
            axis.set_ylabel(_label(keys[1], units.get(keys[1])))
            axis.set_title(name, fontsize=9)
        axis.grid(alpha=0.3)
    for axis in axes[len(panels) :]:
        axis.set_visible(False)
    figure.suptitle(f"magdesign sweep: {result.summary()}", fontsize=10)
    figure.tight_layout()
    with replaced(path) as temporary:
        figure.savefig(temporary, dpi=90)
