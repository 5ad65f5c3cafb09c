"""The [design] table of a spec: parsing, errors naming the key, and the default design."""

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from magdesign.design import solve
from magdesign.fields import cylinder_axial
from magdesign.spec.design import (
    default_spec,
    load_spec,
    problem_from_spec,
    solved_spec,
    spec_text,
    stated_value,
    write_spec,
)
from magdesign.units import SpecError, parse

EXAMPLES = Path(__file__).parents[2] / "examples"


def test_example_dome_hall_spells_out_the_default_design():
    with open(EXAMPLES / "dome_hall.toml", "rb") as file:
        example = tomllib.load(file)
    assert example == default_spec()


@pytest.mark.parametrize("fidelity, rtol", [("reissner", 1e-9), ("axisymmetric", 1e-6)])
@pytest.mark.slow
def test_default_design_meets_its_closed_form_answer(fidelity, rtol):
    """The dome-Hall default at every dome level: the closest approach is where the on-axis field is
    4.8 mT (5.8458 mm), the rest gap 1.6 mm further (0.32 mm/N x 5 N); only the wall
    thickness depends on the dome model."""
    problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
    result = solve(problem)
    assert result.status == "successful"
    closest = result.parameters["geometry.gap"] - 0.32e-3 * 5.0
    field = cylinder_axial(closest + 0.5e-3, radius=1.5e-3, height=1e-3, polarization=1.17)
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
        (
            ("design", "variables", "magnet.colour"),
            {"lower": "1 mm", "upper": "2 mm"},
            "design.variables.magnet.colour",
        ),
        (("design", "variables", "geometry.gap"), {"lower": "9 mm", "upper": "5 mm"}, "design.variables.geometry.gap"),
        (
            ("design", "variables", "geometry.gap"),
            {"lower": "4 mm", "upper": "9 mm", "start": "12 mm"},
            "design.variables.geometry.gap",
        ),
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


def _starts(spec):
    problem, _ = problem_from_spec(spec)
    return {v.name: float(v.start) for v in problem.variables}


def test_a_variable_starts_at_the_value_the_scene_states():
    """One number in one place: [geometry] gap = "7.4 mm" is the gap's start; a start equal
    to it (in any unit) is allowed, one that differs is refused naming both keys, and a
    scene value outside the variable's bounds is refused."""
    spec = default_spec()
    assert _starts(spec) == {
        "geometry.gap": pytest.approx(7.4e-3, rel=1e-15),
        "mechanics.thickness": pytest.approx(2e-3, rel=1e-15),
    }
    spec["design"]["variables"]["geometry.gap"]["start"] = "0.74 cm"
    assert _starts(spec)["geometry.gap"] == pytest.approx(7.4e-3, rel=1e-15)
    spec["design"]["variables"]["geometry.gap"]["start"] = "7 mm"
    with pytest.raises(SpecError) as error:
        problem_from_spec(spec)
    message = str(error.value)
    assert message.startswith("design.variables.geometry.gap.start: '7 mm'") and "geometry.gap = '7.4 mm'" in message
    spec = default_spec()
    spec["design"]["variables"]["geometry.gap"] = {"lower": "8 mm", "upper": "20 mm"}
    with pytest.raises(
        SpecError, match=r"^design\.variables\.geometry\.gap: the scene's geometry\.gap = '7\.4 mm'.*outside"
    ):
        problem_from_spec(spec)


@pytest.mark.slow
def test_a_start_remains_for_a_parameter_the_scene_does_not_state():
    """pole.length is not written in examples/pole_plate.toml (the rod runs through the
    whole 4 mm ball by default): a variable on it starts at its start, else mid-bounds."""
    spec = load_spec(EXAMPLES / "pole_plate.toml")
    assert stated_value(spec, "pole.length") is None and stated_value(spec, "pole.ball_radius") == "2 mm"
    spec["design"] = {
        "variables": {"pole.length": {"lower": "1 mm", "upper": "4 mm", "start": "3 mm"}},
        "targets": {"attraction": "1 mN"},
    }
    assert _starts(spec) == {"pole.length": pytest.approx(3e-3, rel=1e-15)}
    del spec["design"]["variables"]["pole.length"]["start"]
    assert _starts(spec) == {"pole.length": pytest.approx(2.5e-3, rel=1e-15)}


