"""An eFlesh-like skin: discrete magnets in an unmagnetised layer. Their field at rest against
magpylib's cuboids, their field under a press against magpylib's cuboids moved by the layer's
displacement and turned by its rotation (scipy's rotation of a central-difference curl), and
the spec's [[magnet.magnets]] with its errors."""

import jax.numpy as jnp
import magpylib
import numpy as np
import pytest
from scene_helpers import example
from scipy.spatial.transform import Rotation

from magdesign.mechanics.skin_layer import SurfaceLoad, layer_displacement
from magdesign.scene import loads_from_spec, parameters, scene_from_spec, simulate
from magdesign.scene.skin_scene import SkinMagnets, SkinScene
from magdesign.transducers import mlx90393
from magdesign.units import SpecError, mm

CHIPS = np.array([[0.0, 0.0], [4 * mm, 0.0], [-4 * mm, 0.0], [0.0, 4 * mm], [0.0, -4 * mm]])
# four magnets: cubes and a flat block, through the thickness, in-plane and tilted
CENTRES = np.array([[0.0, 0.0, 1.5 * mm], [4 * mm, 0.0, 1.5 * mm], [0.0, 4 * mm, 1.0 * mm], [-4 * mm, -4 * mm, 2 * mm]])
SIZES = np.array([[1 * mm, 1 * mm, 1 * mm]] * 3 + [[2 * mm, 1 * mm, 0.5 * mm]])
DIRECTIONS = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 0.6, 0.8]])
J0 = 1.3


def skin():
    return SkinScene(
        thickness=jnp.asarray(3 * mm),
        size=jnp.array([20 * mm, 20 * mm]),
        polarization=jnp.asarray(J0),
        shear_modulus=jnp.asarray(50e3),
        poisson_ratio=jnp.asarray(0.45),
        sphere_radius=jnp.asarray(5 * mm),
        chips=jnp.asarray(CHIPS),
        depth=jnp.asarray(1 * mm),
        noise=jnp.full(3, 1e-6),
        hall=mlx90393(),
        effects=(),
        map_grid=(1, 1),
        magnets=SkinMagnets(centres=jnp.asarray(CENTRES), sizes=jnp.asarray(SIZES), directions=jnp.asarray(DIRECTIONS)),
    )


def magpylib_field(centres, polarizations, depth=1 * mm):
    """magpylib's field of the four cuboids at ``centres`` with ``polarizations`` at the chips."""
    cuboids = [
        magpylib.magnet.Cuboid(polarization=j, dimension=s, position=c)
        for c, s, j in zip(centres, SIZES, polarizations, strict=True)
    ]
    points = np.concatenate([CHIPS, np.full((len(CHIPS), 1), -depth)], axis=-1)
    return magpylib.Collection(*cuboids).getB(points)


def test_at_rest_the_chips_read_magpylibs_cuboids():
    got = np.asarray(skin().readings_at(jnp.zeros(5)))
    np.testing.assert_allclose(got, magpylib_field(CENTRES, J0 * DIRECTIONS), rtol=1e-9, atol=1e-12)


def test_pressed_the_magnets_move_and_turn_with_the_layer():
    """Under a press and a shear off the centre, the chips read magpylib's cuboids moved by
    the layer's displacement at their centres and their polarisation turned by half the
    curl of that displacement (a central difference, turned by scipy's rotation vector)."""
    scene = skin()
    state = np.array([1 * mm, 0.5 * mm, 0.5, 0.1, 0.0])
    load = SurfaceLoad(
        centre=state[:2], radius=scene.contact_radius(state[2]), normal_force=state[2], shear_force=state[3:5]
    )

    def u(points):
        return np.asarray(layer_displacement(jnp.asarray(points), layer=scene.layer(), load=load))

    step = 1e-7
    gradient = np.stack([(u(CENTRES + step * e) - u(CENTRES - step * e)) / (2 * step) for e in np.eye(3)], axis=-1)
    curl = np.stack(
        [
            gradient[:, 2, 1] - gradient[:, 1, 2],
            gradient[:, 0, 2] - gradient[:, 2, 0],
            gradient[:, 1, 0] - gradient[:, 0, 1],
        ],
        axis=-1,
    )
    moved = CENTRES + u(CENTRES)
    turned = Rotation.from_rotvec(curl / 2).apply(J0 * DIRECTIONS)
    expected = magpylib_field(moved, turned)
    got = np.asarray(scene.readings_at(jnp.asarray(state)))
    change = np.max(np.abs(got - magpylib_field(CENTRES, J0 * DIRECTIONS)))
    assert change > 1e-4  # the press moves the readings by far more than the tolerance below
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-8 * change)


