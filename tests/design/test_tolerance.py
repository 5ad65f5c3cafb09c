"""Tolerance analysis and robust design (magdesign.design.tolerance, `magdesign tolerance`).

The analytic case: the default design's sensor sits on the magnet's axis, where the field is
proportional to the remanence Br; its largest field component is Bz at the closest approach.
With a Gaussian Br tolerance of relative standard deviation s, the field limit B <= L holds
with probability Phi((L / B_nominal - 1) / s); with a uniform one of relative half-width a,
with probability (1 + clip((L / B_nominal - 1) / a, -1, 1)) / 2. No other limit moves with Br,
and a target without a tolerance is not judged, so the yield is that probability.
"""

import copy
import importlib.resources
import json
import math

import numpy as np
import pytest

from magdesign.cli import main
from magdesign.design import solve
from magdesign.design.tolerance import monte_carlo, perturb, robust_solve, sigmas
from magdesign.scene import loads_from_spec, outputs, scene_from_spec, with_parameters
from magdesign.spec.design import default_spec
from magdesign.spec.tolerance import tolerance_problem_from_spec
from magdesign.units import SpecError

LIMIT = 4.8e-3  # the default design's field_max upper bound (T)
# A design a little off the field limit: the yield is neither 0 nor 1.
POINT = {"geometry.gap": 7.55e-3, "mechanics.thickness": 2.14e-3}
SAMPLES = 20_000


def spec_with(tolerances, targets=None):
    spec = default_spec()
    spec["design"]["tolerances"] = tolerances
    if targets is not None:
        spec["design"]["targets"] = targets
    return spec


def phi(x):
    return 0.5 * (1.0 + math.erf(x / math.sqrt(2.0)))


def binomial_error(p, n):
    return math.sqrt(max(p * (1.0 - p), 1.0 / n) / n)


@pytest.fixture(scope="module")
def gaussian_br():
    return tolerance_problem_from_spec(spec_with({"magnet.remanence": "3 %"}))


@pytest.fixture(scope="module")
def nominal(gaussian_br):
    return solve(gaussian_br.problem)


def test_gaussian_br_yield_matches_the_closed_form(gaussian_br):
    result = monte_carlo(gaussian_br, POINT, samples=SAMPLES, seed=1)
    field = result.outputs["field_max"]["nominal"]
    # the field on the axis is proportional to Br: the closed form's premise
    scene = gaussian_br.at(POINT)
    scaled = outputs(with_parameters(scene, {"magnet.remanence": 1.17 * 1.1}), gaussian_br.loads)["field_max"]
    assert float(scaled) == pytest.approx(1.1 * field, rel=1e-12)
    expected = phi((LIMIT / field - 1.0) / 0.03)
    assert 0.05 < expected < 0.95
    assert abs(result.yield_fraction - expected) <= 4 * binomial_error(expected, SAMPLES)
    assert result.outputs["field_max"]["failing"] == pytest.approx(1.0 - result.yield_fraction)
    assert result.outputs["compliance"]["failing"] is None  # a target without a tolerance is not judged
    assert result.unusable == {"nonfinite": 0, "not_converged": 0}
    again = monte_carlo(gaussian_br, POINT, samples=SAMPLES, seed=1)
    assert again.yield_fraction == result.yield_fraction  # reproducible for a seed


def test_uniform_br_yield_matches_the_closed_form():
    tp = tolerance_problem_from_spec(spec_with({"magnet.remanence": {"value": "8 %", "distribution": "uniform"}}))
    result = monte_carlo(tp, POINT, samples=SAMPLES, seed=2)
    field = result.outputs["field_max"]["nominal"]
    expected = 0.5 * (1.0 + min(max((LIMIT / field - 1.0) / 0.08, -1.0), 1.0))
    assert 0.05 < expected < 0.95
    assert abs(result.yield_fraction - expected) <= 4 * binomial_error(expected, SAMPLES)
    # the spread of a uniform half-width a is a / sqrt(3)
    assert result.outputs["field_max"]["std_first_order"] == pytest.approx(0.08 * field / math.sqrt(3), rel=1e-9)


def test_first_order_sensitivities_match_the_monte_carlo_in_a_linear_case(gaussian_br):
    result = monte_carlo(gaussian_br, POINT, samples=SAMPLES, seed=3)
    entry = result.outputs["field_max"]
    field = entry["nominal"]
    # linear in Br: the first-order spread is exact, 3 % of the field
    assert entry["std_first_order"] == pytest.approx(0.03 * field, rel=1e-9)
    sensitivity = result.sensitivities["field_max"]["magnet.remanence"]
    assert sensitivity["first_order"] == pytest.approx(0.03 * field, rel=1e-9)
    # the Monte Carlo's spread and regression slope, within 4 standard errors
    assert abs(entry["std"] - entry["std_first_order"]) <= 4 * entry["std_first_order"] / math.sqrt(2 * SAMPLES)
    assert abs(sensitivity["monte_carlo"] - sensitivity["first_order"]) <= 4 * entry["std"] / math.sqrt(SAMPLES)
    # an output Br does not move has no sensitivities
    assert "closest_gap" not in result.sensitivities


