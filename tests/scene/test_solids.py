"""The solid bodies' inside test and overlap check, against geometry worked by hand."""

import numpy as np
import pytest

from magdesign.scene.pose import rotation
from magdesign.scene.solids import check_apart, solid
from magdesign.units import SpecError

MM = 1e-3


def test_inside_is_strict_and_follows_each_shape():
    ball = solid("soft[0]", "sphere", [0, 0, 0], [1, 1, 1])
    rod = solid("soft[1]", "cylinder", [0, 0, 0], [1, 1, 2])
    box = solid("soft[2]", "cuboid", [0, 0, 0], [1, 2, 3])
    points = np.array([[0.7, 0.7, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.9], [0.9, 1.9, 2.9], [1.0, 0.0, 0.0]])
    # |p| = 0.99 inside the ball; on its surface; outside
    assert ball.contains(points).tolist() == [True, False, False, False, False]
    # radius 0.99 < 1 and |z| < 2; on the axis; on the axis; hypot 2.1 > 1; on the side (touching)
    assert rod.contains(points).tolist() == [True, True, True, False, False]
    assert box.contains(points).tolist() == [True, True, True, True, False]


def test_a_turned_cylinder_lies_along_its_turned_axis():
    # a 1 mm radius, 10 mm long rod turned a quarter about x: its axis is the scene's y
    rod = solid("soft[0]", "cylinder", [0, 0, 0], [MM, MM, 5 * MM], np.asarray(rotation([np.pi / 2, 0, 0])).T)
    assert rod.contains([[0, 4 * MM, 0], [0, 0, 4 * MM], [0, -4.9 * MM, 0.5 * MM]]).tolist() == [True, False, True]


@pytest.mark.parametrize(
    "rod_centre_z, overlaps",
    [
        (0.0, True),  # through the ball's centre
        (5.0, True),  # the rod spans 0 to 10 mm: its end reaches 2 mm into the ball of radius 2 mm
        (6.5, True),  # spans 1.5 to 11.5 mm: 0.5 mm into the ball near the axis
        (7.0, False),  # spans 2 to 12 mm: its end touches the ball's top
        (9.0, False),
    ],
)
def test_a_rod_over_a_ball_overlaps_it_where_hand_geometry_says(rod_centre_z, overlaps):
    ball = solid("soft[0]", "sphere", [0, 0, 0], [2 * MM] * 3)
    rod = solid("soft[1]", "cylinder", [0, 0, rod_centre_z * MM], [0.5 * MM, 0.5 * MM, 5 * MM])
    if overlaps:
        with pytest.raises(SpecError, match=r"soft\[1\]: it overlaps soft\[0\]"):
            check_apart([], [ball, rod])
    else:
        check_apart([], [ball, rod])


def test_boxes_side_by_side_are_apart_and_a_corner_inside_is_not():
    a = solid("soft[0]", "cuboid", [0, 0, 0], [MM, MM, MM])
    check_apart([], [a, solid("soft[1]", "cuboid", [2 * MM, 0, 0], [MM, MM, MM])])  # faces touch
    # a box turned 45 degrees about z, centred 2.2 mm away: its corner reaches 2.2 - 1.41 = 0.79 mm,
    # inside the first box's face at 1 mm
    turned = solid("soft[1]", "cuboid", [2.2 * MM, 0, 0], [MM, MM, MM], np.asarray(rotation([0, 0, np.pi / 4])).T)
    with pytest.raises(SpecError, match="overlaps"):
        check_apart([], [a, turned])


def test_a_sensor_inside_a_body_names_its_key_and_the_body():
    magnet = solid("magnet", "cylinder", [0, 0, 5.5 * MM], [1.5 * MM, 1.5 * MM, 0.5 * MM])
    check_apart([("sensor.positions", [[0, 0, 0], [0, 0, 6 * MM]])], [magnet])  # on the top face: outside
    with pytest.raises(SpecError, match=r"sensor.positions: the point \[0, 0, 5.8\] mm lies inside the magnet"):
        check_apart([("sensor.positions", [[0, 0, 0], [0, 0, 5.8 * MM]])], [magnet])