def test_the_example_builds_its_magnets_and_simulates():
    spec = example("eflesh")
    scene, loads = scene_from_spec(spec), loads_from_spec(spec)
    assert scene.magnets.centres.shape == (9, 3)
    np.testing.assert_allclose(scene.magnets.sizes, 1e-3, rtol=1e-12)
    np.testing.assert_allclose(scene.magnets.directions, np.tile([0.0, 0.0, 1.0], (9, 1)))
    assert float(parameters(scene)["magnet.polarization"]) == pytest.approx(1.3)
    result = simulate(scene, loads)
    # unloaded: the nine cubes' field at the chips plus the 50 uT background
    cubes = magpylib.Collection(
        *[
            magpylib.magnet.Cuboid(polarization=(0, 0, 1.3), dimension=(1e-3,) * 3, position=c)
            for c in np.asarray(scene.magnets.centres)
        ]
    )
    points = np.concatenate([np.asarray(scene.chip_positions()), np.full((5, 1), -1e-3)], axis=-1)
    np.testing.assert_allclose(result.readings[0], cubes.getB(points) + [0.0, 0.0, 50e-6], rtol=1e-9, atol=1e-12)
    assert np.max(np.abs(result.readings[-1] - result.readings[0])) > 1e-5


def magnets_spec(*magnets, **magnet):
    spec = example("eflesh")
    spec["magnet"] = {"shape": "skin", "polarization": "1.3 T", **magnet, "magnets": list(magnets)}
    return spec


def test_a_magnets_own_direction_overrides_the_skins():
    spec = magnets_spec(
        {"position": ["0 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3, "direction": [1, 0, 1]},
        {"position": ["5 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3},
        direction=[0, 1, 0],
    )
    scene = scene_from_spec(spec)
    np.testing.assert_allclose(scene.magnets.directions, [[2**-0.5, 0.0, 2**-0.5], [0.0, 1.0, 0.0]], atol=1e-15)


@pytest.mark.parametrize(
    "magnets, magnet, key",
    [
        ([{"position": ["0 mm", "0 mm", "5.8 mm"], "size": ["1 mm"] * 3}], {}, "magnet.magnets[0].position"),
        ([{"position": ["19.8 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3}], {}, "magnet.magnets[0].position"),
        ([{"position": ["0 mm", "0 mm", "3 mm"], "size": ["1 mm", "0 mm", "1 mm"]}], {}, "magnet.magnets[0].size"),
        ([{"position": ["0 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3, "direction": [0, 0, 0]}], {}, "direction"),
        ([{"position": ["0 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3, "colour": "red"}], {}, "colour"),
        ([{"position": ["0 mm", "0 mm", "3 mm"], "size": ["1 mm"] * 3}], {"cells": [2, 2, 1]}, "magnet.cells"),
        ("a magnet", {}, "magnet.magnets"),
    ],
)
def test_a_bad_magnet_is_an_error_naming_its_key(magnets, magnet, key):
    spec = magnets_spec(*magnets, **magnet) if isinstance(magnets, list) else magnets_spec(**magnet)
    if not isinstance(magnets, list):
        spec["magnet"]["magnets"] = magnets
    with pytest.raises(SpecError, match=key.replace("[", r"\[").replace("]", r"\]")):
        scene_from_spec(spec)
