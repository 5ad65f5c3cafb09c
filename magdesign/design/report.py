"""Results of the design solver: a JSON-ready record and a readable table."""

import csv
from typing import NamedTuple

import equinox as eqx
import numpy as np

from magdesign._files import replaced
from magdesign.design.problem import per_problem, source_of
from magdesign.design.status import STATUS_NAMES as STATUS_NAMES
from magdesign.design.status import DesignStatus as DesignStatus
from magdesign.scene.core import CLIPS_ABOVE
from magdesign.units import convert


def _keys(problem):
    """Names of the theta entries: each target's output, "output.side" per limit row, then
    each fixed input's name."""
    return (
        [t.output for t in problem.targets]
        + [f"{problem.limits[i].output}.{side}" for i, side in problem.limit_rows]
        + list(problem.fixed_names)
    )


class _Layout(NamedTuple):
    """A problem's names as a result shows them: its variables, model outputs
    (``Problem.outputs``), number of targets, theta keys (:func:`_keys`: targets first,
    then limit rows), (output, side) of each limit row, and display units (shared by
    every result of the problem: copy before changing)."""

    names: tuple
    outputs: tuple
    n_targets: int
    keys: tuple
    limit_rows: tuple
    units: dict


@per_problem
def _layout(problem):
    units = {v.name: v.unit for v in problem.variables}
    units.update({t.output: t.unit for t in problem.targets})
    units.update({lim.output: lim.unit for lim in problem.limits})
    units.update(problem.report_units)
    limit_rows = tuple((problem.limits[i].output, side) for i, side in problem.limit_rows)
    names = tuple(v.name for v in problem.variables)
    return _Layout(names, problem.outputs, len(problem.targets), tuple(_keys(problem)), limit_rows, units)


def format_quantity(value: float, unit: str | None, digits: int = 6) -> str:
    """An SI value shown in ``unit`` ("5.8458 mm") to ``digits`` significant digits, or bare
    when ``unit`` is None."""
    return f"{convert(value, unit):.{digits}g} {unit}" if unit else f"{value:.{digits}g}"


def _missed(value: float, reference: float, unit: str | None) -> str:
    """``value`` shown with the fewest digits (6 to 15) that tell it from ``reference``: a
    row that misses its target or bound by less than 6 digits show is seen to miss it."""
    for digits in range(6, 16):
        if format_quantity(value, unit, digits) != format_quantity(reference, unit, digits):
            break
    return format_quantity(value, unit, digits)


