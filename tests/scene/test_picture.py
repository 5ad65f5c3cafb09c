"""The picture of a sensor (magdesign show): what it draws is the field, at rest and at the
largest load."""

import magpylib as magpy
import numpy as np
import pytest
from scene_helpers import example

from magdesign.scene import loads_from_spec, scene_from_spec
from magdesign.scene.picture import GRID_POINTS, MM, SOFT_GRID_POINTS, plot_scene

PNG = b"\x89PNG\r\n\x1a\n"


def _drawn(axis):
    """The grid (x, z) (m) and |B| (T) of a panel (GRID_POINTS per side, or SOFT_GRID_POINTS)."""
    values = np.asarray(axis.collections[0].get_array())
    grid = GRID_POINTS if values.size == GRID_POINTS**2 else SOFT_GRID_POINTS
    x = np.linspace(*axis.get_xlim(), grid) / MM
    z = np.linspace(*axis.get_ylim(), grid) / MM
    magnitude = values.reshape(grid, grid)
    return x, z, magnitude


def test_dome_picture_shows_the_magnets_field_at_rest_and_pressed(tmp_path):
    """The dome-Hall sensor's dome: |B| in the plane y = 0 against magpylib, the magnet 7.4 mm above the
    sensor at rest and lowered by the dome's travel at 5 N in the second panel."""
    spec = example("dome_hall")
    scene, loads = scene_from_spec(spec), loads_from_spec(spec)
    figure = plot_scene(scene, loads, tmp_path / "dome.png")
    assert (tmp_path / "dome.png").read_bytes()[:8] == PNG
    travel = float(np.asarray(scene.displacement(loads)[0])[-1, 2])
    assert travel < -1e-3  # the Reissner dome gives 1.86 mm at 5 N
    for axis, drop in zip(figure.axes[:2], (0.0, travel)):
        x, z, magnitude = _drawn(axis)
        xx, zz = np.meshgrid(x, z)
        points = np.stack([xx, 0 * xx, zz], -1).reshape(-1, 3)
        magnet = magpy.magnet.Cylinder(
            polarization=(0, 0, 1.17), dimension=(3e-3, 1e-3), position=(0, 0, 7.9e-3 + drop)
        )
        expected = np.linalg.norm(magnet.getB(points), axis=-1).reshape(magnitude.shape)
        outside = ~((np.abs(xx) <= 1.5e-3) & (np.abs(zz - 7.9e-3 - drop) <= 0.5e-3))
        np.testing.assert_allclose(magnitude[outside], expected[outside], rtol=1e-9)


@pytest.mark.parametrize("name", ["film_hall", "pole_plate", "spin_valve_matrix"])
@pytest.mark.slow
def test_every_kind_of_scene_draws(name, tmp_path):
    spec = example(name)
    figure = plot_scene(scene_from_spec(spec), loads_from_spec(spec), tmp_path / "scene.png")
    assert (tmp_path / "scene.png").read_bytes()[:8] == PNG
    for axis in figure.axes[:2]:
        magnitude = _drawn(axis)[2]
        assert np.isfinite(magnitude).mean() > 0.2 and np.nanmin(magnitude) > 0  # the film: no field drawn above it


@pytest.mark.slow
def test_further_magnets_are_in_the_picture(tmp_path):
    spec = example("dome_hall")
    spec["magnet"]["fidelity"] = "exact"
    spec["magnet"]["extra"] = [
        {
            "radius": "1 mm",
            "height": "2 mm",
            "polarization": ["0 T", "0 T", "1 T"],
            "position": ["15 mm", "0 mm", "-6 mm"],
            "moves": False,
        }
    ]
    figure = plot_scene(scene_from_spec(spec), loads_from_spec(spec), tmp_path / "two.png")
    for axis in figure.axes[:2]:
        (_, x_max), (z_min, _) = axis.get_xlim(), axis.get_ylim()
        assert x_max > 16 and z_min < -7  # mm: the fixed magnet's outline is inside
        assert len(axis.patches) >= 3  # the two magnets and the dome


@pytest.mark.slow
def test_an_eflesh_skins_magnets_and_their_field_are_drawn(tmp_path):
    """The eFlesh-like example: its nine magnets are drawn (the three the plane y = 0 cuts
    filled), and the field at rest, inside the unmagnetised layer too, is magpylib's nine
    Cuboids'."""
    spec = example("eflesh")
    scene = scene_from_spec(spec)
    figure = plot_scene(scene, loads_from_spec(spec), tmp_path / "eflesh.png")
    axis = figure.axes[0]
    magnets = [patch for patch in axis.patches if patch.get_linestyle() in ("-", ":") and patch.get_width() == 1.0]
    assert len(magnets) == 9
    assert sum(patch.get_facecolor()[3] > 0 for patch in magnets) == 3
    x, z, magnitude = _drawn(axis)
    xx, zz = np.meshgrid(x, z)
    points = np.stack([xx, 0 * xx, zz], -1).reshape(-1, 3)
    cuboids = magpy.Collection(
        [
            magpy.magnet.Cuboid(polarization=(0, 0, 1.3), dimension=(1e-3, 1e-3, 1e-3), position=(cx, cy, 3e-3))
            for cx in (-10e-3, 0.0, 10e-3)
            for cy in (-10e-3, 0.0, 10e-3)
        ]
    )
    expected = np.linalg.norm(cuboids.getB(points), axis=-1).reshape(magnitude.shape)
    inside_layer = (zz > 0) & (zz < 6e-3)
    assert np.all(np.isfinite(magnitude[inside_layer]))
    outside_magnets = np.ones_like(xx, dtype=bool)
    for cx in (-10e-3, 0.0, 10e-3):
        outside_magnets &= ~((np.abs(xx - cx) <= 0.6e-3) & (np.abs(zz - 3e-3) <= 0.6e-3))
    np.testing.assert_allclose(magnitude[outside_magnets], expected[outside_magnets], rtol=1e-9)
