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

import importlib.resources
import tomllib
from collections.abc import Mapping

import equinox as eqx
import jax
from jaxtyping import Array

from magdesign.design.problem import Limit, Objective, Problem, Target, Variable
from magdesign.scene import MECHANICS_CONVERGED, AbstractScene, outputs, parameters, scene_from_spec, with_parameters
from magdesign.units import SpecError, parse, written_unit

_VARIABLE_KEYS = ("lower", "upper", "start", "scale")
_LIMIT_KEYS = ("lower", "upper")
_SENSES = {"maximize": "max", "minimize": "min"}


class SceneModel(eqx.Module):
    """A scene's outputs as a function of some of its parameters: the model of a design.

    A module rather than a closure: two problems built from the same spec compare equal
    in structure, so a jitted solve compiled for one is reused for the other.
    """

    scene: AbstractScene

    def __call__(self, values: Mapping[str, Array]) -> dict[str, Array]:
        """{parameter: value (SI)} -> {output: scalar (SI)} (see :func:`magdesign.scene.outputs`)."""
        return outputs(with_parameters(self.scene, values))


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


def _table(spec, key, *, required):
    value = spec.get(key)
    if value is None and not required:
        return {}
    if not isinstance(value, dict):
        raise SpecError(f"{key}: expected a table")
    return value


def _check_keys(where, entry, allowed):
    if not isinstance(entry, dict):
        raise SpecError(f"{where}: expected a table with keys {', '.join(allowed)}, got {entry!r}")
    unknown = sorted(set(entry) - set(allowed))
    if unknown:
        raise SpecError(f"{where}.{unknown[0]}: unknown key; expected one of {', '.join(allowed)}")


def _parameter_unit(spec, name):
    """The unit the scene spec writes parameter ``name`` in ("mm"), or "1" for a plain number."""
    table, _, key = name.rpartition(".")
    value = spec.get(table, {}).get(key) if table else spec.get(key)
    return written_unit(value) or "1"


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
    design = _table(spec, "design", required=True)
    # A magnet-scene design is for the largest press of its load sweep: without one, its
    # compliance travel, closest approach and sensitivity (per newton) mean nothing.
    if hasattr(scene, "max_force") and not float(scene.max_force) > 0.0:
        raise SpecError("load.normal: a design needs a largest normal load above 0 N (the press it is designed "
                        f"for); the sweep's largest is {float(scene.max_force):g} N")
    _check_keys("design", design, ("variables", "targets", "limits", "objective", "report"))
    known_parameters = parameters(scene)
    output_units = scene.output_units
    known_outputs = set(jax.eval_shape(outputs, scene))

    def output_name(where, name):
        if name not in known_outputs:
            raise SpecError(f"{where}: unknown output {name!r}; expected one of {', '.join(sorted(known_outputs))}")
        return name

    variables = []
    for name, entry in _table(design, "variables", required=True).items():
        where = f"design.variables.{name}"
        if name not in known_parameters:
            raise SpecError(f"{where}: unknown parameter; expected one of {', '.join(sorted(known_parameters))}")
        _check_keys(where, entry, _VARIABLE_KEYS)
        unit = _parameter_unit(spec, name)
        values = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in _VARIABLE_KEYS if key in entry}
        for key in ("lower", "upper"):
            if key not in values:
                raise SpecError(f"{where}.{key}: missing bound; expected a quantity in {unit}")
        try:
            variables.append(Variable(name, unit=None if unit == "1" else unit, **values))
        except ValueError as error:
            raise SpecError(f"{where}: {error}") from None

    targets = []
    for name, value in _table(design, "targets", required=False).items():
        where = f"design.targets.{name}"
        output_name(where, name)
        value_si = parse(value, output_units.get(name, "1"), key=where)
        targets.append(Target(name, value_si, unit=written_unit(value)))

    limits = []
    for name, entry in _table(design, "limits", required=False).items():
        where = f"design.limits.{name}"
        output_name(where, name)
        _check_keys(where, entry, _LIMIT_KEYS)
        if not entry:
            raise SpecError(f"{where}: expected an upper and/or a lower bound")
        unit = output_units.get(name, "1")
        bounds = {key: parse(entry[key], unit, key=f"{where}.{key}") for key in entry}
        limits.append(Limit(name, **bounds, unit=written_unit(next(iter(entry.values())))))

    objective = None
    objective_table = _table(design, "objective", required=False)
    if objective_table:
        _check_keys("design.objective", objective_table, tuple(_SENSES))
        if len(objective_table) != 1:
            raise SpecError("design.objective: expected exactly one of maximize = \"output\" or minimize = \"output\"")
        (sense, name), = objective_table.items()
        objective = Objective(output_name(f"design.objective.{sense}", name), sense=_SENSES[sense])

    report = design.get("report", {})
    if isinstance(report, list):
        report = dict.fromkeys(report)
    if not isinstance(report, dict):
        raise SpecError(f"design.report: expected output names with display units, e.g. {{ closest_gap = \"mm\" }}, got {report!r}")
    for name, unit in report.items():
        output_name(f"design.report.{name}", name)
        if unit is not None:
            parse(f"1 {unit}", output_units.get(name, "1"), key=f"design.report.{name}")

    if not targets and not limits and objective is None:
        raise SpecError("design: expected at least one of [design.targets], [design.limits], [design.objective]")

    converged = MECHANICS_CONVERGED if MECHANICS_CONVERGED in known_outputs else None
    problem = Problem(
        SceneModel(scene), variables, targets=targets, limits=limits, objective=objective, report=report,
        converged=converged,
    )
    return problem, scene
