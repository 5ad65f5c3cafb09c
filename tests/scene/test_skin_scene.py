"""The magnetic skin: its field at rest against magpylib's block, the symmetry of a centred
press, and its resolution outputs against a central-difference Jacobian and numpy's
inverse of the Fisher information."""

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.scene.core import outputs, simulate
from magdesign.scene.effects import Background, Placement
from magdesign.scene.loads import Loads
from magdesign.scene.skin_scene import BACKGROUND_REFERENCE, SkinScene
from magdesign.transducers import mlx90393
from magdesign.units import mm, uT

CHIPS = np.array([[0.0, 0.0], [6 * mm, 0.0], [-6 * mm, 0.0], [0.0, 6 * mm], [0.0, -6 * mm]])  # ReSkin's cross of five


def skin(**changes):
    values = dict(
        thickness=jnp.asarray(2 * mm),
        size=jnp.array([20 * mm, 20 * mm]),
        polarization=jnp.asarray(0.02),
        shear_modulus=jnp.asarray(20e3),
        poisson_ratio=jnp.asarray(0.49),
        sphere_radius=jnp.asarray(5 * mm),
        chips=jnp.asarray(CHIPS),
        depth=jnp.asarray(1 * mm),
        noise=jnp.full(3, 1 * uT),
        hall=mlx90393(),
        effects=(),
        field="cells",
        cells=(8, 8, 1),
        map_grid=(2, 2),
    )
    return SkinScene(**(values | changes))


@pytest.fixture(scope="module")
def pressed():
    """A sweep from rest to 0.1 N at the centre (the middle chip's axis)."""
    return simulate(skin(), Loads(jnp.array([0.0, 0.05, 0.1])))


def test_at_rest_the_chips_read_the_layers_block(pressed):
    block = magpylib.magnet.Cuboid(polarization=(0, 0, 0.02), dimension=(20 * mm, 20 * mm, 2 * mm), position=(0, 0, mm))
    sensors = np.concatenate([CHIPS, np.full((5, 1), -1 * mm)], axis=-1)
    np.testing.assert_allclose(pressed.readings[0], block.getB(sensors), rtol=1e-9, atol=1e-15)


def test_a_centred_press_is_symmetric(pressed):
    """By symmetry the centre chip sees no in-plane field and the four outer chips the same |B|."""
    centre = np.asarray(pressed.readings[:, 0])
    assert np.all(np.abs(centre[:, :2]) < 1e-9 * np.abs(centre[:, 2:]))
    assert centre[1, 2] != centre[0, 2]
    # the four outer chips see the same |B| by the cross's symmetry
    outer = np.linalg.norm(np.asarray(pressed.readings[2, 1:]), axis=-1)
    np.testing.assert_allclose(outer, outer[0], rtol=1e-9)


@pytest.mark.slow  # compiles the Jacobian of every reading through the layer's transforms
def test_resolution_outputs_against_differences_and_numpys_fisher_inverse():
    # the cross stretched along x (arms of 8 mm along x, 4 mm along y): the shear axes' bounds differ
    scene = skin(cells=(4, 4, 1), chips=jnp.asarray(CHIPS * np.array([4 / 3, 2 / 3])))
    loads = Loads(jnp.array([0.0, 2.0]), shear=jnp.array([[0.0, 0.0], [0.3, 0.0]]))
    got = outputs(scene, loads)
    readings = jax.jit(lambda q: scene.readings_at(q).ravel())
    steps = np.array([1e-6, 1e-6, 1e-4, 1e-4, 1e-4])
    noise = np.full(15, 1 * uT)
    localisation, normal, shear_x, shear_y, background = [], [], [], [], []
    for x, y in np.asarray(scene.map_points()):
        state = np.array([x, y, 2.0, 0.3, 0.0])
        columns = []
        for i, h in enumerate(steps):
            e = np.zeros(5)
            e[i] = h
            columns.append((np.asarray(readings(state + e)) - np.asarray(readings(state - e))) / (2 * h))
        weighted = np.stack(columns, axis=-1) / noise[:, None]
        covariance = np.linalg.inv(weighted.T @ weighted)
        localisation.append(np.sqrt(covariance[0, 0] + covariance[1, 1]))
        normal.append(np.sqrt(covariance[2, 2]))
        shear_x.append(np.sqrt(covariance[3, 3]))
        shear_y.append(np.sqrt(covariance[4, 4]))
        uniform = np.tile(np.eye(3) * BACKGROUND_REFERENCE, (1, 5)) / noise
        background.append(np.max(np.abs((covariance @ weighted.T @ uniform.T)[2])))
    np.testing.assert_allclose(got["localisation_worst"], max(localisation), rtol=1e-4)
    np.testing.assert_allclose(got["localisation_median"], np.median(localisation), rtol=1e-4)
    np.testing.assert_allclose(got["force_resolution_normal"], max(normal), rtol=1e-4)
    np.testing.assert_allclose(got["force_resolution_shear_x"], max(shear_x), rtol=1e-4)
    np.testing.assert_allclose(got["force_resolution_shear_y"], max(shear_y), rtol=1e-4)
    assert abs(max(shear_x) / max(shear_y) - 1) > 0.05  # the layout tells the axes apart
    assert got["force_resolution_shear"] == max(got["force_resolution_shear_x"], got["force_resolution_shear_y"])
    np.testing.assert_allclose(got["background_force_error"], max(background), rtol=1e-4)
    assert 0.0 <= float(got["crosstalk"]) <= 1.0 and 0.0 < float(got["saturation_ratio"]) < 1.0


