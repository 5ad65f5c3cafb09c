"""Cell sets: a magnetised layer cut into cuboid cells, and the cells moved by a displacement.

Independent references: magpylib's Cuboid (one block for the undeformed layer, whose cells
share faces without charge; a collection of moved blocks for the moved cells), rotations
written out by hand, and central differences for the derivative through the layer's
displacement field."""

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields.cells import cells_field, layer_cells, moved_cells
from magdesign.frames import rotate_by_vector
from magdesign.mechanics.skin_layer import ElasticLayer, SurfaceLoad, layer_displacement, make_quadrature
from magdesign.units import mm

SIZE, THICKNESS = (20 * mm, 16 * mm), 2 * mm
GRID = (10, 8, 3)
# chip positions on a board 1 mm below the layer, and one above it
CHIPS = np.array(
    [[0.0, 0.0, -1 * mm], [5 * mm, -3 * mm, -1 * mm], [12 * mm, 4 * mm, -1.5 * mm], [1 * mm, 2 * mm, 4 * mm]]
)


def relative(a, b):
    return np.max(np.linalg.norm(np.asarray(a) - b, axis=-1) / np.linalg.norm(b, axis=-1))


@pytest.mark.parametrize("polarization", [(0.0, 0.0, 0.05), (0.03, -0.02, 0.0), (0.01, 0.02, -0.04)])
def test_the_undeformed_layer_is_the_one_block_it_fills(polarization):
    centres, dimension = layer_cells(size=SIZE, thickness=THICKNESS, cells=GRID)
    field = cells_field(
        CHIPS, centres=centres, dimension=dimension, polarization=jnp.tile(jnp.asarray(polarization), (len(centres), 1))
    )
    block = magpylib.magnet.Cuboid(
        polarization=polarization, dimension=(*SIZE, THICKNESS), position=(0.0, 0.0, THICKNESS / 2)
    )
    assert relative(field, block.getB(CHIPS)) < 1e-10


def test_moved_cells_give_magpylibs_field_of_the_moved_blocks():
    centres, dimension = layer_cells(size=SIZE, thickness=THICKNESS, cells=(5, 4, 2), bottom=0.5 * mm)
    rng = np.random.default_rng(7)
    moved = np.asarray(centres) + rng.uniform(-0.3, 0.3, centres.shape) * mm
    polarization = rng.normal(size=centres.shape) * 0.02
    field = cells_field(CHIPS, centres=moved, dimension=dimension, polarization=polarization)
    blocks = [
        magpylib.magnet.Cuboid(polarization=j, dimension=np.asarray(dimension), position=c)
        for c, j in zip(moved, polarization)
    ]
    reference = magpylib.getB(blocks, CHIPS, sumup=True)
    assert relative(field, reference) < 1e-10
    assert len(centres) == 40 and np.allclose(np.asarray(dimension), [4 * mm, 4 * mm, 1 * mm])
    assert np.isclose(float(jnp.min(centres[:, 2])), 1 * mm) and np.isclose(float(jnp.max(centres[:, 2])), 2 * mm)


def test_a_uniform_shift_moves_the_cells_and_leaves_their_polarization():
    centres, _ = layer_cells(size=SIZE, thickness=THICKNESS, cells=(3, 2, 2))
    shift = jnp.array([0.1, -0.2, 0.05]) * mm
    polarization = jnp.tile(jnp.array([0.0, 0.0, 0.05]), (len(centres), 1))
    moved, turned = moved_cells(centres, polarization, lambda p: jnp.broadcast_to(shift, p.shape))
    np.testing.assert_allclose(moved, centres + shift, rtol=0, atol=1e-18)
    np.testing.assert_allclose(turned, polarization, rtol=0, atol=1e-18)


def test_a_rotation_field_turns_the_polarization_by_its_angle():
    """u = w x x (an infinitesimal rotation, curl u / 2 = w) turns J by |w| about w: by hand,
    0.03 rad about y takes (0, 0, J) to (J sin 0.03, 0, J cos 0.03)."""
    centres, _ = layer_cells(size=SIZE, thickness=THICKNESS, cells=(3, 2, 2))
    w = jnp.array([0.0, 0.03, 0.0])
    polarization = jnp.tile(jnp.array([0.0, 0.0, 0.05]), (len(centres), 1))
    _, turned = moved_cells(centres, polarization, lambda p: jnp.cross(w, p))
    expected = 0.05 * np.array([np.sin(0.03), 0.0, np.cos(0.03)])
    np.testing.assert_allclose(turned, np.broadcast_to(expected, turned.shape), rtol=1e-13, atol=1e-16)


@pytest.mark.parametrize("angle", [0.0, 1e-7, 1e-3, 1.0, np.pi])
def test_rotate_by_vector_against_the_rotation_matrix(angle):
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    matrix = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k  # exp of the skew matrix
    v = np.array([0.3, 0.1, -0.7])
    np.testing.assert_allclose(rotate_by_vector(v, angle * axis), matrix @ v, rtol=0, atol=1e-15)
    gradient = jax.jacfwd(lambda w: rotate_by_vector(v, w))(jnp.asarray(angle * axis))
    assert np.all(np.isfinite(gradient))


@pytest.mark.slow  # compiles the layer's Hankel transforms and their derivatives: ~40 s
def test_the_field_of_the_pressed_skin_differentiates_through_the_layer():
    """d B / d Fn at a chip under a skin pressed at (2, 1) mm: jax against central differences
    (a coarse quadrature: the check is of the derivative, not of the displacement)."""
    centres, dimension = layer_cells(size=SIZE, thickness=THICKNESS, cells=(10, 8, 2))
    polarization = jnp.tile(jnp.array([0.0, 0.0, 0.05]), (len(centres), 1))
    layer = ElasticLayer(thickness=THICKNESS, shear_modulus=30e3, poisson_ratio=0.49)
    chip = jnp.array([[1 * mm, 0.0, -1 * mm]])
    quadrature = make_quadrature(s_taper=20.0, taper_width=5.0, width=1.0, order=8)

    @jax.jit
    def field(normal_force):
        load = SurfaceLoad(
            centre=jnp.array([2 * mm, 1 * mm]), radius=2 * mm, normal_force=normal_force, shear_force=jnp.zeros(2)
        )
        moved, turned = moved_cells(
            centres, polarization, lambda p: layer_displacement(p, layer=layer, load=load, quadrature=quadrature)
        )
        return cells_field(chip, centres=moved, dimension=dimension, polarization=turned)[0]

    at_rest, pressed = field(0.0), field(1.0)
    assert np.all(np.isfinite(pressed)) and float(jnp.linalg.norm(pressed - at_rest)) > 0
    derivative = jax.jit(jax.jacfwd(field))(1.0)
    step = 1e-3
    difference = (field(1.0 + step) - field(1.0 - step)) / (2 * step)
    np.testing.assert_allclose(derivative, difference, rtol=1e-5, atol=1e-12)