class DesignResult(eqx.Module):
    """One solved design (SI values, Python floats).

    Attributes:
        status: the name of a :class:`DesignStatus`: "successful", or why not:
            "nonfinite", "mechanics_not_converged" (a solver inside the model, e.g. the
            dome's, did not converge at the end), "infeasible_target" (see ``violated``),
            "limit_violated", "not_a_minimum", "max_steps_reached".
        parameters: {variable: value}.
        targets: {output: {"target": value, "achieved": value}}.
        limits: {output: {"upper" and/or "lower": bound, "achieved": value, "active": bool}}.
        active_bounds: {variable: "lower" | "upper"} for variables held on a bound.
        derivatives: {key: {variable: d parameter / d key}}, key a target's output (d/d its
            value), "output.upper" / "output.lower" for an active limit's bound, or a
            fixed input's name (:class:`Problem` ``fixed``); NaN (null in JSON) where the
            derivative does not exist (every one, unless the status is "successful") or
            could not be computed.
        violated: names of the targets and limits not met.
        outputs: the model outputs named by the problem (targets, limits, objective, report).
        steps: solver steps, all phases; seconds: wall time of the solve.
        units: display units by name (None: SI).
        objective: (output, "max" | "min") of the problem's objective, or None.
        source: the spec the problem was built from
            (:func:`magdesign.spec.design.problem_from_spec`, at the levels it was solved
            at), or None: what :meth:`spec` writes the answer into.
    """

    status: str
    parameters: dict
    targets: dict
    limits: dict
    active_bounds: dict
    derivatives: dict
    violated: tuple
    outputs: dict
    steps: int
    seconds: float
    units: dict
    objective: tuple[str, str] | None = None
    source: dict | None = None

    @classmethod
    def from_core(cls, problem, solution, theta, seconds, rtol):
        # Python lists first: indexing numpy arrays element by element costs more than
        # the solve itself on small problems.
        theta, x, values, residuals, active_rows, at_lower, at_upper, derivatives = (
            np.asarray(a).tolist()
            for a in (
                theta,
                solution.x,
                solution.outputs,
                solution.residuals,
                solution.active_limits,
                solution.at_lower,
                solution.at_upper,
                solution.derivatives,
            )
        )
        names, output_names, n_targets, keys, limit_rows, units = _layout(problem)
        rows = n_targets + len(limit_rows)
        outputs = dict(zip(output_names, values))
        targets = {
            output: {"target": theta[k], "achieved": outputs[output]} for k, output in enumerate(keys[:n_targets])
        }
        limits = {}
        for k, (output, side) in enumerate(limit_rows):
            entry = limits.setdefault(output, {"achieved": outputs[output], "active": False})
            entry[side] = theta[n_targets + k]
            entry["active"] = entry["active"] or active_rows[k]
        derivatives = {
            key: {name: derivatives[j][column] for j, name in enumerate(names)}
            for column, key in enumerate(keys)
            if column < n_targets or column >= rows or active_rows[column - n_targets]
        }
        active_bounds = {
            name: ("lower" if at_lower[j] else "upper") for j, name in enumerate(names) if at_lower[j] or at_upper[j]
        }
        violated = tuple(
            key
            for k, key in enumerate(keys[:rows])
            if (abs(residuals[k]) if k < n_targets else residuals[k]) > float(rtol)
        )
        return cls(
            status=STATUS_NAMES[int(solution.status)],
            parameters=dict(zip(names, x)),
            targets=targets,
            limits=limits,
            active_bounds=active_bounds,
            derivatives=derivatives,
            violated=violated,
            outputs=outputs,
            steps=int(solution.steps),
            seconds=float(seconds),
            units=dict(units),
            objective=None if problem.objective is None else (problem.objective.output, problem.objective.sense),
            source=source_of(problem),
        )

    @property
    def successful(self) -> bool:
        return self.status == "successful"

    def to_json(self) -> dict:
        """The JSON object ``magdesign solve --json`` prints (status, parameters, targets, steps,
        seconds), plus limits, active bounds, derivatives,
        every output the problem names (SI) and the units the table shows them in."""
        return {
            "status": self.status,
            "parameters": dict(self.parameters),
            "targets": {k: dict(v) for k, v in self.targets.items()},
            "steps": self.steps,
            "seconds": self.seconds,
            "limits": {k: dict(v) for k, v in self.limits.items()},
            "active_bounds": dict(self.active_bounds),
            "violated": list(self.violated),
            "derivatives": {k: dict(v) for k, v in self.derivatives.items()},
            "outputs": dict(self.outputs),
            "units": {name: unit for name, unit in self.units.items() if unit is not None},
        }

    def table(self) -> str:
        """A readable report: parameters, targets, limits, other outputs, status and time."""
        unit = self.units.get
        shown = sorted(set(self.targets) | set(self.limits))
        objective = None if self.objective is None else self.objective[0]
        others = [name for name in self.outputs if name not in shown and name != objective]
        aim = (
            None
            if self.objective is None
            else f"{'maximize' if self.objective[1] == 'max' else 'minimize'} {objective}"
        )
        width = max(len(name) for name in [*self.parameters, *shown, *others, aim or "", "parameter"]) + 2
        row = lambda *cells: (
            "  " + "".join(f"{cell:<{width if i == 0 else 18}}" for i, cell in enumerate(cells)).rstrip()
        )  # noqa: E731
        lines = [row("parameter", "value")]
        for name, value in self.parameters.items():
            bound = f"(on {self.active_bounds[name]} bound)" if name in self.active_bounds else ""
            lines.append(row(name, format_quantity(value, unit(name)), bound))
        if self.targets:
            lines.append(row("target", "wanted", "achieved", "met"))
            for name, t in self.targets.items():
                missed = name in self.violated
                achieved = (
                    _missed(t["achieved"], t["target"], unit(name))
                    if missed
                    else format_quantity(t["achieved"], unit(name))
                )
                lines.append(row(name, format_quantity(t["target"], unit(name)), achieved, "no" if missed else "yes"))
        if self.limits:
            lines.append(row("limit", "bound", "achieved", "active"))  # a broken limit: VIOLATED
            for name, lim in self.limits.items():
                bounds = " ".join(
                    f"{'<=' if side == 'upper' else '>='} {format_quantity(lim[side], unit(name))}"
                    for side in ("upper", "lower")
                    if side in lim
                )
                broken = next((side for side in ("upper", "lower") if f"{name}.{side}" in self.violated), None)
                achieved = (
                    _missed(lim["achieved"], lim[broken], unit(name))
                    if broken
                    else format_quantity(lim["achieved"], unit(name))
                )
                lines.append(row(name, bounds, achieved, "VIOLATED" if broken else "yes" if lim["active"] else "no"))
        if objective is not None:
            lines.append(row("objective", "value"))
            lines.append(row(aim, format_quantity(self.outputs[objective], unit(objective))))
        if others:
            lines.append(row("output", "value"))
            lines.extend(row(name, format_quantity(self.outputs[name], unit(name))) for name in others)
        clipping = self.outputs.get("saturation_ratio")
        if clipping is not None and clipping > CLIPS_ABOVE:
            lines.append(
                f"the chip clips: its largest reading is {clipping:.3g} times its range (saturation_ratio); "
                "the real chip's readings stop at its range, and sensitivity and resolution are the unclipped signal's"
            )
        violated = f" (not met: {', '.join(self.violated)})" if self.violated else ""
        lines.append(f"status: {self.status}{violated}   steps: {self.steps}   time: {self.seconds * 1e3:.3g} ms")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.table()

    def spec(self) -> dict:
        """The spec this result was solved from with its answer in place (a parsed TOML
        dict): each variable's value written into the scene's own table in the unit the
        spec writes it (read back exactly, or one rounding off), no ``start`` left for it,
        at the levels the answer was solved at. ``magdesign simulate`` or ``show`` of it
        gives the design reported here.

        Raises:
            ValueError: the result's problem was not built from a spec, or a value is not finite.
        """
        # imported here: magdesign.spec.design imports magdesign.design, whose package imports this module
        from magdesign.spec.design import solved_spec

        if self.source is None:
            raise ValueError(
                "this result's problem was not built from a spec "
                "(magdesign.spec.design.problem_from_spec): there is no spec to write"
            )
        return solved_spec(self.source, self.parameters, self.units)

    def write_spec(self, path) -> None:
        """Write :meth:`spec` to the TOML file ``path`` under the header "# solved by magdesign
        <version> on <date>: status <status>"; the file is replaced whole or not at all."""
        from magdesign.spec.design import write_spec

        violated = f" (not met: {', '.join(self.violated)})" if self.violated else ""
        write_spec(path, self.spec(), status=f"{self.status}{violated}")


