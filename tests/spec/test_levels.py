"""The models' ladders of levels, the mechanics.mesh key and the --accuracy value."""

import math

import pytest

from magdesign.spec.design import default_spec
from magdesign.spec.levels import LADDERS, _error, at_level, grid_factor, ladders, levels_of, parse_accuracy
from magdesign.spec.scene import scene_from_spec
from magdesign.units import SpecError

DOME = next(ladder for ladder in LADDERS if ladder.model == "dome")


def test_mesh_key_reaches_the_dome():
    spec = default_spec()
    spec["mechanics"]["mesh"] = [3, 24]
    assert scene_from_spec(spec).mechanics.mesh == (3, 24)
    del spec["mechanics"]["mesh"]
    assert scene_from_spec(spec).mechanics.mesh == (2, 16)


@pytest.mark.parametrize("bad", [[3], [0, 24], "3x24", [2.5, 24], [True, 24]])
def test_bad_mesh_names_the_key(bad):
    spec = default_spec()
    spec["mechanics"]["mesh"] = bad
    with pytest.raises(SpecError, match=r"^mechanics\.mesh: "):
        scene_from_spec(spec)


def test_ladders_of_the_default_design():
    spec = default_spec()
    # the field at "axis" is the closed form on the axis: only the dome has a ladder
    assert [ladder.model for ladder in ladders(spec)] == ["dome"]
    assert levels_of(spec) == {"dome": "reissner"}
    finer = [levels_of(at_level(spec, DOME, i))["dome"] for i in range(len(DOME.levels))]
    assert finer == ["reissner", "axisymmetric 2x16", "axisymmetric 3x24", "axisymmetric 4x32", "axisymmetric 6x48"]
    ranks = [DOME.rank(at_level(spec, DOME, i)) for i in range(len(DOME.levels))]
    assert ranks == sorted(ranks) and ranks[0] == 0


def test_soft_and_field_ladders():
    spec = default_spec()
    spec["magnet"]["fidelity"] = "dipole"
    spec["soft"] = [{"cells": 8}, {"cells": 12}]
    assert levels_of(spec) == {"dome": "reissner", "field": "dipole", "soft": "8 cells"}
    soft = next(ladder for ladder in LADDERS if ladder.model == "soft")
    assert [part["cells"] for part in at_level(spec, soft, 2)["soft"]] == [16, 16]


def test_grid_factor_is_roache_gci():
    # the coarse grid of a second-order pair refined by 1.5: 3 * 2.25 / 1.25; the fine: 3 / 1.25
    assert grid_factor(2.0, 3.0, 2.0) == pytest.approx(3 * 2.25 / 1.25)
    assert grid_factor(3.0, 2.0, 2.0) == pytest.approx(3 / 1.25)
    assert grid_factor(0, 3.0, 2.0) == 1.0


def test_dome_meshes_take_the_domes_own_estimate():
    """Between two meshes the dome's estimate is its own rule (mechanics/_ladder.py: 5 times
    the move to the finer mesh, 4 times the move to the coarser, never below 0.3 % of the
    value), not a grid factor: the design reports what dome_compliance(estimate=True) would."""
    dome = next(ladder for ladder in LADDERS if ladder.model == "dome")
    coarse, fine = math.sqrt(2 * 16), math.sqrt(3 * 24)
    assert _error(dome, 1.0, 1.01, coarse, fine) == pytest.approx(0.05)
    assert _error(dome, 1.0, 1.01, fine, coarse) == pytest.approx(0.04)
    assert _error(dome, 1.0, 1.0001, coarse, fine) == pytest.approx(3e-3)  # the floor
    assert _error(dome, 2.0, 2.0, coarse, fine) == 0.0  # an output the mesh does not move
    assert _error(dome, 1.0, 1.2, 0, coarse) == pytest.approx(0.2)  # Reissner's move to the FE model
    soft = next(ladder for ladder in LADDERS if ladder.model == "soft")
    assert _error(soft, 1.0, 1.01, 8, 12) == pytest.approx(0.01 * grid_factor(8, 12, 1.0))


@pytest.mark.parametrize(("text", "value"), [("1%", 0.01), ("0.01", 0.01), (" 2.5 % ", 0.025), ("1e-9", 1e-9)])
def test_parse_accuracy(text, value):
    assert math.isclose(parse_accuracy(text), value)


@pytest.mark.parametrize("bad", ["", "%", "abc", "0", "-1%", "nan", "inf"])
def test_bad_accuracy_names_the_option(bad):
    with pytest.raises(SpecError, match="^--accuracy: "):
        parse_accuracy(bad)
