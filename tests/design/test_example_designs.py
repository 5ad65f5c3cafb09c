"""Every design in examples/ from 100 random starts inside its bounds: each start reaches
the optimum solved from the spec's own start, or says it did not; never NaN or inf. Its
answer written as a spec simulates to the design reported."""

import json
from importlib.metadata import version
from pathlib import Path

import numpy as np
import pytest

from magdesign.cli import main
from magdesign.design import multistart, solve
from magdesign.spec.design import load_spec, problem_from_spec

EXAMPLES = Path(__file__).parents[2] / "examples"
DESIGNS = sorted(path.name for path in EXAMPLES.glob("*.toml") if "[design" in path.read_text())
STARTS = 100


@pytest.fixture(scope="module")
def solved():
    """example name -> (problem, its solve from the spec's start), each solved once."""
    answers = {}

    def answer(name):
        if name not in answers:
            problem, _ = problem_from_spec(load_spec(EXAMPLES / name))
            answers[name] = problem, solve(problem)
        return answers[name]

    return answer


def test_the_examples_include_designs_of_every_named_parameter():
    """Magnet gap, period T, elastomer h, dome radius and thickness are each solved for."""
    variables = set()
    for name in DESIGNS:
        problem, _ = problem_from_spec(load_spec(EXAMPLES / name))
        variables |= {(name, v.name) for v in problem.variables}
    for wanted in [
        ("dome_hall.toml", "geometry.gap"),
        ("spin_valve_matrix.toml", "geometry.gap"),
        ("film_hall.toml", "magnet.period"),
        ("film_hall.toml", "mechanics.thickness"),
        ("dome_radius.toml", "mechanics.outer_radius"),
        ("dome_radius.toml", "mechanics.thickness"),
    ]:
        assert wanted in variables


@pytest.mark.parametrize("name", DESIGNS)
@pytest.mark.slow
def test_random_starts_reach_the_optimum_or_say_not(name, solved):
    problem, reference = solved(name)
    assert reference.status == "successful"
    rng = np.random.default_rng(0)
    starts = {v.name: rng.uniform(float(v.lower), float(v.upper), STARTS) for v in problem.variables}
    batch = multistart(problem, starts)
    for v in problem.variables:
        values = batch.parameters[v.name]
        assert np.all(np.isfinite(values))
        reached = np.isclose(values, reference.parameters[v.name], rtol=1e-7, atol=1e-12)
        assert np.all(reached | ~batch.successful), (v.name, values[~reached & batch.successful])
    assert batch.successful.mean() > 0.9, batch.status


@pytest.mark.parametrize("name", DESIGNS)
@pytest.mark.slow
def test_the_written_answer_simulates_the_design_reported(name, solved, tmp_path, capsys):
    """solve -> write_spec -> simulate: the written spec's scene holds the answer (its
    variables start there, no `start` left), and its simulation gives every target and
    limit output the solve reported, to 1e-9 relative."""
    _, result = solved(name)
    path = tmp_path / "solved.toml"
    result.write_spec(path)
    header = path.read_text().splitlines()[0]
    assert (
        header.startswith(f"# solved by magdesign {version('magdesign')} on ") and f": status {result.status}" in header
    )
    written = load_spec(path)
    assert all("start" not in entry for entry in written["design"]["variables"].values())
    again, _ = problem_from_spec(written)
    assert {v.name: float(v.start) for v in again.variables} == pytest.approx(result.parameters, rel=1e-15, abs=0)
    assert main(["simulate", str(path), "--json"]) == 0
    simulated = json.loads(capsys.readouterr().out)["outputs"]
    reported = {name: entry["achieved"] for name, entry in {**result.targets, **result.limits}.items()}
    assert reported
    for output, value in reported.items():
        assert simulated[output] == pytest.approx(value, rel=1e-9, abs=0), output
