"""Design specs: a scene spec plus a [design] table, read into a :class:`Problem`.

    [design]
    name = "dome_hall"                       # optional: the design's name in reports (else the file's)
    [design.variables]                       # scene parameters set free, by dotted spec key
    "geometry.gap" = { lower = "3 mm", upper = "15 mm" }
    [design.targets]                         # equalities on scene outputs
    compliance = "0.32 mm/N"
    [design.limits]                          # inequalities on scene outputs
    field_closest = { upper = "4.8 mT" }
    [design.objective]                       # optional: maximize or minimize one output
    maximize = "sensitivity"
    [design.report]                          # optional: more outputs to show, with display units
    closest_gap = "mm"

A variable starts at the value the scene states for it ([geometry] gap = "7.4 mm"): one
number in one place. A ``start`` is for a parameter the scene does not state (it takes its
default there); one that differs from the scene's value is refused. A variable's bounds
take the unit the scene spec gives that parameter; a target's or limit's value takes the
unit of its output (the scene's ``output_units``). Every error is a one-line
:class:`~magdesign.units.SpecError` naming the key.

A solved design is written back as a spec with its answer in the scene's tables
(:func:`solved_spec`, :func:`write_spec`, :meth:`DesignResult.spec`).
"""

import contextlib
import copy
import datetime
import importlib.metadata
import importlib.resources
import math
import os
import re
import tomllib
from collections.abc import Mapping
from pathlib import Path

import equinox as eqx
import numpy as np
from jaxtyping import Array

from magdesign._files import replaced
from magdesign.design.problem import Limit, Objective, Problem, Target, Variable, remember_source
from magdesign.scene import (
    MECHANICS_CONVERGED,
    AbstractScene,
    Loads,
    MagnetScene,
    loads_from_spec,
    outputs,
    parameters,
    with_parameters,
)
from magdesign.scene.mechanics import Dome
from magdesign.spec.checks import check_domain, check_output_number, fields
from magdesign.spec.scene import check_magnet_fits, check_wall, scene_from_spec
from magdesign.spec.table import check_keys, parameter_unit, sub_table
from magdesign.units import SpecError, echo, parse, unit_factor, written_unit

# The keys of an entry of each design table, from the key table (a target's tolerance is read
# by magdesign.spec.tolerance).
_VARIABLE_KEYS = fields("design.variables.*")
_LIMIT_KEYS = fields("design.limits.*")
_TARGET_KEYS = fields("design.targets.*")
_SENSES = {"maximize": "max", "minimize": "min"}


class SceneModel(eqx.Module):
    """A scene's outputs as a function of some of its parameters: the model of a design.

    A module rather than a closure: two problems built from the same spec compare equal
    in structure, so a jitted solve compiled for one is reused for the other.
    """

    scene: AbstractScene
    loads: Loads

    def __call__(self, values: Mapping[str, Array]) -> dict[str, Array]:
        """{parameter: value (SI)} -> {output: scalar (SI)}: the outputs of the scene's
        simulation over the spec's load sweep (:func:`magdesign.scene.outputs`)."""
        return outputs(with_parameters(self.scene, values), self.loads)


def default_spec() -> dict:
    """The built-in default design: the soft dome with a Hall sensor (the dome-Hall sensor of
    "Design and Fabrication of a Soft Magnetic Tactile Sensor")."""
    text = importlib.resources.files("magdesign.design").joinpath("default.toml").read_text()
    return tomllib.loads(text)


def load_spec(path) -> dict:
    """Read a TOML spec file; SpecError (naming the file) if it is missing or not TOML."""
    try:
        with open(path, "rb") as file:
            return tomllib.load(file)
    except OSError as error:
        raise SpecError(f"{path}: cannot read the spec ({error.strerror})") from None
    except tomllib.TOMLDecodeError as error:
        raise SpecError(f"{path}: not valid TOML ({error})") from None
    except UnicodeDecodeError:
        raise SpecError(f"{path}: not a text file (TOML is UTF-8)") from None
    except RecursionError:
        raise SpecError(f"{path}: arrays or tables nested too deep to read") from None


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def _toml_string(text):
    escaped = "".join(
        "\\" + c if c in '"\\' else f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F else c for c in text
    )
    return f'"{escaped}"'


