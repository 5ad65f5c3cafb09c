"""Design specs: a scene spec plus a [design] table, read into a :class:`Problem`.

    [design.variables]                       # scene parameters set free, by dotted spec key
    "geometry.gap" = { lower = "3 mm", upper = "15 mm", start = "7 mm" }
    [design.targets]                         # equalities on scene outputs
    compliance = "0.32 mm/N"
    [design.limits]                          # inequalities on scene outputs
    field_closest = { upper = "4.8 mT" }
    [design.objective]                       # optional: maximize or minimize one output
    maximize = "sensitivity"
    [design.report]                          # optional: more outputs to show, with display units
    closest_gap = "mm"

A variable's bounds take the unit the scene spec gives that parameter; a target's or
limit's value takes the unit of its output (the scene's ``output_units``). Every error is
a one-line :class:`~magdesign.units.SpecError` naming the key.
"""

import contextlib
import copy
import importlib.resources
import tomllib
from collections.abc import Mapping

import equinox as eqx
import jax
from jaxtyping import Array

from magdesign.design.problem import Limit, Objective, Problem, Target, Variable
from magdesign.design.sweep import sweepable
from magdesign.scene import (MECHANICS_CONVERGED, AbstractScene, Loads, MagnetScene, loads_from_spec, outputs,
                             parameters, scene_from_spec, with_parameters)
from magdesign.scene._spec import check_domain, check_keys, parameter_unit, sub_table
from magdesign.scene.build import check_wall
from magdesign.scene.mechanics import Dome
from magdesign.units import SpecError, echo, parse, written_unit

_VARIABLE_KEYS = ("lower", "upper", "start", "scale")
_LIMIT_KEYS = ("lower", "upper", "scale")
_TARGET_KEYS = ("value", "scale", "tolerance")  # tolerance: read by magdesign.design.tolerance
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
    """The built-in default design: the seed-001 dome with a Hall sensor (PHYSICS.md 2.3)."""
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


@contextlib.contextmanager
def _named(where):
    """Turn a ValueError of the problem's own checks into a SpecError naming ``where``."""
    try:
        yield
    except ValueError as error:
        raise SpecError(f"{where}: {error}") from None


def _parameter_unit(spec, name):
    """(SI unit of parameter ``name``, the unit to show it in): the unit the scene spec writes
    the parameter in ("mm"), else its SI unit; "1" for a dimensionless one."""
    table, _, key = name.rpartition(".")
    value = spec.get(table, {}).get(key) if table else spec.get(key)
    si = parameter_unit(name)
    return si, written_unit(value) or si


def input_units(spec: dict, problem: Problem, scene: AbstractScene) -> dict[str, tuple[str, str]]:
    """{key: (SI unit, unit to show it in)} of every input a sweep of the spec's problem can
    vary (:func:`magdesign.design.sweep.sweepable`): a target's value and a limit's bound in
    their output's unit (as the spec writes them), a scene parameter in the unit the scene
    spec writes it; "1" for a dimensionless one."""
    units = {}
    for key in sweepable(problem):
        output, _, side = key.rpartition(".")
        target = next((t for t in problem.targets if t.output == key), None)
        limit = next((lim for lim in problem.limits if lim.output == output and side in lim.sides), None)
        if target is not None or limit is not None:
            si = scene.output_units.get(target.output if target is not None else output, "1")
            units[key] = (si, (target or limit).unit or si)
        else:
            units[key] = _parameter_unit(spec, key)
    return units


def _si_unit(output_units, name):
    unit = output_units.get(name, "1")
    return None if unit == "1" else unit


def _dome_wall_guards(scene, variables):
    """[the geometry limit ``wall_fraction <= 1``] where the variables' box holds domes
    whose wall is not thinner than their radius, else []; SpecError if it holds no dome."""
    mechanics = getattr(scene, "mechanics", None)
    if not isinstance(mechanics, Dome):
        return []
    bounds = {v.name: v for v in variables}

    def extreme(name, side, fixed):
        return float(getattr(bounds[name], side)) if name in bounds else float(fixed)

    key = "design.variables.mechanics.thickness.lower" if "mechanics.thickness" in bounds else "mechanics.thickness"
    check_wall(extreme("mechanics.thickness", "lower", mechanics.thickness),
               extreme("mechanics.outer_radius", "upper", mechanics.outer_radius), key=key)
    if extreme("mechanics.thickness", "upper", mechanics.thickness) < extreme("mechanics.outer_radius", "lower", mechanics.outer_radius):
        return []
    return [Limit("wall_fraction", upper=1.0)]


