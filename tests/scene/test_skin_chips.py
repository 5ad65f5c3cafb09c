"""The fewest chips: a skin's design solved over candidate chip grids, the smallest grid
whose solve succeeds, with each candidate's status."""

import copy

import jax.numpy as jnp
import pytest
from scene_helpers import example

from magdesign.scene import loads_from_spec, outputs, scene_from_spec, with_parameters
from magdesign.spec import SpecError, fewest_chips
from magdesign.units import mT


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
        bounds[grid] = float(outputs(scene_from_spec(spec), loads_from_spec(spec))["localisation_worst"])
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
    # the answer checked with a simulation of the 3 x 3 grid at the solved J0
    nine = grid_skin((3, 3))
    scene = with_parameters(scene_from_spec(nine), {"magnet.polarization": jnp.asarray(40 * mT)})
    achieved = outputs(scene, loads_from_spec(nine))
    assert float(achieved["localisation_worst"]) == pytest.approx(target, rel=1e-6)
    assert float(achieved["saturation_force"]) >= 5.0
