"""The tolerance grammar: a design spec's [design.tolerances] table, read into a
:class:`ToleranceProblem` (the Monte Carlo and the robust solve over it are
:mod:`magdesign.design.tolerance`).

A design spec states its tolerances beside its targets and limits::

    [design.tolerances]
    distribution = "normal"          # or "uniform": sizes are standard deviations, or half-widths
    "magnet.remanence" = "3 %"       # any scene parameter: "%" of its value, or a quantity in its unit
    "mechanics.c10" = { value = "5 %", distribution = "uniform" }   # one entry's own distribution
    placement = "50 um"              # each sensor's x, y, z offset (or a list of 3 quantities)
    tilt = "2 deg"                   # each chip's tilt angles alpha, beta, gamma (or a list of 3)
    temperature = "10 K"             # the magnet's temperature change (drift of its remanence)
    [design.targets]
    compliance = { value = "0.32 mm/N", tolerance = "5 %" }   # met when |achieved - value| <= 5 %

Placement, tilt and temperature are values of the scene's own effects
(:class:`~magdesign.scene.effects.Placement`, ``ChipTilt``, ``TemperatureDrift``); where the
scene does not list one, it is added at zero (temperature: with the ``[scene]
temperature_coefficient``, default NdFeB's), which leaves the outputs as they are. A scene
whose field is the on-axis closed form (``[magnet] fidelity = "axis"``, exact on the axis)
is read with the exact field where a placement tolerance moves its sensors off the axis.
Every error is a one-line :class:`~magdesign.units.SpecError` naming the key.
"""

import dataclasses
import math

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from magdesign.design.problem import Problem
from magdesign.scene import AbstractScene, Loads, loads_from_spec, parameters, with_parameters
from magdesign.scene import effects as fx
from magdesign.spec.checks import domain_text, fields, listed
from magdesign.spec.design import problem_from_spec, target_tolerance
from magdesign.spec.keys import KEYS
from magdesign.spec.scene import NDFEB_DRIFT
from magdesign.spec.table import check_keys, parameter_unit, sub_table
from magdesign.units import SpecError, echo, parse, written_unit

DISTRIBUTIONS = tuple(KEYS["design.tolerances.distribution"].choices)
# The standard deviation of a unit variate: N(0, 1), or uniform on [-1, 1].
_UNIT_STD = {"normal": 1.0, "uniform": 1.0 / math.sqrt(3.0)}
# Inputs that are effects' values: spec key -> (effect class, its field, SI unit, per sensor (x, y, z)?).
EFFECT_INPUTS = {
    "placement": (fx.Placement, "offsets", "m", True),
    "tilt": (fx.ChipTilt, "angles", "rad", True),
    "temperature": (fx.TemperatureDrift, "temperature_change", "K", False),
}
# The axes of a per-sensor input, naming its variates ("placement.x").
AXES = {"placement": ("x", "y", "z"), "tilt": ("alpha", "beta", "gamma")}


class Tolerance(eqx.Module):
    """One toleranced input.

    Attributes:
        name: a scene parameter's spec key, or "placement", "tilt", "temperature".
        size: the standard deviation ("normal") or half-width ("uniform"): SI, or a
            fraction of the nominal value where ``relative``; (3,) for placement (m, along
            x, y, z) and tilt (rad, alpha, beta, gamma), else a scalar.
        relative: ``size`` is a fraction of the parameter's value at the design.
        distribution: "normal" or "uniform".
        written: the size as the spec wrote it, for reports.
    """

    name: str = eqx.field(static=True)
    size: Float[Array, "*d"]
    relative: bool = eqx.field(static=True)
    distribution: str = eqx.field(static=True)
    written: str = eqx.field(static=True)

    def components(self, sensors: int) -> tuple[int, ...]:
        """The shape of this input's variates: (sensors, 3) for placement and tilt, else ()."""
        return (sensors, 3) if self.name in AXES else ()

    def labels(self, sensors: int) -> list[str]:
        """The group of each variate, for sensitivities: "placement.x" (every sensor's x), ..."""
        if self.name in AXES:
            return [f"{self.name}.{axis}" for _ in range(sensors) for axis in AXES[self.name]]
        return [self.name]


