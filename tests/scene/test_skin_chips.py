"""The fewest chips: a skin's design solved over candidate chip grids, the smallest grid
whose solve succeeds, with each candidate's status."""

import copy
import json
import tomllib
from types import SimpleNamespace

import equinox as eqx
import jax.numpy as jnp
import pytest
from scene_helpers import example

import magdesign.spec.chips as chips
import magdesign.spec.tolerance as tolerance
from magdesign.cli import main
from magdesign.scene import loads_from_spec, outputs, scene_from_spec, with_parameters
from magdesign.spec import SpecError, fewest_chips
from magdesign.spec.design import problem_from_spec, spec_text
from magdesign.units import mT

# the outputs of a scene over its loads, one compiled program per grid (the grid's chips
# are the program's shapes): a grid's outputs at another polarization reuse it
evaluate = eqx.filter_jit(outputs)


def grid_skin(grid=(2, 2)):
    """The example's skin (J0 = 20 mT) on a grid at 8 mm pitch, one map point (the grid's
    middle, the skin's centre), a coarse linear field."""
    spec = example("skin")
    spec["sensor"].pop("chips")
    spec["sensor"].update(grid=list(grid), pitch="8 mm", map_grid=[1, 1])
    spec["magnet"]["resolution"] = [20, 20, 4]
    return spec


def test_bad_candidates_and_chips_off_a_grid_are_errors_and_one_chip_is_refused():
    with pytest.raises(SpecError, match=r"grids\[1\]"):
        fewest_chips(grid_skin(), [[2, 2], [0, 3]])
    with pytest.raises(SpecError, match="sensor.grid"):
        fewest_chips(example("skin"), [[2, 2]])
    with pytest.raises(SpecError, match="design"):  # the spec's own error is raised, not a refusal
        fewest_chips(grid_skin(), [[2, 2]])
    # one chip reads 3 numbers, too few for a contact's 5 unknowns: the spec refuses it, unsolved
    found = fewest_chips(grid_skin(), [[1, 1]])
    assert found.status == "no_grid_succeeded" and found.best is None
    (trial,) = found.trials
    assert (trial.grid, trial.chips, trial.status, trial.result) == ((1, 1), 1, "refused", None)
    assert "at least 2 chips" in trial.reason


@pytest.mark.slow  # compiles three designs through the layer's field: minutes
def test_the_fewest_chips_that_localise_to_a_target():
    """The design varies J0 in [5, 80] mT for a target localisation at the skin's centre. The
    readings are J0 times the layer's unit field (plus a constant background), so their
    Jacobian, and the inverse of the bound's deviation, grow as J0: a grid that localises to
    L at 20 mT needs J0 = 20 mT L / target. The target is the 3 x 3 grid's bound at 40 mT
    (half its 20 mT bound); a grid with fewer chips, whose bound at 20 mT is more than 4
    times the 3 x 3 grid's, needs more than the 80 mT the design allows, so that no grid
    with fewer chips succeeds, and the 3 x 3 grid succeeds at 40 mT."""
    grids = [(1, 1), (3, 3), (1, 2), (2, 2)]
    bounds = {}
    for grid in grids[1:]:
        spec = grid_skin(grid)
        bounds[grid] = float(evaluate(scene_from_spec(spec), loads_from_spec(spec))["localisation_worst"])
    target = bounds[(3, 3)] / 2
    needed = {grid: 20 * mT * bound / target for grid, bound in bounds.items()}
    assert needed[(3, 3)] == pytest.approx(40 * mT) and needed[(1, 2)] > 80 * mT and needed[(2, 2)] > 80 * mT
    spec = grid_skin()
    spec["design"] = {
        "variables": {"magnet.polarization": {"lower": "5 mT", "upper": "80 mT"}},
        "targets": {"localisation_worst": f"{target!r} m"},
        "limits": {"saturation_force": {"lower": "5 N"}},
    }
    found = fewest_chips(copy.deepcopy(spec), [list(grid) for grid in grids])
    assert [trial.grid for trial in found.trials] == [(1, 1), (1, 2), (2, 2), (3, 3)]  # fewest chips first
    assert found.trials[0].status == "refused"
    assert all(trial.status not in ("successful", "refused") for trial in found.trials[1:3])
    assert found.status == "successful" and found.best.grid == (3, 3) and found.best.chips == 9
    assert found.best.result.parameters["magnet.polarization"] == pytest.approx(40 * mT, rel=1e-6)
    # the answer checked with a simulation of the 3 x 3 grid at the solved J0 (the program of its bound)
    nine = grid_skin((3, 3))
    scene = with_parameters(scene_from_spec(nine), {"magnet.polarization": jnp.asarray(40 * mT)})
    achieved = evaluate(scene, loads_from_spec(nine))
    assert float(achieved["localisation_worst"]) == pytest.approx(target, rel=1e-6)
    assert float(achieved["saturation_force"]) >= 5.0


def _grids_spec(tmp_path, grids, spec=None, target="20 mN"):
    """A design spec file of the grid skin (J0 in [5, 80] mT for a normal-force bound of
    ``target``) with ``design.grids``."""
    spec = grid_skin() if spec is None else spec
    spec["design"] = {
        "variables": {"magnet.polarization": {"lower": "5 mT", "upper": "80 mT"}},
        "targets": {"force_resolution_normal": target},
        "grids": grids,
    }
    path = tmp_path / "grids.toml"
    path.write_text(spec_text(spec))
    return str(path)


