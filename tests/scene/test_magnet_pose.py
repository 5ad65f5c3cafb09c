"""Magnets with any polarization, a pose and company: a scene's field against magpylib
objects built here by hand, its magpylib export, and the spec's errors."""

import copy

import jax
import jax.numpy as jnp
import magpylib as magpy
import numpy as np
import pytest
from scene_helpers import example
from scipy.spatial.transform import Rotation

from magdesign.scene import Loads, outputs, scene_from_spec, to_magpylib
from magdesign.units import SpecError

DEG = np.pi / 180


def _body_to_scene(alpha, beta, gamma):
    """The transpose of Rx(alpha) Ry(beta) Rz(gamma) (the spin-valve paper's Eq. 4: scene -> body)."""
    ca, sa, cb, sb, cg, sg = np.cos(alpha), np.sin(alpha), np.cos(beta), np.sin(beta), np.cos(gamma), np.sin(gamma)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rz = np.array([[cg, -sg, 0], [sg, cg, 0], [0, 0, 1]])
    return (rx @ ry @ rz).T


def _posed_spec():
    """The dome-Hall sensor's dome and Hall chip with a tilted, offset, diametral-plus-axial magnet,
    a second magnet carried by the dome and a third fixed beside the sensor."""
    spec = example("dome_hall")
    spec["magnet"].update(
        fidelity="exact",
        direction=[0.6, 0.0, 0.8],
        offset=["0.3 mm", "-0.2 mm", "0.1 mm"],
        rotation=["10 deg", "-20 deg", "30 deg"],
        extra=[
            {
                "radius": "1 mm",
                "height": "2 mm",
                "polarization": ["0 T", "0.5 T", "-0.9 T"],
                "position": ["3 mm", "1 mm", "9 mm"],
            },
            {
                "radius": "0.5 mm",
                "height": "0.2 mm",
                "polarization": ["1.2 T", "0 T", "0 T"],
                "position": ["-4 mm", "0 mm", "-1 mm"],
                "rotation": ["0 deg", "90 deg", "0 deg"],
                "moves": False,
            },
        ],
    )
    return spec


def _hand_built_magnets(displacement):
    """The same three magnets as magpylib objects, poses written out from the spec."""
    main = magpy.magnet.Cylinder(
        polarization=1.17 * np.array([0.6, 0.0, 0.8]),
        dimension=(3e-3, 1e-3),
        position=np.array([0.3e-3, -0.2e-3, 7.4e-3 + 0.5e-3 + 0.1e-3]) + displacement,
        orientation=Rotation.from_matrix(_body_to_scene(10 * DEG, -20 * DEG, 30 * DEG)),
    )
    carried = magpy.magnet.Cylinder(
        polarization=(0, 0.5, -0.9), dimension=(2e-3, 2e-3), position=np.array([3e-3, 1e-3, 9e-3]) + displacement
    )
    fixed = magpy.magnet.Cylinder(
        polarization=(1.2, 0, 0),
        dimension=(1e-3, 0.2e-3),
        position=(-4e-3, 0, -1e-3),
        orientation=Rotation.from_matrix(_body_to_scene(0, 90 * DEG, 0)),
    )
    return magpy.Collection(main, carried, fixed)


@pytest.mark.slow
def test_posed_magnets_sum_as_magpylibs_collection():
    scene = scene_from_spec(_posed_spec())
    rng = np.random.default_rng(4)
    points = rng.uniform(-8e-3, 12e-3, size=(400, 3))
    field = jax.jit(lambda points, u: scene.source_field(points, u))
    for displacement in (np.zeros(3), np.array([0.2e-3, -0.1e-3, -1.5e-3])):
        expected = _hand_built_magnets(displacement).getB(points)
        ours = np.asarray(field(jnp.asarray(points), jnp.asarray(displacement)))
        error = np.linalg.norm(ours - expected, axis=-1) / np.linalg.norm(expected, axis=-1)
        assert np.max(error) < 1e-10


@pytest.mark.slow
def test_outputs_follow_the_posed_magnets():
    """field_rest is Bz at the sensor (the origin) from all three magnets."""
    out = jax.jit(outputs)(scene_from_spec(_posed_spec()), Loads(np.array([0.0, 1.0])))
    expected = _hand_built_magnets(np.zeros(3)).getB(np.zeros(3))[2]
    assert float(out["field_rest"]) == pytest.approx(expected, rel=1e-10)


def test_to_magpylib_gives_the_scenes_field_in_each_chip_frame():
    scene = scene_from_spec(_posed_spec())
    objects = to_magpylib(scene)
    assert len(objects.sources.children) == 3 and len(objects.sensors) == 1
    np.testing.assert_allclose(
        objects.sources.getB(np.zeros(3)), _hand_built_magnets(np.zeros(3)).getB(np.zeros(3)), rtol=1e-12
    )
    # a matrix of chips turned to face outwards (as in the spin-valve matrix): magpylib's readings are in the chip frames
    spec = example("spin_valve_matrix")
    spec["sensor"]["orientation"] = "radial"
    scene = scene_from_spec(spec)
    objects = to_magpylib(scene)
    positions, rotations = scene.sensor_poses()
    expected = np.einsum("sij,sj->si", np.asarray(rotations), np.asarray(scene.source_field(positions, jnp.zeros(3))))
    readings = np.stack([objects.sources.getB(sensor) for sensor in objects.sensors])
    np.testing.assert_allclose(readings, expected, rtol=1e-10, atol=1e-10 * np.max(np.abs(expected)))


def test_to_magpylib_refuses_a_film():
    with pytest.raises(ValueError, match="FilmScene"):
        to_magpylib(scene_from_spec(example("film_hall")))


@pytest.mark.parametrize(
    "edit, key",
    [
        (lambda m: m.update(direction=[0, 0, 0]), "magnet.direction"),
        (lambda m: m.update(direction=[1, 0]), "magnet.direction"),
        (lambda m: m.update(fidelity="axis"), "magnet.direction"),
        (lambda m: m["extra"][0].pop("radius"), "magnet.extra[0].radius"),
        (lambda m: m["extra"][1].update(moves="yes"), "magnet.extra[1].moves"),
        (lambda m: m["extra"][1].update(colour="red"), "magnet.extra[1].colour"),
        (lambda m: m.update(extra={"radius": "1 mm"}), "magnet.extra"),
    ],
)
def test_bad_pose_names_the_key(edit, key):
    spec = copy.deepcopy(_posed_spec())
    edit(spec["magnet"])
    with pytest.raises(SpecError) as error:
        scene_from_spec(spec)
    assert str(error.value).startswith(key) and "\n" not in str(error.value)