class ToleranceProblem(eqx.Module):
    """A design problem and the tolerances of its inputs.

    Attributes:
        problem: the design (:class:`~magdesign.design.Problem` whose model is the scene's).
        scene: the design's scene, with the effects its tolerances move (added at zero
            where the spec's scene does not list them: the same outputs).
        loads: the load sweep the outputs are read over.
        inputs: the toleranced inputs.
        target_tolerances: (output, half-width (SI)) of each target the yield judges.
        sensors: the scene's sensor count S.
    """

    problem: Problem
    scene: AbstractScene
    loads: Loads
    inputs: tuple[Tolerance, ...]
    target_tolerances: tuple[tuple[str, float], ...] = eqx.field(static=True)
    sensors: int = eqx.field(static=True)

    @property
    def labels(self) -> list[str]:
        """The group of each of the D variates, in order."""
        return [label for t in self.inputs for label in t.labels(self.sensors)]

    @property
    def unit_std(self) -> np.ndarray:
        """(D,) the standard deviation of each unit variate (1, or 1/sqrt(3) if uniform)."""
        return np.concatenate(
            [np.full(max(1, math.prod(t.components(self.sensors))), _UNIT_STD[t.distribution]) for t in self.inputs]
        )

    @property
    def uniform(self) -> np.ndarray:
        """(D,) True where a variate is uniform."""
        return self.unit_std != 1.0

    def at(self, values: dict) -> AbstractScene:
        """The scene at design values {parameter: SI}, the problem's fixed inputs held."""
        fixed = dict(zip(getattr(self.problem, "fixed_names", ()), getattr(self.problem, "fixed_values", ())))
        return with_parameters(self.scene, {**fixed, **values})


def _size(value, unit, where, per_axis):
    """(size, relative?) of one entry: SI, (3,) for a per-axis input; a fraction where a
    parameter's tolerance is written in "%"."""
    relative = not per_axis and unit != "K" and written_unit(value) == "%"
    if per_axis and isinstance(value, list):
        if len(value) != 3:
            raise SpecError(f"{where}: expected one quantity in {unit} or a list of 3 (x, y, z), got {echo(value)}")
        sizes = [parse(item, unit, key=where) for item in value]
    else:
        sizes = [parse(value, "1" if relative else unit, key=where)] * (3 if per_axis else 1)
    if any(size < 0 for size in sizes):
        raise SpecError(f"{where}: a tolerance is a size (>= 0), got {echo(value)}")
    return (np.asarray(sizes) if per_axis else np.asarray(sizes[0])), relative


# A normal tolerance's draws stay in the parameter's physical domain out to this many standard
# deviations (beyond, 0.27 % of draws for a two-sided bound: a spread this wide is refused).
DOMAIN_SIGMAS = 3.0


def _check_spread(name, nominal, width, distribution, where):
    """SpecError naming ``where`` where the draws of scene parameter ``name`` (``nominal`` SI,
    a standard deviation or half-width ``width`` SI) leave its physical domain (the key
    table's): a uniform spread whose interval crosses a bound, a normal one whose
    :data:`DOMAIN_SIGMAS` sigmas cross it. Refused rather than truncated: a draw outside is
    not a part that exists (a negative remanence or stiffness)."""
    domain = listed(name).domain
    if domain is None or width == 0.0:
        return
    reach = width * (1.0 if distribution == "uniform" else DOMAIN_SIGMAS)
    low, low_ok, high, high_ok = domain
    lowest, highest = nominal - reach, nominal + reach
    below = low is not None and (lowest < low or (lowest == low and not low_ok))
    above = high is not None and (highest > high or (highest == high and not high_ok))
    if below or above:
        spread = "its interval" if distribution == "uniform" else f"{DOMAIN_SIGMAS:g} standard deviations"
        raise SpecError(
            f"{where}: the draws of {name} reach {lowest:g} to {highest:g} {parameter_unit(name)} ({spread} about "
            f"{nominal:g}), "
            f"outside its physical domain {domain_text(domain)}; expected a smaller tolerance"
        )


def check_spreads(inputs, scene, where=None):
    """:func:`_check_spread` of every toleranced scene parameter among ``inputs`` at
    ``scene``'s values, naming ``where`` (default: the key, about the scene's value). Run
    at load and again before a Monte Carlo: a solve moves the design variables from the
    spec's start, and a spread that fits about the start can leave the domain about the
    solved value (a wall solved thinner than its absolute tolerance)."""
    known = parameters(scene)
    for tolerance in inputs:
        if tolerance.name in known:
            nominal = float(known[tolerance.name])
            width = float(tolerance.size) * (abs(nominal) if tolerance.relative else 1.0)
            about = f"design.tolerances.{tolerance.name} (about the design's {tolerance.name} = {nominal:g})"
            _check_spread(tolerance.name, nominal, width, tolerance.distribution, where or about)