@pytest.mark.slow
def test_effect_tolerances_move_the_scene_effects():
    """A sample's placement, tilt and temperature are the scene's own effects: the
    perturbed scene's outputs equal those of a scene spec that lists the effects."""
    spec = spec_with({"placement": "100 um", "tilt": "2 deg", "temperature": "10 K"})
    tp = tolerance_problem_from_spec(spec)
    assert tp.scene.fidelity == "exact"  # the placement leaves the axis: the exact field
    u = np.array([0.5, -1.0, 2.0, 1.0, -0.5, 0.25, 1.5])  # placement x y z, tilt a b c, temperature
    moved = outputs(perturb(tp.at(POINT), tp.inputs, tp.sensors, u), tp.loads)
    listed = copy.deepcopy(spec)
    del listed["design"]
    listed["magnet"]["fidelity"] = "exact"
    listed["scene"] = {
        "effects": ["temperature_drift", "placement", "chip_tilt", "saturation", "quantisation"],
        "placement": ["50 um", "-100 um", "200 um"],
        "tilt": ["2 deg", "-1 deg", "0.5 deg"],
        "temperature_change": "15 K",
    }
    scene = with_parameters(scene_from_spec(listed), POINT)
    expected = outputs(scene, loads_from_spec(listed))
    for name in ("field_max", "field_rest", "sensitivity", "inplane_field_max", "compliance"):
        assert float(moved[name]) == pytest.approx(float(expected[name]), rel=1e-12, abs=1e-18)


def test_robust_design_holds_its_limits_at_k_sigma(gaussian_br, nominal):
    assert nominal.status == "successful"
    robust = robust_solve(gaussian_br, 2.0, start=nominal.parameters)
    assert robust.status == "successful" and robust.settled
    sigma = sigmas(gaussian_br, robust.parameters)
    field = robust.design.outputs["field_max"]
    assert field + 2.0 * sigma["field_max"] <= LIMIT * (1 + 1e-8)
    assert field + 2.0 * sigma["field_max"] == pytest.approx(LIMIT, rel=1e-6)  # active: the limit binds
    before = monte_carlo(gaussian_br, nominal.parameters, samples=SAMPLES, seed=4)
    after = monte_carlo(gaussian_br, robust.parameters, samples=SAMPLES, seed=4)
    assert after.yield_fraction >= before.yield_fraction
    # linear in Br, the k-sigma design's yield is Phi(k)
    assert abs(after.yield_fraction - phi(2.0)) <= 4 * binomial_error(phi(2.0), SAMPLES)


def write_spec(tmp_path, tolerances, target='"0.32 mm/N"'):
    text = importlib.resources.files("magdesign.design").joinpath("default.toml").read_text()
    text = text.replace('compliance = "0.32 mm/N"', f"compliance = {target}")
    path = tmp_path / "spec.toml"
    path.write_text(text + "\n[design.tolerances]\n" + tolerances + "\n")
    return str(path)


@pytest.mark.parametrize(
    "tolerances, target, key",
    [
        ('"magnet.nonexistent" = "3 %"', '"0.32 mm/N"', "design.tolerances.magnet.nonexistent"),
        ('"magnet.remanence" = "3 mm"', '"0.32 mm/N"', "design.tolerances.magnet.remanence"),
        ('placement = "3 T"', '"0.32 mm/N"', "design.tolerances.placement"),
        ('temperature = "5 %"', '"0.32 mm/N"', "design.tolerances.temperature"),
        ('distribution = "cauchy"\n"magnet.remanence" = "3 %"', '"0.32 mm/N"', "design.tolerances.distribution"),
        (
            '"magnet.remanence" = "3 %"',
            '{ value = "0.32 mm/N", tolerance = "1 T" }',
            "design.targets.compliance.tolerance",
        ),
    ],
)
def test_bad_input_is_one_line_naming_the_key_exit_2(tmp_path, capsys, tolerances, target, key):
    code = main(["tolerance", write_spec(tmp_path, tolerances, target), "--quiet"])
    error = capsys.readouterr().err.strip()
    assert code == 2
    assert len(error.splitlines()) == 1 and key in error


