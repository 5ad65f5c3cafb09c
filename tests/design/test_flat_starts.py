"""Starts where the model is flat in every direction (zero gradient): the solver moves off
them and solves, instead of stopping there or calling the problem infeasible."""

import pytest

from magdesign.design import Objective, Problem, Target, Variable, solve


def bowl(values):
    return {"y": (values["x"] - 0.5) ** 2 + (values.get("z", 0.5) - 0.5) ** 2}


@pytest.mark.parametrize("names", [("x",), ("x", "z")])
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