def test_a_solved_spec_holds_each_value_where_the_spec_states_it():
    """In the unit the spec writes it (read back exactly where a decimal in that unit does),
    a plain number where the spec writes one, in the variable's unit where the spec does not
    state it (created in its table), inside a list, or bare for a sphere's one size; each
    variable's start dropped."""
    spec = load_spec(EXAMPLES / "pole_plate.toml")
    spec["soft"] = [{"shape": "sphere", "size": "1 mm", "position": ["0 mm", "0 mm", "-2 mm"], "permeability": 100}]
    spec["design"] = {
        "variables": {
            "pole.length": {"lower": "1 mm", "upper": "4 mm", "start": "3 mm"},
            "geometry.gap": {"lower": "0.1 mm", "upper": "1 mm"},
        }
    }
    values = {
        "pole.length": 3.3e-3,
        "geometry.gap": 0.5e-3,
        "soft[0].size[0]": 1.25e-3,
        "soft[0].position[2]": -2.5e-3,
        "pole.permeability": 1234.5,
    }
    solved = solved_spec(spec, values, {"pole.length": "mm"})
    assert solved["pole"]["length"] == "3.3 mm" and solved["geometry"]["gap"] == "0.5 mm"
    assert solved["soft"][0]["size"] == "1.25 mm" and solved["soft"][0]["position"] == ["0 mm", "0 mm", "-2.5 mm"]
    assert solved["pole"]["permeability"] == 1234.5
    assert "start" not in solved["design"]["variables"]["pole.length"]
    assert spec["design"]["variables"]["pole.length"]["start"] == "3 mm" and "length" not in spec["pole"]  # a copy

    def written(value):
        return parse(solved_spec(spec, {"geometry.gap": value})["geometry"]["gap"], "m", key="gap")

    assert parse("7.4458 mm", "m", key="gap") != 7.4458e-3 and written(7.4458e-3) == 7.4458e-3
    for value in np.random.default_rng(0).uniform(0.1e-3, 1e-3, 200):
        assert abs(written(value) - value) <= math.ulp(value)
    with pytest.raises(ValueError, match="geometry.gap"):
        solved_spec(spec, {"geometry.gap": float("nan")})


HOSTILE = {
    "a b": {
        "x.y": 'quote " backslash \\ newline \n delete \x7f e-acute \u00e9',
        "n": [1, -2.5, -0.0, 1e300, 5e-324, True],
        "t": {"u": {"v": [{"w": 1}], "inf": float("inf")}},
    },
    "soft": [{"size": "1 mm", "sub": {"k": 1}, "arr": [{"z": 2}]}, {"e": []}],
    "empty": {},
    "top": {"only": {"deep": {}}},
}


@pytest.mark.parametrize("name", [*sorted(path.name for path in EXAMPLES.glob("*.toml")), "hostile"])
def test_spec_text_reads_back_equal(name):
    spec = HOSTILE if name == "hostile" else load_spec(EXAMPLES / name)
    assert tomllib.loads(spec_text(spec)) == spec


