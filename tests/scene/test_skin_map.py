"""The skin's outputs' map over a stated area (sensor.map_size): its points where the key
puts them, a map wider than the chip array localising worse, and the key's bad inputs."""

import numpy as np
import pytest
from scene_helpers import example

from magdesign.scene import loads_from_spec, outputs, scene_from_spec
from magdesign.spec.checks import PlausibilityWarning
from magdesign.units import SpecError


def skin(**sensor):
    spec = example("skin")
    spec["sensor"].update(sensor)
    return spec


def test_the_map_spans_the_stated_area_about_the_skins_centre():
    # a 20 x 16 mm area on the 30 x 30 mm skin, 3 points along x and 2 along y, corners
    # included: x at -10, 0, 10 mm and y at -8, 8 mm, x the slower index
    scene = scene_from_spec(skin(map_size=["20 mm", "16 mm"], map_grid=[3, 2]))
    expected = [[-10, -8], [-10, 8], [0, -8], [0, 8], [10, -8], [10, 8]]
    np.testing.assert_allclose(np.asarray(scene.map_points()) * 1e3, expected, atol=1e-12)
    # one point along an axis: the area's middle, the skin's centre
    one = scene_from_spec(skin(map_size=["20 mm", "16 mm"], map_grid=[1, 2]))
    np.testing.assert_allclose(np.asarray(one.map_points()) * 1e3, [[0, -8], [0, 8]], atol=1e-12)
    # absent, the chips' bounding box: the example's cross reaches 10 mm each way
    box = scene_from_spec(skin(map_grid=[2, 2]))
    assert box.map_size is None
    np.testing.assert_allclose(np.asarray(box.map_points()) * 1e3, [[-10, -10], [-10, 10], [10, -10], [10, 10]])


def _small(map_size=None):
    """A 16 mm square, 1.5 mm skin over 4 chips at (+-3, +-3) mm, 1.5 mm deep, a 3 x 3 map."""
    spec = {
        "magnet": {"shape": "skin", "polarization": "20 mT", "direction": [0, 0, 1]},
        "mechanics": {
            "model": "bonded_layer",
            "thickness": "1.5 mm",
            "size": ["16 mm", "16 mm"],
            "shear_modulus": "100 kPa",
            "poisson_ratio": 0.49,
        },
        "indenter": {"radius": "1 mm"},
        "sensor": {
            "model": "hall3d",
            "preset": "MLX90393",
            "chips": [["-3 mm", "-3 mm"], ["3 mm", "-3 mm"], ["-3 mm", "3 mm"], ["3 mm", "3 mm"]],
            "depth": "1.5 mm",
            "map_grid": [3, 3],
        },
        "load": {"normal": ["0 N", "0.1 N"], "contact_x": ["0 mm", "0 mm"], "contact_y": ["0 mm", "0 mm"]},
    }
    if map_size is not None:
        spec["sensor"]["map_size"] = map_size
    return spec


@pytest.mark.slow
def test_a_map_wider_than_the_array_localises_worse():
    """The chips' box puts the map's corners over the corner chips, (+-3, +-3) mm; a 10 x 10 mm
    area puts them at (+-5, +-5) mm, outside the array (3 mm from the skin's side, beyond its
    1.5 mm thickness).
    A chip's reading changes with the contact's position most where the contact lies over or
    near it and falls off with the distance (the layer's displacement decays over a few
    thicknesses): a contact outside the array is seen by fewer chips, each more weakly, so its
    Fisher information is smaller and the Cramer-Rao bound of its position larger."""

    def worst(spec):
        return float(outputs(scene_from_spec(spec), loads_from_spec(spec))["localisation_worst"])

    inside, wider = worst(_small()), worst(_small(["10 mm", "10 mm"]))
    # measured: 0.70 mm over the chips' box and 1.38 mm over the 10 mm area
    assert wider > 1.2 * inside, (inside, wider)


@pytest.mark.parametrize(
    "map_size, expected",
    [
        (["0 mm", "10 mm"], "0 m is not physical; expected a value in (0, inf)"),
        (["10 mm", "-2 mm"], "-0.002 m is not physical"),
        (["40 mm", "10 mm"], "a 40 x 10 mm map centred on the skin reaches off the 30 x 30 mm skin"),
        (["10 mm", "31 mm"], "reaches off the 30 x 30 mm skin (mechanics.size)"),
        (["10 mm"], "expected a list of 2 quantities in m"),
        ("10 mm", "expected a list of 2 quantities in m"),
    ],
)
def test_a_bad_map_size_is_a_spec_error_naming_it(map_size, expected):
    with pytest.raises(SpecError, match=r"^sensor.map_size: ") as error:
        scene_from_spec(skin(map_size=map_size))
    assert expected in str(error.value)


def test_a_map_reaching_near_the_side_warns_naming_map_size():
    # the whole 30 mm skin: its corners lie on the side, within the 2 mm thickness
    with pytest.warns(PlausibilityWarning, match=r"^sensor.map_size: a point lies 0 mm from the skin's side"):
        scene_from_spec(skin(map_size=["30 mm", "30 mm"]))