def _toml_key(key):
    return key if _BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value):
    """One TOML value, on one line (a table inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)  # a float's repr reads back bit for bit; inf and nan are TOML's own
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (datetime.date, datetime.time)):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml_value, value)) + "]"
    if isinstance(value, dict):
        return (
            "{ " + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) + " }" if value else "{}"
        )
    raise TypeError(f"cannot write a {type(value).__name__} to TOML: {echo(value)}")


def spec_text(spec: dict) -> str:
    """A parsed spec as TOML text that :func:`tomllib.loads` reads back equal: each table
    and each table in one a [section] ("[design.variables]"), an array of tables in them
    [[sections]], tables deeper down inline ({ lower = "4 mm", upper = "20 mm" })."""
    lines = []

    def sectioned(value, depth):
        tables = isinstance(value, list) and value and all(isinstance(item, dict) for item in value)
        return depth < 2 and (isinstance(value, dict) or tables)

    def section(table, path):
        lines.extend(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in table.items() if not sectioned(v, len(path)))
        for key, value in table.items():
            if not sectioned(value, len(path)):
                continue
            name = ".".join(_toml_key(step) for step in [*path, key])
            for item in [value] if isinstance(value, dict) else value:
                # a table holding only tables needs no header of its own
                if isinstance(value, list) or not item or not all(sectioned(v, len(path) + 1) for v in item.values()):
                    lines.extend(["", f"[[{name}]]" if isinstance(value, list) else f"[{name}]"])
                section(item, [*path, key])

    section(spec, [])
    return "\n".join(lines).lstrip("\n") + "\n"


def write_spec(path, spec: dict, *, status: str) -> None:
    """Write a solved ``spec`` as TOML to ``path`` under the header "# solved by magdesign
    <version> on <date>: status <status>": into a new file beside it, then renamed over it,
    so that a failure or an interrupt leaves the old file or none, never half a file."""
    path = Path(path)
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    levels = fidelity_levels(spec)
    text = (
        f"# solved by magdesign {importlib.metadata.version('magdesign')} on {date}: status {status}\n"
        f"# the answer stands in the scene's tables{f' ({levels})' if levels else ''}: simulate or show this file\n\n"
        + spec_text(spec)
    )
    with replaced(path) as temporary, open(temporary, "w", encoding="utf-8") as file:
        file.write(text)
        file.flush()
        os.fsync(file.fileno())


_STEP = re.compile(r"(\w+)((?:\[\d+\])*)")


def _place(spec, name, create=False):
    """(table or list, key or index) holding scene parameter ``name`` in ``spec``
    ("soft[0].position[2]": spec["soft"][0]["position"], 2); the one entry of a one-entry
    list (a ball's ``size``) may be written bare. ``create``: make missing tables. KeyError,
    IndexError or TypeError where the spec has no place for it."""
    steps = []
    for part in name.split("."):
        key, indices = _STEP.fullmatch(part).groups()
        steps += [key, *map(int, re.findall(r"\d+", indices))]
    holder = spec
    for index, step in enumerate(steps[:-1]):
        if create and isinstance(step, str) and step not in holder:
            holder[step] = {}
        if index == len(steps) - 2 and steps[-1] == 0 and not isinstance(holder[step], list):
            return holder, step
        holder = holder[step]
    if not create:
        holder[steps[-1]]  # noqa: B018 (raises where the spec does not state it)
    return holder, steps[-1]


def stated_value(spec: dict, name: str):
    """The value ``spec`` writes for scene parameter ``name``, as written ("7.4 mm", 0.49),
    or None where it does not state it (the scene takes its default)."""
    try:
        holder, key = _place(spec, name)
    except (KeyError, IndexError, TypeError):
        return None
    return holder[key]


def _quantity_text(value, unit):
    """``value`` (SI) as a spec writes it in ``unit`` ("7.4458 mm"), the number chosen so
    that :func:`magdesign.units.parse` reads back ``value`` exactly (or one rounding off,
    where no number times the unit's factor rounds to it); a plain (SI) number where
    ``unit`` is None."""
    if unit is None or unit == "1":
        return value
    factor = unit_factor(unit)
    number = value / factor
    # the shortest decimal that reads back exactly, else a neighbour of the quotient that does
    candidates = [float(f"{number:.{digits}g}") for digits in range(1, 18)]
    candidates += [math.nextafter(number, math.inf), math.nextafter(number, -math.inf)]
    return f"{next((c for c in candidates if c * factor == value), number)!r} {unit}"


def solved_spec(spec: dict, values: Mapping[str, float], units: Mapping[str, str | None] | None = None) -> dict:
    """A copy of ``spec`` with each scene parameter of ``values`` ({name: SI value}) written
    in place: in the unit the spec writes it (a plain SI number where it writes one), where
    the spec does not state it in ``units[name]`` (else SI); its variable's ``start`` is
    dropped (the scene's value is the start). ValueError for a value that is not finite."""
    solved = copy.deepcopy(spec)
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"{name}: the answer {value!r} is not a finite value to write")
        stated = stated_value(solved, name)
        unit = written_unit(stated) if stated is not None else (units or {}).get(name)
        holder, key = _place(solved, name, create=True)
        holder[key] = _quantity_text(float(value), unit)
        variable = solved.get("design", {}).get("variables", {}).get(name)
        if isinstance(variable, dict):
            variable.pop("start", None)
    return solved


def target_tolerance(value, target: float, unit: str, where: str) -> float:
    """The allowed miss (SI, >= 0) of a target's ``tolerance`` as written: "%" of the
    target's value ``target`` (SI), or a quantity in the output's SI ``unit``; SpecError
    naming ``where`` for a negative size. The one reading of it, for ``solve`` and
    ``tolerance`` alike."""
    if written_unit(value) == "%":
        width = parse(value, "1", key=where) * abs(float(target))
    else:
        width = parse(value, unit, key=where)
    if not width >= 0.0:
        raise SpecError(f"{where}: a tolerance is a size (>= 0), got {echo(value)}")
    return width


@contextlib.contextmanager
def _named(where):
    """Turn a ValueError of the problem's own checks into a SpecError naming ``where``."""
    try:
        yield
    except ValueError as error:
        raise SpecError(f"{where}: {error}") from None


def parameter_units(spec, name):
    """(SI unit of parameter ``name``, the unit to show it in): the unit the scene spec writes
    the parameter in ("mm"), else its SI unit; "1" for a dimensionless one."""
    si = parameter_unit(name)
    return si, written_unit(stated_value(spec, name)) or si


def _si_unit(output_units, name):
    unit = output_units.get(name, "1")
    return None if unit == "1" else unit


def _dome_wall_guards(scene, variables):
    """[the geometry limit ``wall_fraction <= 1``] where the variables' box holds domes
    whose wall is not thinner than their radius, else []; SpecError if it holds no dome, or
    a magnet wider than a dome (a guard refused at load: the box must keep the magnet narrower)."""
    mechanics = getattr(scene, "mechanics", None)
    if not isinstance(mechanics, Dome):
        return []
    bounds = {v.name: v for v in variables}

    def extreme(name, side, fixed):
        return float(getattr(bounds[name], side)) if name in bounds else float(fixed)

    # the widest magnet of the box fits the narrowest dome (a magnet wider than its dome is refused)
    check_magnet_fits(
        extreme("magnet.radius", "upper", scene.radius),
        extreme("mechanics.outer_radius", "lower", mechanics.outer_radius),
        key="design.variables.magnet.radius.upper" if "magnet.radius" in bounds else "magnet.radius",
    )
    key = "design.variables.mechanics.thickness.lower" if "mechanics.thickness" in bounds else "mechanics.thickness"
    check_wall(
        extreme("mechanics.thickness", "lower", mechanics.thickness),
        extreme("mechanics.outer_radius", "upper", mechanics.outer_radius),
        key=key,
    )
    if extreme("mechanics.thickness", "upper", mechanics.thickness) < extreme(
        "mechanics.outer_radius", "lower", mechanics.outer_radius
    ):
        return []
    return [Limit("wall_fraction", upper=1.0)]


# Guards a spec may relax by limiting the output itself: the chip's range (a design may
# choose to clip, and its report then says so); the geometry's guards are never relaxed.
_RELAXABLE_GUARDS = ("saturation_ratio",)


def _with_guards(limits, guards):
    """The spec's limits with the guards merged in: a guard on an output the spec does not
    limit is added; on one it limits, each side the spec gives replaces the guard's for a
    relaxable guard (:data:`_RELAXABLE_GUARDS`: ``saturation_ratio <= 1.5`` is the chip
    allowed to clip), else the stricter bound of each side holds (a spec's
    ``closest_gap <= 10 mm`` gains the side ``closest_gap >= 0``; its ``closest_gap >= 1 mm``
    is kept as written)."""
    merged = {limit.output: limit for limit in limits}
    for guard in guards:
        spec = merged.get(guard.output)
        if spec is None:
            merged[guard.output] = guard
            continue
        if guard.output in _RELAXABLE_GUARDS:
            upper, lower = (
                spec.upper if spec.upper is not None else guard.upper,
                spec.lower if spec.lower is not None else guard.lower,
            )
        else:
            uppers = [b for b in (spec.upper, guard.upper) if b is not None]
            lowers = [b for b in (spec.lower, guard.lower) if b is not None]
            upper, lower = min(uppers, key=float) if uppers else None, max(lowers, key=float) if lowers else None
        merged[guard.output] = Limit(guard.output, upper=upper, lower=lower, scale=spec.scale, unit=spec.unit)
    return list(merged.values())


def _range_guards(scene, limits):
    """[the limit ``saturation_ratio <= 1``] for a scene whose readings have a range
    (:meth:`magdesign.scene.AbstractScene.chip_range`), else []. Left out where the spec's
    own ``field_max`` upper bound already keeps every reading of a Hall chip (whose reading
    is the field) inside its range: the same row twice has no multiplier of its own."""
    judged = scene.chip_range()
    if judged is None or "saturation_ratio" not in scene.output_units:
        return []
    field_max = next((limit for limit in limits if limit.output == "field_max" and limit.upper is not None), None)
    reads_field = isinstance(scene, MagnetScene) and scene.reading_unit == "T"
    if reads_field and field_max is not None and float(field_max.upper) <= float(np.min(np.asarray(judged.limit))):
        return []
    return [Limit("saturation_ratio", upper=1.0)]


# Models with cheaper levels: (table, key, model) -> (name in a report, the table holding
# its fidelity, the spec's default level, {cheap level: the exact level that confirms it}).
# A cylinder's "axis" level is exact where a scene may use it (every sensor on the axis),
# so only "dipole" needs confirming. A reduced pole is not confirmed at the moments level:
# its spec names no permeability or cells (the defaults, Ni-Fe and 16, are guesses).
_LEVELS = {
    ("mechanics", "model", "dome"): ("dome", "mechanics", "reissner", {"reissner": "axisymmetric"}),
    ("mechanics", "model", "layer"): ("layer", "mechanics", "hooke", {}),
    ("magnet", "shape", "cylinder"): ("field", "magnet", "exact", {"dipole": "exact"}),
    ("magnet", "shape", "plate"): ("pole", "pole", "reduced", {}),
}


def _leveled(spec):
    """(table, report name, level now, most exact level) of each such model in the spec."""
    for (table, key, model), (name, level_table, default, exact) in _LEVELS.items():
        entry = spec.get(table)
        if isinstance(entry, dict) and entry.get(key) == model:
            level = (spec.get(level_table) or {}).get("fidelity", default)
            # a small-strain (linear) dome has no finite-strain level to be confirmed by
            confirmable = not (name == "dome" and entry.get("material") == "linear")
            yield level_table, name, level, exact.get(level, level) if confirmable else level


def fidelity_levels(spec: dict) -> str:
    """The levels a spec's models run at, for a report ("dome reissner, field axis")."""
    return ", ".join(f"{name} {level}" for _, name, level, _ in _leveled(spec))


def exact_levels(spec: dict) -> dict | None:
    """The spec with its dome and cylinder field at their exact levels (axisymmetric dome,
    exact field for a dipole), or None when it runs at them already."""
    changes = {table: exact for table, _, level, exact in _leveled(spec) if level != exact}
    if not changes:
        return None
    exact = copy.deepcopy(spec)
    for table, level in changes.items():
        exact[table]["fidelity"] = level
    return exact


def grid_candidate(candidate, where: str) -> tuple[int, int]:
    """A candidate chip grid [rows, columns] of whole numbers of 1 or more, as (rows, columns),
    else a SpecError naming ``where``."""
    if (
        not isinstance(candidate, (list, tuple))
        or len(candidate) != 2
        or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 1 for n in candidate)
    ):
        raise SpecError(f"{where}: expected [rows, columns], two whole numbers of 1 or more, got {echo(candidate)}")
    return int(candidate[0]), int(candidate[1])


def design_grids(spec: dict) -> tuple[tuple[int, int], ...] | None:
    """The candidate chip grids of ``design.grids`` ((rows, columns) each, as written), or None
    where the spec gives none: ``magdesign solve`` solves the design once per grid, fewest chips
    first (:func:`magdesign.spec.fewest_chips`). A SpecError naming design.grids unless it is a
    non-empty list of [rows, columns] on a skin whose chips sit on ``sensor.grid``."""
    grids = spec.get("design", {}).get("grids")
    if grids is None:
        return None
    if not isinstance(grids, list) or not grids:
        raise SpecError(
            f"design.grids: expected a list of candidate chip grids [[rows, columns], ...], got {echo(grids)}"
        )
    sensor = spec.get("sensor", {})
    if spec.get("magnet", {}).get("shape") != "skin" or "grid" not in sensor or "chips" in sensor:
        raise SpecError(
            "design.grids: the candidate grids replace a skin's sensor.grid (magnet.shape = 'skin', its chips "
            "placed by sensor.grid and sensor.pitch)"
        )
    return tuple(grid_candidate(candidate, f"design.grids[{i}]") for i, candidate in enumerate(grids))


def problem_from_spec(spec: dict, *, fidelity: str | None = None):
    """Build (problem, scene) from a parsed spec with a [design] table.

    Args:
        spec: the parsed TOML (scene tables plus [design]).
        fidelity: overrides the scene's mechanics fidelity ("reissner", "axisymmetric").

    Returns:
        The :class:`Problem` whose model maps the free parameters (SI) to the scene's
        outputs, and the scene at its spec values.
    """
    scene = scene_from_spec(spec, fidelity=fidelity)
    loads = loads_from_spec(spec)
    design = sub_table(spec, "design")
    # A magnet-scene design is for the largest press of its load sweep, from its first point:
    # without a press, its compliance, closest approach and sensitivity (per newton) mean nothing.
    if isinstance(scene, MagnetScene):
        normal = np.asarray(loads.normal)  # numpy: no small JAX program to compile in a new process
        press = float(normal.max() - normal[0])
        if not press > 0.0:
            raise SpecError(
                "load.normal: a design needs a sweep that presses harder than its first point (the "
                f"press it is designed for); its largest normal load is {press:g} N above its first"
            )
    check_keys(
        "design", design, ("name", "variables", "targets", "limits", "objective", "report", "tolerances", "grids")
    )
    design_grids(spec)  # the candidate chip grids are read, and refused off a skin on a grid, by every command
    if not isinstance(design.get("name", ""), str):
        raise SpecError(f"design.name: expected the design's name (a string), got {echo(design['name'])}")
    known_parameters = parameters(scene)
    output_units = scene.output_units
    # the scene's contract: output_units names every output (tests/scene/test_output_units.py);
    # tracing the outputs to learn their names costs a second on the axisymmetric dome
    known_outputs = set(output_units)

    def output_name(where, name):
        if not isinstance(name, str) or name not in known_outputs:
            raise SpecError(f"{where}: unknown output {name!r}; expected one of {', '.join(sorted(known_outputs))}")
        return name

    variables = []
    for name, entry in sub_table(design, "variables", where="design.variables").items():
        where = f"design.variables.{name}"
        if name not in known_parameters:
            raise SpecError(f"{where}: unknown parameter; expected one of {', '.join(sorted(known_parameters))}")
        check_keys(where, entry, _VARIABLE_KEYS)
        unit, shown = parameter_units(spec, name)
        shown = written_unit(entry.get("lower")) or shown if shown == unit else shown
        values = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in _VARIABLE_KEYS if key in entry}
        for key in ("lower", "upper"):
            if key not in values:
                raise SpecError(f"{where}.{key}: missing bound; expected a quantity in {shown}")
        for key, value in values.items():
            if key != "scale":
                check_domain(name, value, key=f"{where}.{key}", unit=parameter_unit(name), written=entry[key])
        # One number in one place: a variable starts at the value the scene states for it;
        # ``start`` is for a parameter the scene leaves at its default.
        stated = stated_value(spec, name)
        if stated is not None:
            value = float(known_parameters[name])
            if "start" in values and not math.isclose(values["start"], value, rel_tol=1e-12):
                raise SpecError(
                    f"{where}.start: {echo(entry['start'])} differs from {name} = {echo(stated)}, the "
                    "scene's value, where the variable starts; drop the start or give both one number"
                )
            if values["lower"] < values["upper"] and not values["lower"] <= value <= values["upper"]:
                raise SpecError(
                    f"{where}: the scene's {name} = {echo(stated)}, where the variable starts, lies "
                    f"outside its bounds [{entry['lower']}, {entry['upper']}]"
                )
            values["start"] = value
        with _named(where):
            variables.append(Variable(name, unit=None if shown == "1" else shown, **values))

    wall_guards = _dome_wall_guards(scene, variables)

    targets = []
    for name, value in sub_table(design, "targets", where="design.targets", required=False).items():
        where = f"design.targets.{name}"
        output_name(where, name)
        unit = output_units.get(name, "1")
        if isinstance(value, dict):  # { value = "0 mT", scale = "1 mT" }: a zero target needs a scale
            check_keys(where, value, _TARGET_KEYS)
            if "value" not in value:
                raise SpecError(f"{where}.value: missing; expected a quantity in {unit}")
            entry = value
        else:
            entry = {"value": value}
        numbers = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in entry if key != "tolerance"}
        for key in numbers:
            check_output_number(f"{where}.{key}" if isinstance(value, dict) else where, entry[key], unit)
        if numbers["value"] == 0.0 and "scale" not in numbers:
            raise SpecError(
                f"{where}: a target of 0 needs a scale to judge 'met' by; write it as "
                f'{{ value = {entry["value"]!r}, scale = "..." }} with a quantity in {unit}'
            )
        if "tolerance" in entry:  # read here as the tolerance analysis reads it: one rule for both
            target_tolerance(entry["tolerance"], numbers["value"], unit, f"{where}.tolerance")
        with _named(where):
            targets.append(
                Target(name, numbers["value"], scale=numbers.get("scale"), unit=written_unit(entry["value"]))
            )

    limits = []
    for name, entry in sub_table(design, "limits", where="design.limits", required=False).items():
        where = f"design.limits.{name}"
        output_name(where, name)
        check_keys(where, entry, _LIMIT_KEYS)
        if not entry:
            raise SpecError(f"{where}: expected an upper and/or a lower bound")
        unit = output_units.get(name, "1")
        bounds = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in entry}
        for key in bounds:
            check_output_number(f"{where}.{key}", entry[key], unit)
        if not set(bounds) - {"scale"}:
            raise SpecError(f"{where}: expected an upper and/or a lower bound")
        written = written_unit(entry.get("upper", entry.get("lower")))
        with _named(where):
            limits.append(Limit(name, **bounds, unit=written))

    objective = None
    objective_table = sub_table(design, "objective", where="design.objective", required=False)
    if objective_table:
        check_keys("design.objective", objective_table, tuple(_SENSES))
        if len(objective_table) != 1:
            raise SpecError('design.objective: expected exactly one of maximize = "output" or minimize = "output"')
        ((sense, name),) = objective_table.items()
        objective = Objective(output_name(f"design.objective.{sense}", name), sense=_SENSES[sense])

    report = design.get("report", {})
    if isinstance(report, list) and all(isinstance(name, str) for name in report):
        report = dict.fromkeys(report)
    if not isinstance(report, dict):
        raise SpecError(
            f'design.report: expected output names with display units, e.g. {{ closest_gap = "mm" }}, got {echo(report)}'
        )
    for name, unit in report.items():
        output_name(f"design.report.{name}", name)
        if unit is not None:
            parse(f"1 {unit}", output_units.get(name, "1"), key=f"design.report.{name}")
    # every reported output carries a unit: the spec's, else its SI unit
    report = {name: unit or _si_unit(output_units, name) for name, unit in report.items()}
    if objective is not None and objective.output not in report:
        report[objective.output] = _si_unit(output_units, objective.output)

    if not targets and not limits and objective is None:
        raise SpecError("design: expected at least one of [design.targets], [design.limits], [design.objective]")

    # The geometry is a limit every design meets or reports: the magnet never reaches the sensor
    # plane nor floats above the layer or dome that carries it, the dome or layer never travels
    # beyond its own room, a dome's wall is thinner than its radius (a load that drives the magnet through gives limit_violated, not a negative gap).
    if isinstance(scene, MagnetScene):
        guards = [
            Limit("closest_gap", lower=0.0, scale=float(scene.height), unit="mm"),
            Limit("travel_fraction", upper=1.0),
            Limit("embed", lower=0.0, scale=float(scene.height), unit="mm"),
        ]  # the magnet never floats above its part
        if isinstance(scene.mechanics, Dome):  # nor hangs in a dome's cavity below its wall
            guards.append(Limit("reach", lower=0.0, scale=float(scene.height), unit="mm"))
        limits = _with_guards(limits, guards + wall_guards)
    # Every design keeps its chip's readings inside the chip's range, or says it does not
    # (limit_violated naming saturation_ratio), unless the spec relaxes that limit itself.
    limits = _with_guards(limits, _range_guards(scene, limits))
    converged = MECHANICS_CONVERGED if MECHANICS_CONVERGED in known_outputs else None
    with _named("design"):
        problem = Problem(
            SceneModel(scene, loads),
            variables,
            targets=targets,
            limits=limits,
            objective=objective,
            report=report,
            converged=converged,
        )
    at_levels = spec if fidelity is None else {**spec, "mechanics": {**spec.get("mechanics", {}), "fidelity": fidelity}}
    remember_source(problem, copy.deepcopy(at_levels))
    return problem, scene