def test_the_map_spans_the_chips_box_and_one_point_is_its_middle():
    low, high = np.min(CHIPS, axis=0), np.max(CHIPS, axis=0)
    corners = np.asarray(skin(map_grid=(2, 3)).map_points())
    assert corners.shape == (6, 2)
    np.testing.assert_allclose(corners.min(axis=0), low)
    np.testing.assert_allclose(corners.max(axis=0), high)
    np.testing.assert_allclose(np.asarray(skin(map_grid=(1, 1)).map_points()), [(low + high) / 2])
    np.testing.assert_allclose(np.asarray(skin(map_grid=(1, 2)).map_points())[:, 0], (low[0] + high[0]) / 2)


def test_the_bounds_read_the_placed_chips():
    """The readings whose Jacobian the bounds take come from the placed chips: chips lifted
    by a placement offset read what chips set that much less deep read (placement's first
    order is not zero in a tolerance analysis)."""
    lift = 0.2 * mm
    state = jnp.array([1 * mm, 0.5 * mm, 0.05, 0.01, 0.0])
    placed = skin(cells=(4, 4, 2), effects=(Placement(jnp.array([0.0, 0.0, lift])),))
    shallower = skin(cells=(4, 4, 2), depth=jnp.asarray(1 * mm - lift))
    nominal = skin(cells=(4, 4, 2))
    np.testing.assert_allclose(placed.readings_at(state), shallower.readings_at(state), rtol=1e-12, atol=1e-15)
    assert np.max(np.abs(placed.readings_at(state) - nominal.readings_at(state))) > 1e-6


def test_the_background_error_is_stated_for_the_listed_background(monkeypatch):
    """background_force_error's uniform field has the listed background's size, else the
    Earth's 50 uT. The chips' readings are replaced by a fixed linear map of the load state
    (a known Jacobian, so no layer to compile); the error is numpy's least-squares response
    to that field along z, and scales with the field's size (the fit is linear in it)."""
    jacobian = np.random.default_rng(0).normal(size=(15, 5)) * np.array([1e-3, 1e-3, 1e-4, 1e-4, 1e-4])
    monkeypatch.setattr(SkinScene, "readings_at", lambda self, state: (jnp.asarray(jacobian) @ state).reshape(5, 3))
    noise = np.full(15, 1 * uT)
    weighted = jacobian / noise[:, None]
    response = np.linalg.inv(weighted.T @ weighted) @ weighted.T @ (np.tile(np.eye(3), (1, 5)) / noise).T
    state = jnp.array([1 * mm, 0.5 * mm, 0.05, 0.01, 0.0])
    stated = {
        "none": ((), BACKGROUND_REFERENCE),
        "earth": ((Background(field_=jnp.array([50 * uT, 0.0, 0.0])),), 50 * uT),
        "strong": ((Background(field_=jnp.array([300 * uT, 0.0, -400 * uT])),), 500 * uT),
    }
    errors = {}
    for name, (effects, size) in stated.items():
        scene = skin(effects=effects)
        assert float(scene.background_reference()) == pytest.approx(size, rel=1e-12)
        _, errors[name] = scene.resolution_at(state)
        np.testing.assert_allclose(errors[name], size * response[2], rtol=1e-9)
    # the error is linear in the field's size: 500 uT against 50 uT, ten times
    np.testing.assert_allclose(errors["strong"], 10.0 * errors["earth"], rtol=1e-9)
    np.testing.assert_allclose(errors["earth"], errors["none"], rtol=1e-12)


@pytest.mark.slow  # compiles the linear field at three resolutions
def test_the_linear_fields_estimate_is_the_size_of_its_error():
    # at coarse nodes (2 mm apart, 1 mm above the chips) the change to the finer resolution
    # against the error from a far finer one (independent of the estimate's own pair)
    coarse, far = skin(field="linear", resolution=(10, 10, 3)), skin(field="linear", resolution=(40, 40, 10))
    state = jnp.array([1 * mm, 0.5 * mm, 0.1, 0.02, -0.01])
    points, _ = coarse.sensor_poses()
    load = coarse.surface_load(state)
    error = np.asarray(coarse.linear_field(points, load) - far.linear_field(points, load))
    estimate = np.asarray(coarse.field_error(state))
    scale = np.max(np.abs(error))
    assert scale > 0
    assert np.all(np.abs(error) <= 1.5 * estimate + 0.05 * scale)
    assert np.max(estimate) < 3 * scale