def test_write_spec_leaves_no_half_file(tmp_path, monkeypatch):
    """An interrupt while the file is written leaves the old file as it was and nothing
    else; a whole write replaces it, under its header."""
    path = tmp_path / "solved.toml"
    path.write_text("old = 1\n")

    def interrupted(descriptor):
        raise KeyboardInterrupt

    monkeypatch.setattr("os.fsync", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_spec(path, default_spec(), status="successful")
    assert [entry.name for entry in tmp_path.iterdir()] == ["solved.toml"] and path.read_text() == "old = 1\n"
    monkeypatch.undo()
    write_spec(path, default_spec(), status="successful")
    text = path.read_text()
    assert text.startswith("# solved by magdesign ") and text.splitlines()[0].endswith(": status successful")
    assert tomllib.loads(text) == default_spec() and [entry.name for entry in tmp_path.iterdir()] == ["solved.toml"]


# The saturation guard: a design keeps its chip's readings inside the chip's range.
AK8963_RANGE = 4.8e-3  # T, the AK8963's saturation (its datasheet; the dome-Hall paper)


def _textbook_on_axis(distance, radius=1.5e-3, height=1e-3, remanence=1.17):
    """Bz (T) on a cylinder's axis ``distance`` (m) from its face (the textbook closed form)."""
    far = distance + height
    return remanence / 2 * (far / math.hypot(far, radius) - distance / math.hypot(distance, radius))


def _closest_at(field):
    """The distance (m) from the face where the on-axis field is ``field`` (T), by bisection."""
    low, high = 1e-4, 0.05
    for _ in range(200):
        middle = 0.5 * (low + high)
        low, high = (middle, high) if _textbook_on_axis(middle) > field else (low, middle)
    return 0.5 * (low + high)


def _unlimited_default(**changes):
    """The default design without its own field limit (only the guard keeps the chip in range)."""
    spec = copy.deepcopy(default_spec())
    del spec["design"]["limits"]
    for path, value in changes.items():
        table, key = path.split(".")
        spec[table][key] = value
    return spec


def test_the_saturation_guard_joins_every_design_on_a_chip_with_a_range():
    """Without a field limit the guard saturation_ratio <= 1 holds; the default's own
    field_max <= 4.8 mT (the AK8963's range) implies it and is not given twice; a spec's own
    saturation_ratio bound replaces the guard's, looser or stricter."""
    assert float(_limits(_unlimited_default())["saturation_ratio"].upper) == 1.0
    assert "saturation_ratio" not in _limits(default_spec())
    spec = _unlimited_default()
    spec["design"]["limits"] = {"saturation_ratio": {"upper": 1.5}}
    assert float(_limits(spec)["saturation_ratio"].upper) == 1.5
    spec["design"]["limits"] = {"saturation_ratio": {"upper": 0.5}}
    assert float(_limits(spec)["saturation_ratio"].upper) == 0.5
    # a scene that does not list the saturation effect is judged against its preset's range
    spec = _unlimited_default()
    spec["scene"]["effects"] = ["quantisation"]
    assert float(_limits(spec)["saturation_ratio"].upper) == 1.0


@pytest.mark.slow
def test_a_design_that_would_saturate_its_chip_is_not_successful():
    """The default design maximizes its sensitivity, which brings the magnet as close as the
    chip allows: with the guard alone it stops where the on-axis field at the closest
    approach is the AK8963's 4.8 mT (the paper's limit); with the gap held below that it
    reports limit_violated naming saturation_ratio."""
    result = solve(problem_from_spec(_unlimited_default())[0])
    assert result.status == "successful"
    assert result.limits["saturation_ratio"]["active"]
    assert result.parameters["geometry.gap"] == pytest.approx(_closest_at(AK8963_RANGE) + 0.32e-3 * 5.0, rel=1e-6)
    assert "clips" not in result.table()
    # the 2 mm wall's compliance (about 0.32 mm/N) brings a magnet 6 mm or less above the
    # chip within 4.4 mm of it, where the on-axis field exceeds 4.8 mT
    held = _unlimited_default(**{"geometry.gap": "5 mm"})
    held["design"]["variables"] = {"geometry.gap": {"lower": "4 mm", "upper": "6 mm"}}
    del held["design"]["targets"]
    assert _textbook_on_axis(6e-3 - 1.6e-3) > AK8963_RANGE
    result = solve(problem_from_spec(held)[0])
    assert result.status == "limit_violated" and "saturation_ratio.upper" in result.violated
    assert result.outputs["saturation_ratio"] > 1.0
    assert "the chip clips" in result.table()


@pytest.mark.slow
def test_a_spec_that_relaxes_the_saturation_guard_solves_and_reports_the_clipping():
    """saturation_ratio <= 1.5: the optimum lets the chip's largest reading (the z axis at
    the closest approach, on the axis) reach 1.5 x 4.8 mT = 7.2 mT, and the table says the
    chip clips."""
    spec = _unlimited_default()
    spec["design"]["limits"] = {"saturation_ratio": {"upper": 1.5}}
    result = solve(problem_from_spec(spec)[0])
    assert result.status == "successful"
    assert result.outputs["saturation_ratio"] == pytest.approx(1.5, rel=1e-9)
    assert result.parameters["geometry.gap"] == pytest.approx(_closest_at(1.5 * AK8963_RANGE) + 0.32e-3 * 5.0, rel=1e-6)
    assert "the chip clips: its largest reading is 1.5 times its range" in result.table()


@pytest.mark.slow
def test_the_smallest_dome_carries_its_magnet_at_its_apex():
    """examples/dome_radius.toml: the smallest dome whose apex carries the magnet (embed =
    outer radius - gap >= 0) and keeps the AK8963 in range: the radius and the gap meet at
    the closest approach where the on-axis field is 4.8 mT, plus the 1.6 mm press
    (0.32 mm/N x 5 N)."""
    result = solve(problem_from_spec(load_spec(EXAMPLES / "dome_radius.toml"))[0])
    assert result.status == "successful"
    expected = _closest_at(AK8963_RANGE) + 0.32e-3 * 5.0
    assert result.parameters["geometry.gap"] == pytest.approx(expected, rel=1e-6)
    assert result.parameters["mechanics.outer_radius"] == pytest.approx(expected, rel=1e-6)
    assert result.limits["embed"]["active"] and result.limits["saturation_ratio"]["active"]


@pytest.mark.slow
def test_a_layer_design_never_floats_its_magnet_above_the_layer():
    """The spin-valve matrix asked for a weak in-plane field (0.5 mT) that only a magnet
    above its 3.5 mm layer would give: not successful, and the gap stays on the layer."""
    spec = load_spec(EXAMPLES / "spin_valve_matrix.toml")
    spec["design"]["targets"]["inplane_field_max"] = "0.5 mT"
    result = solve(problem_from_spec(spec)[0])
    assert result.status in ("infeasible_target", "limit_violated")
    # where target and guard cannot both hold, the search ends where the violation is least:
    # the magnet at the layer's top face, give or take that compromise
    assert result.parameters["geometry.gap"] < 3.6e-3
    assert "inplane_field_max" in result.violated


@pytest.mark.slow
def test_a_dome_design_never_hangs_its_magnet_in_the_cavity():
    """A weak magnet (0.1 T) whose gap is free, the wall held at 2 mm and no compliance
    target: the sensitivity grows as the magnet nears the chip, so the optimum sits where
    the magnet's far face just reaches the dome's inner apex, gap = R_o - t - h =
    8 - 2 - 1 = 5 mm (reach = 0), never lower, and its written spec reads back."""
    spec = copy.deepcopy(default_spec())
    spec["magnet"]["remanence"] = "0.1 T"
    spec["design"]["variables"] = {"geometry.gap": {"lower": "1 mm", "upper": "20 mm"}}
    del spec["design"]["targets"]
    spec["mechanics"]["fidelity"] = "reissner"
    result = solve(problem_from_spec(spec)[0])
    assert result.status == "successful"
    assert result.parameters["geometry.gap"] == pytest.approx(5e-3, rel=1e-9)
    assert result.limits["reach"]["active"]
    problem_from_spec(result.spec())  # the solved spec is a scene that exists
