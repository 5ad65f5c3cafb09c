"""A skin unlike the example's, read from its spec: a 3 mm, non-square layer magnetised in-plane
and obliquely, over chips off-centre and at the layer's edge, against magpylib's block at rest;
and under a press the readings' linearity in J0 and their mirror image under a reversed shear."""

import copy

import jax.numpy as jnp
import magpylib
import numpy as np
import pytest
from scene_helpers import example

from magdesign.scene import scene_from_spec, with_parameters
from magdesign.units import SpecError

CHIPS_MM = [[3.0, 2.0], [15.0, 0.0], [-7.0, 9.0], [5.0, -12.0]]  # off-centre, one on the layer's edge
CROSS_MM = [[0.0, 0.0], [6.0, 0.0], [-6.0, 0.0], [0.0, 6.0], [0.0, -6.0]]


def outside_skin(direction, chips_mm, resolution=(30, 24, 4)):
    """A 30 x 24 x 3 mm layer of 20 mT along ``direction`` over ``chips_mm`` 2 mm below the
    board, no effects, pressed at the centre."""
    spec = copy.deepcopy(example("skin"))
    spec["scene"] = {}
    spec["magnet"].update(direction=list(direction), resolution=list(resolution))
    spec["mechanics"].update(thickness="3 mm", size=["30 mm", "24 mm"], poisson_ratio=0.45)
    spec["sensor"].update(chips=[[f"{x} mm", f"{y} mm"] for x, y in chips_mm], depth="2 mm", map_grid=[1, 1])
    spec["load"].update(contact_x=["0 mm", "0 mm"], contact_y=["0 mm", "0 mm"])
    return scene_from_spec(spec)


@pytest.mark.slow  # compiles the layer's field: about half a minute on two cores
@pytest.mark.parametrize("direction", [(1.0, 0.0, 0.0), (0.6, 0.0, 0.8)])
def test_an_inplane_non_square_layer_at_rest_reads_magpylibs_block(direction):
    scene = outside_skin(direction, CHIPS_MM)
    got = np.asarray(scene.readings_at(jnp.zeros(5)))
    block = magpylib.magnet.Cuboid(
        polarization=0.02 * np.asarray(direction), dimension=(0.03, 0.024, 0.003), position=(0.0, 0.0, 0.0015)
    )
    sensors = np.concatenate([np.asarray(CHIPS_MM) * 1e-3, np.full((len(CHIPS_MM), 1), -2e-3)], axis=-1)
    np.testing.assert_allclose(got, block.getB(sensors), rtol=1e-9, atol=1e-12)


@pytest.mark.slow  # compiles the layer's field under a load: about a minute on two cores
def test_a_press_is_linear_in_j0_and_a_reversed_shear_mirrors_the_readings():
    scene = outside_skin((0.0, 0.0, 1.0), CROSS_MM)
    rest = np.asarray(scene.readings_at(jnp.zeros(5)))
    forward = np.asarray(scene.readings_at(jnp.array([0.0, 0.0, 0.3, 0.05, 0.0]))) - rest
    backward = np.asarray(scene.readings_at(jnp.array([0.0, 0.0, 0.3, -0.05, 0.0]))) - rest
    assert np.max(np.abs(forward)) > 1e-6  # the press moves the centre chip's Bz by about 3 uT (20 LSB)
    # the field is linear in the polarisation, at rest and under the load alike
    stronger = with_parameters(scene, {"magnet.polarization": 0.05})
    np.testing.assert_allclose(
        np.asarray(stronger.readings_at(jnp.array([0.0, 0.0, 0.3, 0.05, 0.0]))) - 2.5 * rest,
        2.5 * forward,
        rtol=1e-9,
        atol=1e-12,
    )
    # the mirror x -> -x maps the +x shear onto the -x one: chips at +-6 mm swap, Bx changes sign
    mirrored = backward[[0, 2, 1, 3, 4]] * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(mirrored, forward, rtol=1e-9, atol=1e-12)


def test_a_chip_on_the_layers_edge_is_on_the_skin_and_one_past_it_is_not():
    """The outside array's chip at x = 15 mm sits on the 30 mm layer's edge: accepted, placed
    where written; 0.5 mm further it lies off the skin, an error naming sensor.chips."""
    scene = outside_skin((1.0, 0.0, 0.0), CHIPS_MM)
    np.testing.assert_allclose(np.asarray(scene.chip_positions()), np.asarray(CHIPS_MM) * 1e-3, atol=1e-15)
    with pytest.raises(SpecError, match=r"^sensor.chips: a x of 15.5 mm from the centre lies off the 30 x 24 mm skin"):
        outside_skin((1.0, 0.0, 0.0), [*CHIPS_MM[:1], [15.5, 0.0], *CHIPS_MM[2:]])