def _with_guards(limits, guards):
    """The spec's limits with the geometry guards merged in: a guard on an output the spec
    does not limit is added; on one it limits, the stricter bound of each side holds (a
    spec's ``closest_gap <= 10 mm`` gains the side ``closest_gap >= 0``; its
    ``closest_gap >= 1 mm`` is kept as written)."""
    merged = {limit.output: limit for limit in limits}
    for guard in guards:
        spec = merged.get(guard.output)
        if spec is None:
            merged[guard.output] = guard
            continue
        upper = [b for b in (spec.upper, guard.upper) if b is not None]
        lower = [b for b in (spec.lower, guard.lower) if b is not None]
        merged[guard.output] = Limit(
            guard.output,
            upper=min(upper, key=float) if upper else None,
            lower=max(lower, key=float) if lower else None,
            scale=spec.scale,
            unit=spec.unit,
        )
    return list(merged.values())


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
        press = float(loads.max_normal - loads.normal[0])
        if not press > 0.0:
            raise SpecError("load.normal: a design needs a sweep that presses harder than its first point (the "
                            f"press it is designed for); its largest normal load is {press:g} N above its first")
    check_keys("design", design, ("variables", "targets", "limits", "objective", "report", "tolerances"))
    known_parameters = parameters(scene)
    output_units = scene.output_units
    known_outputs = set(jax.eval_shape(outputs, scene, loads))

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
        unit, shown = _parameter_unit(spec, name)
        shown = written_unit(entry.get("lower")) or shown if shown == unit else shown
        values = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in _VARIABLE_KEYS if key in entry}
        for key in ("lower", "upper"):
            if key not in values:
                raise SpecError(f"{where}.{key}: missing bound; expected a quantity in {shown}")
        for key, value in values.items():
            if key != "scale":
                check_domain(name, value, key=f"{where}.{key}", unit=parameter_unit(name))
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
        if numbers["value"] == 0.0 and "scale" not in numbers:
            raise SpecError(f"{where}: a target of 0 needs a scale to judge 'met' by; write it as "
                            f"{{ value = {entry['value']!r}, scale = \"...\" }} with a quantity in {unit}")
        with _named(where):
            targets.append(Target(name, numbers["value"], scale=numbers.get("scale"), unit=written_unit(entry["value"])))

    limits = []
    for name, entry in sub_table(design, "limits", where="design.limits", required=False).items():
        where = f"design.limits.{name}"
        output_name(where, name)
        check_keys(where, entry, _LIMIT_KEYS)
        if not entry:
            raise SpecError(f"{where}: expected an upper and/or a lower bound")
        unit = output_units.get(name, "1")
        bounds = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in entry}
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
            raise SpecError("design.objective: expected exactly one of maximize = \"output\" or minimize = \"output\"")
        (sense, name), = objective_table.items()
        objective = Objective(output_name(f"design.objective.{sense}", name), sense=_SENSES[sense])

    report = design.get("report", {})
    if isinstance(report, list) and all(isinstance(name, str) for name in report):
        report = dict.fromkeys(report)
    if not isinstance(report, dict):
        raise SpecError(f"design.report: expected output names with display units, e.g. {{ closest_gap = \"mm\" }}, got {echo(report)}")
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
    # plane, the dome or layer never travels beyond its own room, a dome's wall is thinner than
    # its radius (a load that drives the magnet through gives limit_violated, not a negative gap).
    if isinstance(scene, MagnetScene):
        guards = [Limit("closest_gap", lower=0.0, scale=float(scene.height), unit="mm"), Limit("travel_fraction", upper=1.0)]
        limits = _with_guards(limits, guards + wall_guards)
    converged = MECHANICS_CONVERGED if MECHANICS_CONVERGED in known_outputs else None
    with _named("design"):
        problem = Problem(
            SceneModel(scene, loads), variables, targets=targets, limits=limits, objective=objective, report=report,
            converged=converged,
        )
    return problem, scene
