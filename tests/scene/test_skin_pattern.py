"""A skin magnetised as the sinusoidal film's pattern, from its spec: the example builds the
pattern it states, its field at rest is the slabs' (the field's own checks are in
tests/fields/test_layer_pattern.py), and every bad period or direction is a SpecError naming
its key."""

import numpy as np
import pytest
from scene_helpers import example

from magdesign.fields.film import film
from magdesign.scene import scene_from_spec
from magdesign.spec.checks import PlausibilityWarning
from magdesign.units import SpecError, mm


@pytest.mark.slow
def test_the_example_is_the_films_pattern():
    scene = scene_from_spec(example("skin_pattern"))
    assert float(scene.period) == pytest.approx(4 * mm)
    assert scene.direction == (0.0, 0.0, -1.0)
    assert "magnet.period" in scene.parameter_paths
    # the chips' field at rest beside the infinite film's (scene frame: (Bx, 0, -Bz) of
    # fields.film), off by the 30 mm layer's sides (7.5 periods: a side charge at each)
    points, _ = scene.sensor_poses()
    rest = np.asarray(scene.skin_field(points, np.zeros(5)))
    bx, bz = film(points[:, 0], -points[:, 2], period=4 * mm, thickness=2 * mm, polarization=0.02)
    infinite = np.stack([bx, 0 * bx, -bz], axis=-1)
    np.testing.assert_allclose(rest, infinite, atol=0.05 * np.max(np.abs(infinite)))


def magnet(**keys):
    spec = example("skin_pattern")
    spec["magnet"].update(keys)
    return spec


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        (magnet(period="0 mm"), r"^magnet.period: 0 m is not physical"),
        (magnet(period="-2 mm"), r"^magnet.period: -0.002 m is not physical"),
        (magnet(direction=[0, 1, 0]), r"^magnet.direction: .*y component"),
        (magnet(field="cells", resolution=[8, 8, 2]), r"^magnet.resolution: "),
        # 15 nodes over 30 mm: 2 mm apart, two per 4 mm period, each node may sit on a zero of J_z
        (
            magnet(resolution=[15, 30, 6]),
            r"^magnet.resolution: 15 along x .* too few .*; expected more than 15 along x",
        ),
        (magnet(field="cells", cells=[7, 16, 2]), r"^magnet.cells: 7 along x .* too few"),
    ],
)
def test_bad_period_names_the_key(spec, expected):
    with pytest.raises(SpecError, match=expected):
        scene_from_spec(spec)


def test_a_coarse_pattern_resolution_warns():
    # 40 nodes over 30 mm: 5.3 per 4 mm period, under the default's 8
    with pytest.warns(PlausibilityWarning, match=r"^magnet.resolution: 40 along x is 5.33 per 4 mm period"):
        scene_from_spec(magnet(resolution=[40, 40, 6]))


def test_a_period_with_discrete_magnets_is_refused():
    spec = example("skin_pattern")
    spec["magnet"]["magnets"] = [{"position": ["0 mm", "0 mm", "1 mm"], "size": ["1 mm", "1 mm", "1 mm"]}]
    with pytest.raises(SpecError, match=r"^magnet.period: .*unmagnetised layer"):
        scene_from_spec(spec)


def test_a_direction_in_the_xz_plane_shifts_the_phase():
    scene = scene_from_spec(magnet(direction=[1, 0, 0]))
    assert scene.direction == (1.0, 0.0, 0.0)


@pytest.mark.slow
def test_the_cells_carry_the_pattern_at_their_centres():
    # at rest the rigid cells are thin slabs across x with the pattern at their centres, whose
    # midpoint error is (k D)^2 / 24 = 1.6e-3 of the field at D = 0.125 mm (T = 4 mm): the
    # linear field's slabs (pattern_field) agree to that
    cells = scene_from_spec(magnet(field="cells", cells=[240, 1, 1]))
    linear = scene_from_spec(example("skin_pattern"))
    points, _ = linear.sensor_poses()
    at_rest = np.asarray(cells.skin_field(points, np.zeros(5)))
    expected = np.asarray(linear.linear_field(points, linear.surface_load(np.zeros(5))))
    np.testing.assert_allclose(at_rest, expected, atol=3e-3 * np.max(np.abs(expected)))
