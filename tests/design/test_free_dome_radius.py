"""The smallest dome meeting the compliance, its radius and thickness both free (issue 5).

Reissner's compliance C = (R_o - t/2) k / (4 E t^2), k = sqrt(3 (1 - nu^2)), rises with the
radius R_o and falls with the thickness t, so for a given C the radius
R_o(t) = 4 E C t^2 / k + t/2 grows with t: the smallest dome is the thinnest wall allowed,
its radius inside its own bounds. Expected values are that closed form, never the solver's.
"""

import math

from dome_hall_model import default_problem

from magdesign.design import Objective, Problem, Target, Variable, solve
from magdesign.mechanics import dome_compliance
from magdesign.units import mm

COMPLIANCE, FORCE = 0.32 * mm, 5.0  # m/N at N
THINNEST = 1.5 * mm
MATERIAL = default_problem().model.material


def dome_model(v):
    compliance = dome_compliance(
        outer_radius=v["outer_radius"],
        thickness=v["thickness"],
        material=MATERIAL,
        max_force=FORCE,
        fidelity="reissner",
    )
    return {"compliance": compliance, "outer_radius": v["outer_radius"]}


def radius_at(compliance, thickness=THINNEST):
    e, nu = float(MATERIAL.youngs_modulus), float(MATERIAL.poisson_ratio)
    k = math.sqrt(3 * (1 - nu**2))
    return 4 * e * compliance * thickness**2 / k + thickness / 2


PROBLEM = Problem(
    dome_model,
    [Variable("outer_radius", 3 * mm, 15 * mm, unit="mm"), Variable("thickness", THINNEST, 4 * mm, unit="mm")],
    [Target("compliance", COMPLIANCE, unit="mm/N")],
    objective=Objective("outer_radius", "min"),
)


def test_smallest_dome_is_the_thinnest_wall_with_a_free_radius():
    expected = radius_at(COMPLIANCE)
    assert 3 * mm < expected < 15 * mm  # the radius bound is not the answer
    for start in [(15 * mm, 4 * mm), (3 * mm, THINNEST), (8 * mm, 2 * mm)]:
        result = solve(PROBLEM, start={"outer_radius": start[0], "thickness": start[1]})
        assert result.status == "successful"
        assert result.active_bounds == {"thickness": "lower"}
        assert abs(result.parameters["outer_radius"] / expected - 1) <= 1e-9
        assert abs(result.parameters["thickness"] / THINNEST - 1) <= 1e-12
        assert abs(result.targets["compliance"]["achieved"] / COMPLIANCE - 1) <= 1e-9
    h = 1e-4 * COMPLIANCE
    slope = (radius_at(COMPLIANCE + h) - radius_at(COMPLIANCE - h)) / (2 * h)
    assert abs(result.derivatives["compliance"]["outer_radius"] / slope - 1) <= 1e-6
    assert abs(result.derivatives["compliance"]["thickness"]) <= 1e-12
