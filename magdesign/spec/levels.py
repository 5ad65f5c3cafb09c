"""The ladder of levels of each model a spec runs, the error estimate of a design's or a
simulation's outputs from the next finer level, and a design solved to an accuracy.

A model computed more or less exactly (the dome's mechanics, a cylinder magnet's field,
the suspension pole, the ``[[soft]]`` parts) has a ladder of levels, cheapest first
(:data:`LADDERS`). The estimate of an output at a point comes from how far it moves when one
model at a time is raised to its next level (at its ladder's top: lowered to the level
below, the estimate from the top two): the move itself from a cheaper model to a finer one;
between two meshes or cell sizes, the model's own rule where it has one (the dome's mesh
ladder: :func:`magdesign.mechanics.dome.dome_compliance`'s estimate, measured on its
meshes; a skin's linear field: :func:`skin_field_error`) and else Roache's grid
convergence index of the move (:func:`grid_factor`); the largest over the models, and the
model that made it.
"""

import copy
import dataclasses
import math
from collections.abc import Callable, Mapping
from typing import NamedTuple

from magdesign import _export
from magdesign._numerics import ROUNDING_SPREAD
from magdesign._progress import stage
from magdesign.design import solve
from magdesign.design.report import DesignResult, format_quantity
from magdesign.fields.layer_field import FINER_NODES, finer
from magdesign.mechanics._ladder import bound as dome_mesh_error
from magdesign.mechanics.dome import MESH_LADDER
from magdesign.scene import MECHANICS_CONVERGED, loads_from_spec, outputs, with_parameters
from magdesign.scene.skin_scene import default_resolution
from magdesign.spec.design import problem_from_spec
from magdesign.spec.scene import POLE_CELLS, SOFT_CELLS, scene_from_spec
from magdesign.spec.table import Table
from magdesign.units import SpecError

# The axisymmetric dome's meshes (its own ladder), the moments pole's cells along its rod
# and the soft parts' cells along their longest side, coarsest first.
DOME_MESHES = MESH_LADDER
POLE_CELL_LADDER = (8, 12, 16, 24)
SOFT_CELL_LADDER = (8, 12, 16)


def _table(spec, name):
    entry = spec.get(name)
    return entry if isinstance(entry, dict) else {}


def _dome_rank(spec):
    """0 at Reissner's level, else the mesh's linear resolution sqrt(wall x meridian elements)."""
    mechanics = _table(spec, "mechanics")
    if mechanics.get("fidelity", "reissner") == "reissner":
        return 0
    wall, meridian = mechanics.get("mesh", DOME_MESHES[0])
    return math.sqrt(wall * meridian)


def _dome_label(spec):
    mechanics = _table(spec, "mechanics")
    level = mechanics.get("fidelity", "reissner")
    return level if level == "reissner" else f"{level} {'x'.join(map(str, mechanics.get('mesh', DOME_MESHES[0])))}"


def _pole_rank(spec):
    pole = _table(spec, "pole")
    return 0 if pole.get("fidelity", "reduced") == "reduced" else pole.get("cells", POLE_CELLS)


def _soft_rank(spec):
    return min(part.get("cells", SOFT_CELLS) for part in spec["soft"])


def _skin_applies(spec):
    magnet = _table(spec, "magnet")
    return magnet.get("shape") == "skin" and magnet.get("field", "linear") == "linear" and "magnets" not in magnet


def _skin_default(spec):
    """The skin's linear field's default (n_x, n_y, Gauss nodes) for its layer, chips and
    pattern (:func:`~magdesign.scene.skin_scene.default_resolution`)."""
    size = Table(spec, "mechanics").quantities("size", "m", length=2)
    depth = Table(spec, "sensor").quantity("depth", "m")
    magnet = Table(spec, "magnet")
    period = magnet.quantity("period", "m") if magnet.has("period") else None
    return default_resolution(size, depth, period)


def _skin_resolution(spec):
    given = _table(spec, "magnet").get("resolution")
    return _skin_default(spec) if given is None else tuple(given)


def _skin_rank(spec):
    """The linear field's in-plane resolution sqrt(n_x n_y)."""
    nx, ny, _ = _skin_resolution(spec)
    return math.sqrt(nx * ny)