def test_solve_with_candidate_grids_refuses_bad_input_and_a_spec_it_cannot_solve(tmp_path, capsys):
    """design.grids from the command line: a lone chip is refused (three readings cannot fix a
    contact's five unknowns) without a solve, so with no other candidate nothing is solved: a
    bad spec (exit 2) naming each refusal; a bad candidate, a skin whose chips are listed, and sweep and tolerance (which
    take the spec's own grid) are bad specs naming the key."""
    for json_option in (["--json"], []):  # nothing solved: a bad spec, with each refusal
        assert main(["solve", _grids_spec(tmp_path, [[1, 1]]), *json_option]) == 2
        error = capsys.readouterr().err
        assert "\nmagdesign solve: design.grids: every candidate grid is refused ([1, 1]: " in error
        assert "at least 2 chips" in error
    for grids, key in (([[2, 2], [0, 3]], "design.grids[1]"), ([], "design.grids"), ("2x2", "design.grids")):
        assert main(["solve", _grids_spec(tmp_path, grids)]) == 2
        assert capsys.readouterr().err.startswith(f"magdesign solve: {key}:")
    listed = example("skin")
    listed["magnet"]["resolution"] = [20, 20, 4]
    assert main(["solve", _grids_spec(tmp_path, [[2, 2]], listed)]) == 2
    assert "design.grids: the candidate grids replace a skin's sensor.grid" in capsys.readouterr().err
    path = _grids_spec(tmp_path, [[2, 2]])
    assert main(["sweep", path, "--over", "sensor.pitch=6mm:8mm:2"]) == 2
    assert capsys.readouterr().err.startswith("magdesign sweep: design.grids: magdesign sweep takes the spec's own")
    assert main(["tolerance", path]) == 2
    assert capsys.readouterr().err.startswith("magdesign tolerance: design.grids:")
    assert main(["solve", path, "--accuracy", "1%"]) == 2
    assert "--accuracy: not with design.grids" in capsys.readouterr().err


@pytest.mark.slow  # compiles the 2 x 2 grid's outputs, its design and the finer level's estimate: minutes
def test_solve_with_candidate_grids_reports_the_fewest_chips_that_succeed(tmp_path, capsys):
    """The normal-force bound scales as 1 / J0 (the readings are J0 times the layer's unit field
    plus a constant background): a target of half the 2 x 2 grid's bound at 20 mT needs 40 mT.
    The lone chip is refused, the 2 x 2 grid succeeds there, and the 3 x 3 grid is never tried."""
    spec = grid_skin((2, 2))
    bound = float(evaluate(scene_from_spec(spec), loads_from_spec(spec))["force_resolution_normal"])
    path = _grids_spec(tmp_path, [[3, 3], [1, 1], [2, 2]], target=f"{bound / 2!r} N")
    written = tmp_path / "solved.toml"
    assert main(["solve", path, "--json", "--write", str(written)]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["status"] == "successful" and document["grid"] == [2, 2] and document["chips"] == 4
    assert [(t["grid"], t["status"]) for t in document["trials"]] == [([1, 1], "refused"), ([2, 2], "successful")]
    assert document["parameters"]["magnet.polarization"] == pytest.approx(40 * mT, rel=1e-6)
    assert document["targets"]["force_resolution_normal"]["achieved"] == pytest.approx(bound / 2, rel=1e-6)
    # the written answer is a plain design at the found grid
    solved = tomllib.loads(written.read_text())
    assert solved["sensor"]["grid"] == [2, 2] and "grids" not in solved["design"]


def test_candidate_grids_refuse_a_tolerance_that_the_tolerance_command_refuses():
    """[design.tolerances] is read as `magdesign tolerance` reads it, before any grid is
    solved: a tolerance on an input a skin does not have is the spec's own error."""
    spec = grid_skin()
    spec["design"] = {
        "variables": {"sensor.pitch": {"start": "8 mm", "lower": "4 mm", "upper": "12 mm"}},
        "targets": {"force_resolution_normal": {"value": "1 mN"}},
        "tolerances": {"mechanics.c10": "5 %"},
    }
    with pytest.raises(SpecError, match=r"design\.tolerances\.mechanics\.c10"):
        fewest_chips(spec, [[1, 1], [2, 2]])


def test_candidate_grids_build_each_grid_once(monkeypatch):
    """A grid's [design.tolerances] is read on the problem its trial built: the spec stage
    (seconds for a skin) runs once per grid, not twice."""
    spec = grid_skin()
    spec["design"] = {
        "variables": {"sensor.pitch": {"start": "8 mm", "lower": "4 mm", "upper": "12 mm"}},
        "targets": {"force_resolution_normal": {"value": "1 mN"}},
        "tolerances": {"magnet.polarization": "5 %"},
    }
    built = []

    def counted(trial_spec, **options):
        built.append(tuple(trial_spec["sensor"]["grid"]))
        return problem_from_spec(trial_spec, **options)

    monkeypatch.setattr(chips, "problem_from_spec", counted)
    monkeypatch.setattr(tolerance, "problem_from_spec", counted)
    # no solve: the count is of the spec stage alone
    monkeypatch.setattr(chips, "solve", lambda problem, **options: SimpleNamespace(status="successful"))
    found = fewest_chips(spec, [[2, 2]])
    assert found.status == "successful"
    assert built == [(2, 2)]