def _with_effect(scene, name, spec):
    """The scene with the effect input ``name`` moves, added at zero where it is not listed."""
    cls, field, _, _ = EFFECT_INPUTS[name]
    if any(isinstance(effect, cls) for effect in scene.effects):
        return scene
    if name == "temperature":
        coefficient = parse(
            spec.get("scene", {}).get("temperature_coefficient", NDFEB_DRIFT),
            "1/K",
            key="scene.temperature_coefficient",
        )
        effect = fx.TemperatureDrift(coefficient=jnp.asarray(coefficient), temperature_change=jnp.asarray(0.0))
    else:
        effect = cls(**{field: jnp.zeros(3)})
    return eqx.tree_at(lambda s: s.effects, scene, fx.in_order([*scene.effects, effect]))


def tolerance_problem_from_spec(
    spec: dict, *, fidelity: str | None = None, built: tuple[Problem, AbstractScene] | None = None
) -> ToleranceProblem:
    """Read a design spec with a [design.tolerances] table (see the module docstring).

    Args:
        spec: the parsed TOML (scene tables, [design] with its tolerances).
        fidelity: overrides the scene's mechanics fidelity, as for
            :func:`~magdesign.spec.design.problem_from_spec`.
        built: the (problem, scene) that :func:`~magdesign.spec.design.problem_from_spec`
            already built from ``spec`` (at ``fidelity``), reused rather than built again (the
            spec stage costs seconds for a skin); None builds it here.

    Raises:
        SpecError: one line naming the key: a tolerance on an input the scene does not
            have, a unit that does not fit, a negative size, an unknown distribution.
    """
    problem, scene = problem_from_spec(spec, fidelity=fidelity) if built is None else built
    table = dict(sub_table(sub_table(spec, "design"), "tolerances", where="design.tolerances"))
    default = table.pop("distribution", "normal")
    if default not in DISTRIBUTIONS:
        raise SpecError(f"design.tolerances.distribution: expected one of 'normal', 'uniform', got {echo(default)}")
    if not table:
        raise SpecError(
            "design.tolerances: expected at least one toleranced input (a scene parameter, placement, "
            "tilt or temperature)"
        )
    known = parameters(scene)
    sensors = int(scene.sensor_poses()[0].shape[0])
    inputs = []
    for name, entry in table.items():
        where = f"design.tolerances.{name}"
        distribution = default
        if isinstance(entry, dict):
            check_keys(where, entry, fields("design.tolerances.*"))
            if "value" not in entry:
                raise SpecError(f"{where}.value: missing; expected the tolerance's size")
            distribution = entry.get("distribution", default)
            if distribution not in DISTRIBUTIONS:
                raise SpecError(f"{where}.distribution: expected one of 'normal', 'uniform', got {echo(distribution)}")
            where, entry = f"{where}.value", entry["value"]
        if name in EFFECT_INPUTS:
            _, _, unit, per_axis = EFFECT_INPUTS[name]
            if name == "placement" and getattr(scene, "fidelity", None) == "axis":
                # the on-axis form is exact on the axis only, which a placement error leaves
                scene = dataclasses.replace(scene, fidelity="exact")
            scene = _with_effect(scene, name, spec)
        elif name in known:
            unit, per_axis = parameter_unit(name), False
        else:
            raise SpecError(
                f"{where}: unknown input; expected a scene parameter ({', '.join(sorted(known))}), "
                "placement, tilt or temperature"
            )
        size, relative = _size(entry, unit, where, per_axis)
        shown = entry if isinstance(entry, str) else echo(entry)
        inputs.append(Tolerance(name, jnp.asarray(size), relative, distribution, shown))
        check_spreads(inputs[-1:], scene, where)

    target_tolerances = []
    for target in problem.targets:
        entry = spec["design"]["targets"][target.output]
        if not (isinstance(entry, dict) and "tolerance" in entry):
            continue
        where, value = f"design.targets.{target.output}.tolerance", entry["tolerance"]
        width = target_tolerance(value, target.value, scene.output_units.get(target.output, "1"), where)
        target_tolerances.append((target.output, width))
    return ToleranceProblem(problem, scene, loads_from_spec(spec), tuple(inputs), tuple(target_tolerances), sensors)