def _skin_levels(spec):
    """The linear field's resolutions, each the :func:`~magdesign.fields.layer_field.finer`
    of the one before: half the default's nodes across (at least 2) and FINER_NODES fewer
    Gauss nodes (at least 1), the default, and its finer one; for a resolution the spec
    states off these, that resolution and its finer one. Below the top a level's neighbour is
    then its finer one (the pair :meth:`~magdesign.scene.skin_scene.SkinScene.field_error`
    compares, SKIN_FINER_FACTOR's), never a level barely finer, whose move says little."""
    default = _skin_default(spec)
    nx, ny, nodes = default
    coarse = (max(2, -(-nx // 2)), max(2, -(-ny // 2)), max(1, nodes - FINER_NODES))
    resolutions = (coarse, default, finer(default))
    given = _skin_resolution(spec)
    if given not in resolutions:
        resolutions = (given, finer(given))
    return tuple({"magnet.resolution": list(resolution)} for resolution in resolutions)


# A skin's outputs converge at an order of 1.5 to 2.5 in the linear field's node spacing
# (each doubling of the nodes across cut their error 3 to 6 times, measured against 4 times
# the default's nodes on two layers: tests/spec/test_skin_levels.py): a level's error is its
# move to the next finer level plus that level's error, at most the move again for an order
# of 1 or more, so the estimate is SKIN_FINER_FACTOR times the move; at the top, compared
# with the level below, the move itself (the coarser level's error, which bounds the finer's).
SKIN_FINER_FACTOR = 2.0


def skin_field_error(value, other, other_is_finer):
    """The skin's estimate of an output ``value`` from its ``other`` value at the neighbouring
    resolution (finer where ``other_is_finer``), in the output's unit: SKIN_FINER_FACTOR
    times their difference from a finer level, the difference itself from a coarser one."""
    return (SKIN_FINER_FACTOR if other_is_finer else 1.0) * abs(value - other)


@dataclasses.dataclass(frozen=True)
class Ladder:
    """One model's levels, cheapest first.

    Attributes:
        model: its name in reports ("dome").
        applies: whether a spec runs the model.
        levels: each level as {"table.key": value} set in the spec (None: the key dropped;
            in an array of tables, [[soft]], set in each table), or a function of the spec
            giving them (levels relative to the spec's own sizes: the skin's).
        rank: a spec's place on the ladder: 0 at a cheaper model's level, else the linear
            resolution of the discretisation (elements or cells along a length).
        label: a spec's level in words ("axisymmetric 3x24").
        closed_top: whether the top level is a closed form, exact to rounding: at the top
            the model has no estimate (a finer level exists nowhere).
        order: the order p of the discretisation's convergence in its resolution, for
            :func:`grid_factor`.
        mesh_error: the model's own estimate between two of its discretisations, in
            place of :func:`grid_factor`: (value, the neighbour's value, whether the
            neighbour is finer) -> the value's absolute error; None: the grid factor.
    """

    model: str
    applies: Callable[[dict], bool]
    levels: tuple[Mapping[str, object], ...] | Callable[[dict], tuple[Mapping[str, object], ...]]
    rank: Callable[[dict], float]
    label: Callable[[dict], str]
    closed_top: bool = False
    order: float = 1.0
    mesh_error: Callable[[float, float, bool], float] | None = None


LADDERS = (
    Ladder(
        "dome",
        lambda spec: _table(spec, "mechanics").get("model") == "dome",
        (
            {"mechanics.fidelity": "reissner", "mechanics.mesh": None},
            *({"mechanics.fidelity": "axisymmetric", "mechanics.mesh": list(mesh)} for mesh in DOME_MESHES),
        ),
        _dome_rank,
        _dome_label,
        mesh_error=dome_mesh_error,
    ),
    # A cylinder's "axis" level is the closed form on the axis, exact where a spec may use it:
    # such a field has no ladder.
    Ladder(
        "field",
        lambda spec: (
            _table(spec, "magnet").get("shape") == "cylinder" and _table(spec, "magnet").get("fidelity") != "axis"
        ),
        ({"magnet.fidelity": "dipole"}, {"magnet.fidelity": "exact"}),
        lambda spec: 0 if _table(spec, "magnet").get("fidelity") == "dipole" else 1,
        lambda spec: _table(spec, "magnet").get("fidelity", "exact"),
        closed_top=True,
    ),
    # The moments level takes the spec's pole.permeability, else Ni-Fe's (a reduced pole's
    # spec names none), and drops the reduced level's demagnetizing factor.
    Ladder(
        "pole",
        lambda spec: _table(spec, "magnet").get("shape") == "plate",
        (
            {"pole.fidelity": "reduced", "pole.cells": None},
            *(
                {"pole.fidelity": "moments", "pole.cells": n, "pole.demagnetizing_factor": None}
                for n in POLE_CELL_LADDER
            ),
        ),
        _pole_rank,
        lambda spec: "reduced" if _pole_rank(spec) == 0 else f"moments {_pole_rank(spec)} cells",
    ),
    Ladder(
        "soft",
        lambda spec: isinstance(spec.get("soft"), list) and bool(spec["soft"]),
        tuple({"soft.cells": n} for n in SOFT_CELL_LADDER),
        _soft_rank,
        lambda spec: f"{_soft_rank(spec)} cells",
    ),
    # A skin's magnetised layer (uniform or patterned): its linear field's resolution (the rigid
    # cells and an eFlesh-like skin's magnets have no ladder).
    Ladder(
        "skin",
        _skin_applies,
        _skin_levels,
        _skin_rank,
        lambda spec: "linear {}x{}x{}".format(*_skin_resolution(spec)),
        mesh_error=skin_field_error,
    ),
)


def levels_for(ladder: Ladder, spec: dict) -> tuple[Mapping[str, object], ...]:
    """``ladder``'s levels for ``spec``, cheapest first."""
    return ladder.levels(spec) if callable(ladder.levels) else ladder.levels


def at_level(spec: dict, ladder: Ladder, index: int) -> dict:
    """A copy of ``spec`` with ``ladder``'s model at its level ``index``."""
    changed = copy.deepcopy(spec)
    for dotted, value in levels_for(ladder, spec)[index].items():
        name, key = dotted.split(".")
        entry = changed.setdefault(name, {})
        for table in entry if isinstance(entry, list) else [entry]:
            if value is None:
                table.pop(key, None)
            else:
                table[key] = value
    return changed


def ladders(spec: dict) -> tuple[Ladder, ...]:
    """The ladders of the models ``spec`` runs."""
    return tuple(ladder for ladder in LADDERS if ladder.applies(spec))


def levels_of(spec: dict) -> dict[str, str]:
    """{model: its level in words} of each model of ``spec`` with a ladder ({"dome":
    "axisymmetric 2x16"})."""
    return {ladder.model: ladder.label(spec) for ladder in ladders(spec)}


def levels_text(spec: dict) -> str:
    """The levels of ``spec``'s models in one line ("dome axisymmetric 2x16, soft 8 cells")."""
    return ", ".join(f"{model} {label}" for model, label in levels_of(spec).items()) or "no leveled model"


def _neighbour(spec, ladder):
    """(the spec with ``ladder``'s model one level finer, or at the top one level coarser;
    whether it is finer), or None for a closed-form top."""
    rank = ladder.rank(spec)
    ranks = [ladder.rank(at_level(spec, ladder, i)) for i in range(len(levels_for(ladder, spec)))]
    finer = [i for i, r in enumerate(ranks) if r > rank]
    if finer:
        return at_level(spec, ladder, finer[0]), True
    coarser = [i for i, r in enumerate(ranks) if r < rank]
    if ladder.closed_top or not coarser:
        return None
    return at_level(spec, ladder, coarser[-1]), False


# The safety factor of a grid convergence index from two grids: Roache, "Perspective: a
# method for uniform reporting of grid refinement studies" (1994).
GCI_SAFETY = 3.0


def grid_factor(rank: float, other: float, order: float) -> float:
    """The factor from |difference| of an output between two levels to the estimated error
    of the level at resolution ``rank`` (the other at ``other``): Roache's grid convergence
    index, :data:`GCI_SAFETY` r^p / (r^p - 1) for the coarser of the two and
    :data:`GCI_SAFETY` / (r^p - 1) for the finer, r the ratio of resolutions and p the
    ``order``; 1 where one of them is a cheaper model's level (rank 0), whose difference
    to the other model is its error."""
    if rank == 0 or other == 0:
        return 1.0
    ratio = (max(rank, other) / min(rank, other)) ** order
    return GCI_SAFETY * (ratio if rank < other else 1.0) / (ratio - 1.0)


def _error(ladder: Ladder, value: float, moved: float, rank: float, other: float) -> float:
    """The estimated error of an output ``value`` at resolution ``rank`` that moves to
    ``moved`` at the neighbouring level (resolution ``other``): the ladder's own
    ``mesh_error`` between two discretisations, else the move times :func:`grid_factor`.
    An output that moves by no more than rounding does not depend on the model: 0."""
    move = abs(moved - value)
    if ladder.mesh_error is None or rank == 0 or other == 0 or move <= ROUNDING_SPREAD * abs(value):
        return grid_factor(rank, other, ladder.order) * move
    return float(ladder.mesh_error(value, moved, other > rank))


_evaluate = _export.filter_jit(outputs, "outputs")


def outputs_at(spec: dict, values: Mapping[str, float] | None = None) -> dict[str, float]:
    """{output: value (SI)} of ``spec``'s scene over its load sweep, with the scene
    parameters ``values`` ({name: SI value}) set (:func:`magdesign.scene.outputs`)."""
    scene = scene_from_spec(spec)
    if values:
        scene = with_parameters(scene, dict(values))  # float64 arrays, made there
    return {name: float(value) for name, value in _evaluate(scene, loads_from_spec(spec)).items()}


class Estimate(NamedTuple):
    """The estimated error of one output: ``absolute`` (SI, in the output's unit),
    ``relative`` (of the output's value; None where it is 0), ``model`` (the model whose
    neighbouring level moved it most: "dome", "field", "pole", "soft", "skin")."""

    absolute: float
    relative: float | None
    model: str

    def to_json(self) -> dict:
        return {"absolute": self.absolute, "relative": self.relative, "model": self.model}


class Estimates(NamedTuple):
    """The error estimates at one point of a spec: ``outputs`` {output: :class:`Estimate`}
    (the largest over the models), ``by_model`` {model: {output: its estimate from that
    model (SI)}},
    ``against`` {model: the level it was compared with, in words}, ``failed`` {model: why
    its neighbouring level gave no estimate}."""

    outputs: dict
    by_model: dict
    against: dict
    failed: dict

    def to_json(self) -> dict:
        return {name: estimate.to_json() for name, estimate in self.outputs.items()}

    def lines(self, values: Mapping[str, float], units: Mapping[str, str | None]) -> list[str]:
        """One line per estimated output: its value in ``units`` and the estimate beside it
        ("compliance  0.32 mm/N +- 0.21 % (dome)"), one naming the outputs that no
        level compared moves, then a line per failed model."""
        width = max((len(name) for name in self.outputs), default=0) + 2
        lines, unmoved = [], [name for name, estimate in self.outputs.items() if estimate.absolute == 0.0]
        for name, estimate in self.outputs.items():
            if name in unmoved:
                continue
            unit = units.get(name)
            size = (
                f"{100 * estimate.relative:.2g} %"
                if estimate.relative is not None
                else format_quantity(estimate.absolute, unit, 2)
            )
            lines.append(f"  {name:<{width}}{format_quantity(values[name], unit)} +- {size} ({estimate.model})")
        if unmoved:
            lines.append(f"  the same at every level compared: {', '.join(unmoved)}")
        lines += [f"  no estimate from the {model}: {why}" for model, why in self.failed.items()]
        return lines


def estimate(spec: dict, values: Mapping[str, float] | None = None, base: Mapping[str, float] | None = None):
    """The error estimate of every output of ``spec``'s scene at the parameters ``values``
    ({name: SI value}; None: the spec's own), one model at a time at its neighbouring level.

    Args:
        spec: a scene or design spec, at the levels the outputs were found at.
        values: scene parameters to set (a design's answer).
        base: the outputs at those levels (SI), where known; else evaluated here.

    Returns:
        :class:`Estimates`: per output the largest estimate over the models (SI), each
        the |difference| to its neighbouring level times :func:`grid_factor`, relative
        to the output's value, and that model; a model whose
        neighbouring level cannot be built, does not converge or gives a non-finite value
        for an output is listed in ``failed`` instead.
    """
    base = dict(base) if base is not None else outputs_at(spec, values)
    names = [name for name in base if name != MECHANICS_CONVERGED and math.isfinite(base[name])]
    by_model, against, failed = {}, {}, {}
    for ladder in ladders(spec):
        neighbour = _neighbour(spec, ladder)
        if neighbour is None:
            continue
        other, finer = neighbour
        against[ladder.model] = f"{ladder.label(other)}{'' if finer else ' (the level below the top)'}"
        try:
            moved = outputs_at(other, values)
        except SpecError as error:
            failed[ladder.model] = f"{ladder.label(other)} cannot run here ({error})"
            continue
        if moved.get(MECHANICS_CONVERGED, 1.0) < 1.0:
            failed[ladder.model] = f"the mechanics at {ladder.label(other)} did not converge"
            continue
        broken = [name for name in names if not math.isfinite(moved.get(name, math.nan))]
        if broken:
            failed[ladder.model] = f"{broken[0]} is not finite at {ladder.label(other)}"
            continue
        by_model[ladder.model] = {
            name: _error(ladder, base[name], moved[name], ladder.rank(spec), ladder.rank(other)) for name in names
        }
    estimates = {}
    for name in names:
        moves = {model: moved[name] for model, moved in by_model.items()}
        if moves:
            model = max(moves, key=moves.get)
            relative = moves[model] / abs(base[name]) if base[name] != 0.0 else None
            estimates[name] = Estimate(moves[model], relative, model)
    return Estimates(estimates, by_model, against, failed)


def estimates_json(spec, estimates) -> dict:
    """The JSON keys of the error estimates at ``spec``'s levels: "levels" {model: level},
    "estimates" {output: {"absolute", "relative", "model"}}, "estimate_failures" {model: why}."""
    return {
        "levels": levels_of(spec),
        "estimates": {} if estimates is None else estimates.to_json(),
        "estimate_failures": {} if estimates is None else dict(estimates.failed),
    }


def estimates_text(spec, estimates, values, units) -> str:
    """The lines of the error estimates at ``spec``'s levels, for a report."""
    head = f"levels: {levels_text(spec)}"
    if not estimates.against:
        return head + " (no model with a finer level: no error estimates)"
    against = ", ".join(f"{model} {level}" for model, level in estimates.against.items())
    lines = estimates.lines(values, units)
    return "\n".join([f"{head}; each output's estimated error, from one model at a time at {against}:", *lines])


def _allowed(problem, result, accuracy):
    """{output: the largest error (SI) ``accuracy`` allows} of the problem's targets (of
    the target's value, or its scale for a target of 0) and limits (of the nearest bound, or the limit's scale where that
    bound is 0). A limit with more room to its bound than its estimate is met whatever the
    error: it is left out by :func:`_loose`, which is given the estimates."""
    allowed = {t.output: accuracy * (abs(float(t.value)) or float(t.scale)) for t in problem.targets}
    for limit in problem.limits:
        achieved = result.outputs[limit.output]
        bounds = [float(b) for b in (limit.upper, limit.lower) if b is not None]
        nearest = min(bounds, key=lambda b: abs(achieved - b))
        size = abs(nearest) if nearest != 0.0 else float(limit.scale)
        allowed[limit.output] = (accuracy * size, min(abs(achieved - b) for b in bounds))
    return allowed


def _loose(problem, result, estimates, accuracy):
    """{model: why it must go up} of the models whose estimate of some target or limit is
    larger than ``accuracy`` allows (a limit whose room to its bound exceeds the estimate
    excepted), and of the models whose neighbouring level failed."""
    loose = {model: f"no estimate ({why})" for model, why in estimates.failed.items()}
    for output, allowed in _allowed(problem, result, accuracy).items():
        size, room = allowed if isinstance(allowed, tuple) else (allowed, 0.0)
        for ladder in LADDERS:
            move = estimates.by_model.get(ladder.model, {}).get(output, 0.0)
            if move > size and move >= room and ladder.model not in loose:
                unit = result.units.get(output)
                loose[ladder.model] = (
                    f"its estimate of {output}, {format_quantity(move, unit, 3)}, is above the "
                    f"{format_quantity(size, unit, 3)} that the accuracy allows"
                )
    return loose


class AccurateDesign(NamedTuple):
    """A design solved to an accuracy (:func:`solve_to_accuracy`).

    Attributes:
        result: the last answer (:class:`~magdesign.design.report.DesignResult`).
        problem: its problem, at ``spec``'s levels.
        spec: the spec at the levels of the last answer.
        levels: {model: level in words} of the last answer.
        estimates: :class:`Estimates` of the last answer's outputs.
        accuracy: the relative accuracy asked.
        reached: whether every target's and limit's estimate is within it.
        why: where not reached, why ("" where reached).
        answers: (levels in words, result) of each solve, cheapest first.
    """

    result: DesignResult
    problem: object
    spec: dict
    levels: dict
    estimates: Estimates
    accuracy: float
    reached: bool
    why: str
    answers: list

    @property
    def verdict(self) -> str:
        """One line: "accuracy 0.01: reached at dome axisymmetric 2x16", or "accuracy 1e-09:
        NOT reached: <why>"."""
        if self.reached:
            return f"accuracy {self.accuracy:.3g}: reached at {self.answers[-1][0]}"
        return f"accuracy {self.accuracy:.3g}: NOT reached: {self.why}"


def _cheapest(spec, ladder):
    """The cheapest level of ``ladder`` at which ``spec``'s scene builds (a reduced pole
    needs its demagnetizing factor, an axisymmetric dome a finite-strain law)."""
    for index in range(len(levels_for(ladder, spec))):
        try:
            scene_from_spec(at_level(spec, ladder, index))
        except SpecError:
            continue
        return index
    raise SpecError(f"{ladder.model}: the spec runs at none of its model's levels ({ladder.label(spec)})")


def solve_to_accuracy(spec: dict, *, accuracy: float) -> AccurateDesign:
    """Solve a design spec at the cheapest levels that meet a relative ``accuracy``.

    Every model with a ladder (:data:`LADDERS`) starts at its cheapest level. After each
    solve, the outputs are estimated at the answer (:func:`estimate`); each model whose
    estimate of a target exceeds ``accuracy`` times the target's value, or of a limit
    ``accuracy`` times its bound (the limit's scale for a bound of 0; a limit with more room
    to its bound than its estimate excepted), goes up one level, and the design is solved
    again from the previous answer. It stops when every estimate is within the accuracy, or
    when a model that must go up is at its ladder's top or its next level fails at the
    answer (``reached`` False, ``why`` says which and why).

    Args:
        spec: a parsed design spec.
        accuracy: the relative accuracy wanted (0.01: 1 %), > 0.

    Returns:
        :class:`AccurateDesign`: the last answer, its levels, estimates and whether the
        accuracy was reached.
    """
    if not (isinstance(accuracy, (int, float)) and math.isfinite(accuracy) and accuracy > 0.0):
        raise ValueError(f"accuracy: expected a relative accuracy > 0 (0.01 for 1 %), got {accuracy!r}")
    steps = ladders(spec)
    index = {ladder.model: _cheapest(spec, ladder) for ladder in steps}
    answers, start = [], None
    while True:
        current = spec
        for ladder in steps:
            current = at_level(current, ladder, index[ladder.model])
        levels = levels_text(current)
        problem, _ = problem_from_spec(current)
        stage(f"solving at {levels}")
        if start is not None:
            start = {v.name: min(max(start[v.name], float(v.lower)), float(v.upper)) for v in problem.variables}
        result = solve(problem, start=start)
        answers.append((levels, result))
        if not all(math.isfinite(value) for value in result.parameters.values()):
            estimates = Estimates({}, {}, {}, {})
            why = "the answer is not finite"
            break
        stage(f"estimating each output's error at {levels}, one model at a time one level finer")
        estimates = estimate(current, result.parameters, base=result.outputs)
        loose = _loose(problem, result, estimates, accuracy)
        # a model at its top, or whose next level fails here, cannot go up
        stuck = [
            ladder
            for ladder in steps
            if ladder.model in loose
            and (index[ladder.model] == len(levels_for(ladder, spec)) - 1 or ladder.model in estimates.failed)
        ]
        if not loose or stuck:
            why = "; ".join(
                f"the {s.model} at {s.label(current)} cannot go up usefully: {loose[s.model]}" for s in stuck
            )
            break
        for ladder in steps:
            if ladder.model in loose:
                index[ladder.model] += 1
        start = result.parameters
    return AccurateDesign(
        result=result,
        problem=problem,
        spec=current,
        levels=levels_of(current),
        estimates=estimates,
        accuracy=accuracy,
        reached=not why,
        why=why,
        answers=answers,
    )


def parse_accuracy(text: str) -> float:
    """A relative accuracy as written: "1%" or "0.01" -> 0.01; SpecError naming --accuracy
    for anything else or a value not above 0."""
    written = str(text).strip()
    try:
        value = float(written[:-1]) / 100.0 if written.endswith("%") else float(written)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0.0):
        raise SpecError(f"--accuracy: expected a relative accuracy above 0, e.g. 1% or 0.01, got {text!r}")
    return value