class DesignSweep(eqx.Module):
    """A grid or list of solved designs: numpy arrays of shape ``shape`` (a grid's axes in
    the order of ``over``, or (points,)), SI.

    Attributes:
        over: {key: (shape) values}: the swept inputs (a target's output, "output.upper" /
            "output.lower" of a limit, or a fixed scene parameter such as
            "mechanics.outer_radius"); empty for a batch of starts.
        status: (shape) status names, as in :class:`DesignResult`.
        parameters: {variable: (shape)}.
        targets: {output: {"target": (shape), "achieved": (shape)}}.
        limits: {output: {"achieved": (shape), "active": (shape) bool}}.
        outputs: {output: (shape)}: every output the problem names.
        derivatives: {key: {variable: (shape)}}: implicit derivatives of the optimum with
            respect to every target value, limit bound (0 where that limit is inactive) and
            fixed input.
        steps: (shape); seconds: wall time of the whole batch.
        units: display units by name (None: SI), as in :class:`DesignResult`.
    """

    over: dict
    status: np.ndarray
    parameters: dict
    targets: dict
    limits: dict
    outputs: dict
    derivatives: dict
    steps: np.ndarray
    seconds: float
    units: dict

    @classmethod
    def from_core(cls, problem, solution, thetas, seconds, over=None, shape=None, over_units=None):
        """From the core's flat (points,) solution; ``shape`` (default (points,)) reshapes it;
        ``over_units`` gives the swept keys' display units."""
        thetas = np.asarray(thetas)
        shape = tuple(shape) if shape is not None else (thetas.shape[0],)
        grid = lambda values: np.asarray(values).reshape(shape)  # noqa: E731
        names = [v.name for v in problem.variables]
        outputs = {name: grid(solution.outputs[:, k]) for k, name in enumerate(problem.outputs)}
        limits = {}
        for k, (i, _) in enumerate(problem.limit_rows):
            output = problem.limits[i].output
            entry = limits.setdefault(output, {"achieved": outputs[output], "active": np.zeros(shape, bool)})
            entry["active"] = entry["active"] | grid(solution.active_limits[:, k])
        units = dict(_layout(problem).units)
        units.update(over_units or {})
        units.update({f"{key}.achieved": units.get(key) for key in over or {} if key in outputs})
        return cls(
            over={key: grid(values) for key, values in (over or {}).items()},
            status=grid(np.asarray(STATUS_NAMES)[np.asarray(solution.status)]),
            parameters={name: grid(solution.x[:, j]) for j, name in enumerate(names)},
            targets={
                t.output: {"target": grid(thetas[:, k]), "achieved": outputs[t.output]}
                for k, t in enumerate(problem.targets)
            },
            limits=limits,
            outputs=outputs,
            derivatives={
                key: {name: grid(solution.derivatives[:, j, column]) for j, name in enumerate(names)}
                for column, key in enumerate(_keys(problem))
            },
            steps=grid(solution.steps),
            seconds=float(seconds),
            units=units,
        )

    @property
    def shape(self) -> tuple[int, ...]:
        return self.status.shape

    @property
    def successful(self) -> np.ndarray:
        """(shape) bool: which designs solved."""
        return self.status == "successful"

    def status_counts(self) -> dict:
        """{status name: number of points}, most frequent first."""
        names, counts = np.unique(self.status, return_counts=True)
        return {str(name): int(count) for count, name in sorted(zip(counts, names), reverse=True)}

    def _achieved(self) -> dict:
        """The outputs, one whose name is also a swept key (a target's output, or a fixed
        input that the model also reports) named "<output>.achieved", so that it does not
        hide the swept value."""
        return {(f"{name}.achieved" if name in self.over else name): values for name, values in self.outputs.items()}

    def columns(self) -> dict[str, np.ndarray]:
        """{column: (points,) values (SI)}, flattened in the grid's (C) order: the swept
        inputs, status, parameters, outputs (one named like a swept key as "<output>.achieved"),
        steps, and each derivative as "d(variable)/d(key)"."""
        columns = {**self.over, "status": self.status, **self.parameters, **self._achieved(), "steps": self.steps}
        for key, entry in self.derivatives.items():
            columns.update({f"d({name})/d({key})": values for name, values in entry.items()})
        return {name: np.ravel(values) for name, values in columns.items()}

    def records(self) -> list[dict]:
        """One flat dict per point (SI), with the keys of :meth:`columns`."""
        flat = {name: values.tolist() for name, values in self.columns().items()}
        return [dict(zip(flat, row)) for row in zip(*flat.values())]

    def write_csv(self, path, block: int = 10_000) -> None:
        """Write :meth:`columns` to a CSV file (a header row, then one row per point, SI),
        ``block`` rows at a time so that a sweep of millions of points needs little memory."""
        columns = self.columns()
        with replaced(path) as temporary, open(temporary, "w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow(columns)
            for start in range(0, self.status.size, block):
                writer.writerows(zip(*(values[start : start + block].tolist() for values in columns.values())))

    def summary(self) -> str:
        """One line: how many points, how many solved, and the others by status."""
        total = self.status.size
        failed = {name: count for name, count in self.status_counts().items() if name != "successful"}
        line = f"{total} points, {total - sum(failed.values())} successful"
        if failed:
            line += f", {sum(failed.values())} not: " + ", ".join(f"{count} {name}" for name, count in failed.items())
        return line + f" ({self.seconds:.3g} s)"

    def table(self) -> str:
        """A readable table: one row per point with the swept inputs, the status, the
        parameters and the problem's outputs in their display units."""
        columns = {**self.over, **self.parameters, **self._achieved()}
        names = list(columns)
        header = names[: len(self.over)] + ["status"] + names[len(self.over) :]
        cells = [[f"{name} ({self.units.get(name)})" if self.units.get(name) else name for name in header]]
        flat = {name: np.ravel(values) for name, values in columns.items()}
        for index, status in enumerate(np.ravel(self.status)):
            row = [
                f"{convert(flat[name][index], self.units.get(name)):.6g}"
                if self.units.get(name)
                else f"{flat[name][index]:.6g}"
                for name in names
            ]
            cells.append(row[: len(self.over)] + [str(status)] + row[len(self.over) :])
        widths = [max(len(row[i]) for row in cells) + 2 for i in range(len(header))]
        return "\n".join(
            "  " + "".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip() for row in cells
        )
