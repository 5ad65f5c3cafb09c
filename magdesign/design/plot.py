"""A picture of a solved design: each target, limit and objective output along each
variable, through the solution, with the wanted values and the chosen design marked."""

import jax
import jax.numpy as jnp

from matplotlib.figure import Figure

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
    figure.savefig(path, dpi=110)
