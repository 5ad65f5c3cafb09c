"""Starts where the model is flat in every direction (zero gradient): the solver moves off
them and solves, instead of stopping there or calling the problem infeasible; and starts at
or next to a stationary point of the objective, a minimum or not."""

import pytest

from magdesign.design import Objective, Problem, Target, Variable, solve


def bowl(values):
    return {"y": (values["x"] - 0.5) ** 2 + (values.get("z", 0.5) - 0.5) ** 2}


@pytest.mark.parametrize("names", [("x",), ("x", "z")])
@pytest.mark.slow
def test_target_from_the_symmetric_centre(names):
    problem = Problem(bowl, [Variable(name, 0.0, 1.0, start=0.5) for name in names], targets=[Target("y", 0.04)])
    result = solve(problem)
    assert result.status == "successful"
    assert result.targets["y"]["achieved"] == pytest.approx(0.04, rel=1e-9)


def test_maximum_from_the_bottom_of_the_bowl():
    problem = Problem(bowl, [Variable("x", 0.0, 1.0, start=0.5)], objective=Objective("y", sense="max"))
    result = solve(problem)
    assert result.status == "successful"
    assert result.outputs["y"] == pytest.approx(0.25, rel=1e-9)  # on either bound
    assert result.active_bounds


@pytest.mark.parametrize(
    "objective, start, expected",
    [
        # next to x^3's degenerate point: its curvature, scaled at the start, looks like a
        # minimum's, and only the probe of a stationary start finds the way down
        (lambda v: v["x"] ** 3, 1e-6, -1.0),
        # a start at (or within rounding of) the minimum, as a sweep's prediction of its next
        # optimum may be: its gradient is rounding, and scaling the objective by it alone
        # left the polish nothing but rounding ("max_steps_reached")
        (lambda v: (v["x"] - 0.3) ** 2, 0.3, 0.3),
        (lambda v: (v["x"] - 0.3) ** 2, 0.3 + 1e-12, 0.3),
    ],
)
@pytest.mark.slow
def test_a_start_at_or_next_to_a_stationary_point(objective, start, expected):
    problem = Problem(lambda v: {"f": objective(v)}, [Variable("x", -1.0, 1.0)], objective=Objective("f", "min"))
    result = solve(problem, start={"x": start})
    assert result.status == "successful"
    assert result.parameters["x"] == pytest.approx(expected, abs=1e-12)