@pytest.mark.parametrize("option", [["--samples", "0"], ["--robust", "-1"], ["--robust", "nan"]])
def test_bad_options_exit_2(tmp_path, capsys, option):
    assert main(["tolerance", write_spec(tmp_path, '"magnet.remanence" = "3 %"'), *option]) == 2
    assert option[0] in capsys.readouterr().err


def test_missing_table_is_a_spec_error():
    with pytest.raises(SpecError, match=r"design\.tolerances"):
        tolerance_problem_from_spec(default_spec())


def test_command_json_and_picture(tmp_path, capsys, nominal):
    spec = write_spec(tmp_path, '"magnet.remanence" = "3 %"', '{ value = "0.32 mm/N", tolerance = "5 %" }')
    picture = tmp_path / "tolerance.png"
    code = main(
        ["tolerance", spec, "--samples", "2000", "--json", "--robust", "2", "--seed", "5", "--plot", str(picture)]
    )
    document = json.loads(capsys.readouterr().out)
    assert code == 0
    assert document["status"] == "successful" and 0 < document["yield"] < 1
    assert document["tolerances"]["magnet.remanence"] == {
        "size": 0.03,
        "relative": True,
        "distribution": "normal",
        "written": "3 %",
    }
    carlo = document["design"]["monte_carlo"]
    assert carlo["samples"] == 2000 and carlo["seed"] == 5 and carlo["yield"] == document["yield"]
    field = carlo["outputs"]["field_max"]
    assert set(field) == {"unit", "nominal", "mean", "std", "std_first_order", "percentiles", "bounds", "failing"}
    assert field["bounds"] == {"upper": LIMIT} and field["unit"] == "T"
    assert carlo["outputs"]["compliance"]["bounds"]["tolerance"] == pytest.approx(0.05 * 0.32e-3)
    assert carlo["outputs"]["compliance"]["failing"] == 0.0  # Br does not move the compliance
    assert set(carlo["sensitivities"]["field_max"]["magnet.remanence"]) == {"first_order", "monte_carlo"}
    robust = document["robust"]
    assert robust["k"] == 2 and robust["status"] == "successful" and robust["settled"]
    assert robust["monte_carlo"]["yield"] >= document["yield"]
    assert robust["parameters"]["geometry.gap"] > document["design"]["parameters"]["geometry.gap"]
    assert picture.stat().st_size > 10_000


def test_a_spread_is_checked_again_about_the_solved_design():
    """An absolute 1 mm spread on the wall passes about the spec's start (a 3.5 mm wall)
    but not about a design whose wall is 2.14 mm: 3 standard deviations reach below zero,
    refused before any sample is drawn."""
    spec = spec_with({"mechanics.thickness": "1 mm"})
    spec["mechanics"]["thickness"] = "3.5 mm"
    tp = tolerance_problem_from_spec(spec)
    with pytest.raises(SpecError, match=r"design.tolerances.mechanics.thickness \(about the design's"):
        monte_carlo(tp, POINT, samples=10)


def test_a_batch_out_of_memory_is_retried_at_half_its_size(gaussian_br, monkeypatch):
    """A batch above 16 samples stands for one that does not fit memory (XLA's own error):
    the run goes on in batches of 15 (30 samples: 2 x 15 after 1 x 30 failed), says so, and
    draws what a run asked for batches of 15 draws."""
    import jax

    from magdesign.design import tolerance
    from magdesign.spec.sizes import SizeWarning

    real = tolerance._chunk

    def chunk(tp, scene, key, count, names):
        if count > 16:
            raise jax.errors.JaxRuntimeError(f"RESOURCE_EXHAUSTED: Out of memory allocating {count} bytes.")
        return real(tp, scene, key, count, names)

    monkeypatch.setattr(tolerance, "_chunk", chunk)
    with pytest.warns(SizeWarning, match="a batch of 30 samples ran out of this machine's memory; batches of 15"):
        halved = monte_carlo(gaussian_br, POINT, samples=30, seed=3, chunk=64, progress=False)
    asked = monte_carlo(gaussian_br, POINT, samples=30, seed=3, chunk=15, progress=False)
    for name, values in asked.values.items():
        np.testing.assert_array_equal(halved.values[name], values)

    def failing(tp, scene, key, count, names):
        raise jax.errors.JaxRuntimeError("INTERNAL: something else")

    monkeypatch.setattr(tolerance, "_chunk", failing)  # another runtime error is not retried
    with pytest.raises(jax.errors.JaxRuntimeError, match="INTERNAL"):
        monte_carlo(gaussian_br, POINT, samples=30, seed=3, chunk=64, progress=False)
