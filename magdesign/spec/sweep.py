"""The sweep grammar: the inputs a sweep of a design spec varies, and their values.

    magdesign sweep SPEC.toml --over mechanics.outer_radius=6mm:10mm:5 --over geometry.gap=3mm:9mm:4
    magdesign sweep SPEC.toml --points points.csv

``--over KEY=LO:HI:N`` sweeps one input over N evenly spaced values from LO to HI (every
``--over`` a dimension of a grid); ``--points`` reads a CSV file whose header row names the
keys and whose every further row is one point. A key is a scene parameter (its dotted spec
key), a target's output or a limit's output and side ("field_max.upper"): the inputs of
:func:`magdesign.design.sweep.sweepable`. Each value is read as a spec value (a quantity
with its unit, or a plain SI number) and checked as the spec's own would be
(:func:`check_swept`). Every error is a one-line :class:`~magdesign.units.SpecError`
naming the argument.
"""

import csv
import itertools
import warnings
from collections.abc import Mapping, Sequence

import numpy as np

from magdesign.design.problem import Problem
from magdesign.design.sweep import sweepable
from magdesign.scene.core import AbstractScene
from magdesign.spec.checks import check_domain, spec_name
from magdesign.spec.design import parameter_units, solved_spec
from magdesign.spec.keys import KEYS
from magdesign.spec.scene import scene_from_spec
from magdesign.spec.sizes import check_fits
from magdesign.units import SpecError, convert, parse, written_unit

# The most values of one swept scene parameter (or rows of a list of points) whose scenes
# are built and checked one by one, evenly spaced with both ends; beyond, the values between
# are checked by their domain only (:func:`sweep_points` reads each value as a spec value).
SWEEP_CHECKS = 1000


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
            units[key] = parameter_units(spec, key)
    return units


def sweep_points(over: Sequence[str], points: str | None, units: Mapping[str, tuple[str, str]]):
    """({key: (k,) SI values}, {key: display unit}, grid) of a sweep given by ``over``
    (``--over`` arguments, "KEY=LO:HI:N": a grid) or ``points`` (the path of a ``--points``
    CSV file: a list), exactly one of them; ``units`` is :func:`input_units`'s."""
    if bool(over) == bool(points):
        raise SpecError("sweep: give --over KEY=LO:HI:N (one or more) or --points CSV")
    if points:
        return _csv_points(points, units)
    return _over_points(over, units)


def _unit_of(units, key, where):
    if key not in units:
        raise SpecError(f"{where}: unknown key {key!r}; expected one of {', '.join(units)}")
    return units[key]


def _csv_points(path, units):
    """The points of a ``--points`` CSV file: a header row of keys, then one row per point."""
    try:
        with open(path, newline="", encoding="utf-8") as file:
            rows = [row for row in csv.reader(file) if any(cell.strip() for cell in row)]
    except OSError as error:
        raise SpecError(f"--points {path}: cannot read ({error.strerror})") from None
    except (UnicodeDecodeError, csv.Error):
        raise SpecError(f"--points {path}: not a CSV text file (UTF-8)") from None
    if len(rows) < 2:
        raise SpecError(f"--points {path}: expected a header row of keys and at least one point")
    keys = [key.strip() for key in rows[0]]
    twice = next((key for key in keys if keys.count(key) > 1), None)
    if twice is not None:
        raise SpecError(f"--points {path}: {twice} is swept twice (two columns of the header)")
    values = {key: [] for key in keys}
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != len(keys):
            raise SpecError(f"--points {path}: line {number} has {len(row)} cells, the header {len(keys)}")
        for key, cell in zip(keys, row):
            si, _ = _unit_of(units, key, f"--points {path}")
            text = cell.strip()
            values[key].append(swept_value(text, si, key, f"--points line {number} {key}"))
    return values, {key: _unit_of(units, key, "--points")[1] for key in keys}, False


def _over_points(over, units):
    """The grid of ``--over KEY=LO:HI:N`` arguments: N evenly spaced values of each key."""
    values, shown = {}, {}
    for item in over:
        key, equals, rest = item.partition("=")
        key = key.strip()
        where = f"--over {item}"
        parts = rest.split(":")
        if not equals or len(parts) != 3:
            raise SpecError(f"{where}: expected KEY=LO:HI:N, e.g. mechanics.outer_radius=6mm:10mm:5")
        si, display = _unit_of(units, key, where)
        if key in values:
            raise SpecError(f"{where}: {key} is swept twice")
        low, high = (swept_value(t, si, key, f"--over {key}") for t in parts[:2])
        try:
            count = int(parts[2])
        except ValueError:
            raise SpecError(f"{where}: N must be a whole number, got {parts[2]!r}") from None
        if count < 1:
            raise SpecError(f"{where}: N must be at least 1, got {count}")
        if not low < high:
            raise SpecError(f"{where}: LO must be below HI")
        check_fits(where, count, what="its values")  # the whole grid's records: the sweep checks them
        values[key] = np.linspace(low, high, count)
        shown[key] = written_unit(parts[0].strip()) or display
    return values, shown, True


def swept_value(text: str, si: str, key: str, where: str) -> float:
    """One swept value of ``key`` (SI), read as a spec value: a scene parameter's is checked
    as the spec's would be (its physical domain; a warning for an implausible plain number)."""
    written = float(text) if _is_number(text) else text.strip()
    value = parse(written, si, key=where)
    if spec_name(key) in KEYS:
        check_domain(key, value, key=where, unit=si, written=written)
    return value


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def _spread(items):
    """At most :data:`SWEEP_CHECKS` of ``items``, evenly spaced, the first and last kept."""
    if len(items) <= SWEEP_CHECKS:
        return items
    return [items[i] for i in np.unique(np.linspace(0, len(items) - 1, SWEEP_CHECKS).round().astype(int))]


def check_swept(spec: dict, over: Mapping, grid: bool = True) -> None:
    """SpecError unless each swept value of a scene parameter passes the checks the same
    value passes in ``spec``: the scene is built with it in place (:func:`scene_from_spec`:
    its domain and the scene's guards, a wall thinner than the dome, the magnet carried by
    its part, sensors outside the magnet, ...).

    ``over`` {key: (k,) SI values} of a sweep (targets' and limits' keys are not scene
    parameters and pass); ``grid``: each key's values with the others at the spec's, and
    every corner of the grid (the guards are linear in each parameter), else the lists
    taken together row by row. At most :data:`SWEEP_CHECKS` values or rows are built.
    """
    keys = [key for key in over if spec_name(key) in KEYS and not key.startswith("design.")]
    if not keys:
        return
    columns = {key: np.atleast_1d(np.asarray(over[key], np.float64)).tolist() for key in keys}
    if grid:
        rows = [{key: value} for key in keys for value in _spread(sorted(set(columns[key])))]
        rows += [dict(zip(keys, corner)) for corner in itertools.product(*((min(c), max(c)) for c in columns.values()))]
    else:
        rows = _spread([dict(zip(keys, row)) for row in dict.fromkeys(zip(*columns.values()))])
    for row in rows:
        with warnings.catch_warnings():  # a plain number's warning was given where it was read
            warnings.simplefilter("ignore")
            try:
                scene_from_spec(solved_spec(spec, row))
            except SpecError as error:
                shown = {key: parameter_units(spec, key)[1] for key in row}
                swept = ", ".join(f"{key} = {convert(value, shown[key]):g} {shown[key]}" for key, value in row.items())
                raise SpecError(f"swept {swept}: {error}") from None
