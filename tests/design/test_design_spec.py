"""The [design] table of a spec: parsing, errors naming the key, and the default design."""

import copy
import tomllib
from pathlib import Path

import pytest

from magdesign.design import solve
from magdesign.design.spec import default_spec, problem_from_spec
from magdesign.fields import cylinder_on_axis
from magdesign.units import SpecError

EXAMPLES = Path(__file__).parents[2] / "examples"


def test_example_dome_hall_spells_out_the_default_design():
    with open(EXAMPLES / "dome_hall.toml", "rb") as file:
        example = tomllib.load(file)
    assert example == default_spec()


@pytest.mark.parametrize("fidelity, rtol", [("reissner", 1e-9), ("axisymmetric", 1e-6)])
def test_default_design_meets_its_closed_form_answer(fidelity, rtol):
    """Seed 001 at every dome level: the closest approach is where the on-axis field is
    4.8 mT (5.8458 mm), the rest gap 1.6 mm further (0.32 mm/N x 5 N); only the wall
    thickness depends on the dome model."""
    problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
    result = solve(problem)
    assert result.status == "successful"
    closest = result.parameters["geometry.gap"] - 0.32e-3 * 5.0
    field = cylinder_on_axis(closest, radius=1.5e-3, height=1e-3, remanence=1.17)
    assert float(field) == pytest.approx(4.8e-3, rel=rtol)
    assert result.parameters["geometry.gap"] == pytest.approx(7.4458e-3, abs=1e-7)
    assert result.targets["compliance"]["achieved"] == pytest.approx(0.32e-3, rel=rtol)
    assert result.limits["field_max"]["active"]


def _broken(path, value):
    spec = copy.deepcopy(default_spec())
    table = spec
    for key in path[:-1]:
        table = table[key]
    if value is None:
        del table[path[-1]]
    else:
        table[path[-1]] = value
    return spec


@pytest.mark.parametrize(
    "path, value, key",
    [
        (("design", "targets", "compliance"), "0.32", "design.targets.compliance"),
        (("design", "targets", "compliance"), "0.32 mT", "design.targets.compliance"),
        (("design", "variables", "magnet.colour"), {"lower": "1 mm", "upper": "2 mm"}, "design.variables.magnet.colour"),
        (("design", "variables", "geometry.gap"), {"lower": "9 mm", "upper": "5 mm"}, "design.variables.geometry.gap"),
        (("design", "variables", "geometry.gap"), {"lower": "4 mm", "upper": "9 mm", "start": "12 mm"}, "design.variables.geometry.gap"),
        (("design", "variables", "geometry.gap"), {"lower": "4 mm"}, "design.variables.geometry.gap.upper"),
        (("design", "limits", "field_closest"), {"upper": "4.8 mT", "at": "1"}, "design.limits.field_closest.at"),
        (("design", "objective"), {"maximize": "happiness"}, "design.objective.maximize"),
        (("design", "targets", "wow"), "1 m", "design.targets.wow"),
        (("design",), None, "design"),
    ],
)
def test_bad_design_specs_name_the_key(path, value, key):
    with pytest.raises(SpecError) as error:
        problem_from_spec(_broken(path, value))
    message = str(error.value)
    assert message.removeprefix("[").startswith(key) and "\n" not in message  # "[design]: missing table"


def _limits(spec):
    problem, _ = problem_from_spec(spec)
    return {limit.output: limit for limit in problem.limits}


def test_geometry_guards_join_the_specs_own_limits():
    """A spec's one-sided limit on a guarded output gains the guard's other side; a
    stricter bound on the guard's side is kept as written."""
    spec = default_spec()
    limits = _limits(spec)
    assert float(limits["closest_gap"].lower) == 0.0 and limits["closest_gap"].upper is None
    assert float(limits["travel_fraction"].upper) == 1.0
    assert "wall_fraction" not in limits  # a 2-4 mm wall always fits in an 8 mm dome
    spec["design"]["limits"]["closest_gap"] = {"upper": "10 mm"}
    spec["design"]["limits"]["travel_fraction"] = {"upper": "0.5"}
    limits = _limits(spec)
    assert float(limits["closest_gap"].lower) == 0.0 and float(limits["closest_gap"].upper) == pytest.approx(0.01)
    assert float(limits["travel_fraction"].upper) == 0.5
    spec["design"]["limits"]["closest_gap"] = {"lower": "1 mm"}
    assert float(_limits(spec)["closest_gap"].lower) == pytest.approx(1e-3)


def test_a_box_that_holds_walls_as_thick_as_the_dome_gets_the_wall_guard():
    with open(EXAMPLES / "dome_radius.toml", "rb") as file:
        spec = tomllib.load(file)
    # radius from 3 mm, wall up to 4 mm: some corners of the box are no dome
    assert float(_limits(spec)["wall_fraction"].upper) == 1.0
    spec["design"]["variables"]["mechanics.outer_radius"]["lower"] = "5 mm"
    assert "wall_fraction" not in _limits(spec)
