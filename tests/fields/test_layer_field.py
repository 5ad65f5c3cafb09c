"""The linear field of a deformed uniformly magnetised layer.

Independent references: magpylib's Cuboid for the undeformed layer; for the field's change,
an integral written here in numpy over a dense tensor Gauss-Legendre rule, with the
displacement from the layer's Hankel quadrature (``layer_displacement``, not the Fourier
grid the model uses), the rotation from its forward-mode Jacobian and the dipole field
written out from the textbook formula; and the rigid cells of ``fields.cells``, whose
n_z^-2 convergence Richardson-extrapolates to the same limit."""

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields.cells import carried_cells, cells_field, layer_cells
from magdesign.fields.layer_field import finer, gauss_levels, layer_field
from magdesign.mechanics.skin_layer import (
    ElasticLayer,
    SurfaceLoad,
    layer_displacement,
    layer_displacement_grid,
    make_quadrature,
    spectral_grid,
)
from magdesign.scene.skin_scene import band_limited_grid
from magdesign.units import mm

SIZE, THICKNESS, DEPTH = (10 * mm, 10 * mm), 2 * mm, 1 * mm
LAYER = ElasticLayer(thickness=THICKNESS, shear_modulus=1e5, poisson_ratio=0.49)
POLARIZATION = np.array([0.0, 0.0, 0.02])
CHIPS = np.array([[0.0, 0.0, -DEPTH], [3 * mm, 2 * mm, -DEPTH], [-4 * mm, 0.0, -DEPTH], [0.0, -2 * mm, -2 * DEPTH]])
CENTRED = SurfaceLoad(centre=jnp.zeros(2), radius=0.8 * mm, normal_force=0.1, shear_force=jnp.zeros(2))
SHEARED = SurfaceLoad(
    centre=jnp.array([1 * mm, -0.5 * mm]), radius=0.8 * mm, normal_force=0.1, shear_force=jnp.array([0.03, 0.01])
)


def linear(points, load, resolution, polarization=POLARIZATION, layer=LAYER):
    """The model as the skin scene runs it: Gauss heights, the band-limited Fourier grid."""
    heights, _ = gauss_levels(resolution[2])
    periods = spectral_grid(size=SIZE, thickness=layer.thickness, cells=(*resolution[:2], 1)).periods
    u, rotation = layer_displacement_grid(
        layer=layer,
        load=load,
        size=jnp.asarray(SIZE),
        cells=resolution,
        grid=band_limited_grid(periods, resolution[2]),
        levels=tuple(heights),
    )
    return layer_field(
        points, size=SIZE, thickness=layer.thickness, polarization=polarization, displacement=u, rotation=rotation
    )


def block(points, polarization=POLARIZATION):
    return magpylib.magnet.Cuboid(
        polarization=polarization, dimension=(*SIZE, THICKNESS), position=(0.0, 0.0, THICKNESS / 2)
    ).getB(points)


@pytest.mark.parametrize("polarization", [(0.0, 0.0, 0.05), (0.03, -0.02, 0.01)])
def test_the_undeformed_layer_is_magpylibs_cuboid(polarization):
    # no displacement: the block's field alone, whatever the nodes
    zero = jnp.zeros((4, 3, 2, 3))
    field = layer_field(
        CHIPS, size=SIZE, thickness=THICKNESS, polarization=jnp.asarray(polarization), displacement=zero, rotation=zero
    )
    expected = block(CHIPS, polarization)
    assert np.max(np.abs(np.asarray(field) - expected)) < 1e-10 * np.max(np.abs(expected))


def test_a_uniform_shift_is_the_shifted_block():
    # u uniform, no rotation: to first order the block moved by u (magpylib, by differences);
    # the midpoint rule's error, largest for the chip 1 mm inside the layer's edge, falls as
    # the node spacing squared (1.4 % at 24 nodes across)
    shift = np.array([3e-6, -2e-6, 1e-6])
    nodes = (64, 64, 6)
    u = jnp.broadcast_to(jnp.asarray(shift), (*nodes, 3))
    field = layer_field(
        CHIPS, size=SIZE, thickness=THICKNESS, polarization=POLARIZATION, displacement=u, rotation=jnp.zeros_like(u)
    )
    moved = magpylib.magnet.Cuboid(
        polarization=POLARIZATION, dimension=(*SIZE, THICKNESS), position=(0.0, 0.0, THICKNESS / 2)
    )
    plus, minus = moved.copy(), moved.copy()
    plus.move(shift), minus.move(-shift)
    change = (plus.getB(CHIPS) - minus.getB(CHIPS)) / 2
    np.testing.assert_allclose(np.asarray(field) - block(CHIPS), change, atol=3e-3 * np.max(np.abs(change)))


def dipole_field(offsets, moments):
    """The textbook point dipole: B = (3 r^ (r^ . m) - m) / (4 pi r^3) per unit J dV."""
    r = np.linalg.norm(offsets, axis=-1, keepdims=True)
    unit = offsets / r
    return (3 * unit * np.sum(unit * moments, axis=-1, keepdims=True) - moments) / (4 * np.pi * r**3)


# the reference's Hankel nodes: panels of width 2 in k a (reference_change says why)
HANKEL = make_quadrature(width=2.0)


@jax.jit
def _with_jacobian(points, load):
    """u (m) and du_i / dx_j (-) from the Hankel quadrature at points (P, 3): (P, 3), (P, 3, 3)."""

    def displacement(p):
        return layer_displacement(p, layer=LAYER, load=load, quadrature=HANKEL)

    return jax.vmap(lambda p: (displacement(p), jax.jacfwd(displacement)(p)))(points)


def reference_change(points, load, panels=10, order=6, heights=8):
    """dB by a dense tensor Gauss-Legendre rule over the layer: u from the Hankel quadrature,
    omega = curl(u) / 2 from its forward-mode Jacobian, the gradient of the dipole field by
    central differences in the field point. The Hankel nodes lie in panels of width 2 in
    k a, a quarter of the default's nodes (whose panels of 0.5 resolve J0(k r) out to r / a
    of 40; the rule's points lie within 11 load radii of the load): at the rule's points u
    agrees with the default nodes' to 1e-8 of its peak."""
    x, w = np.polynomial.legendre.leggauss(order)

    def axis(length):
        edges = np.linspace(-length / 2, length / 2, panels + 1)
        lo, hi = edges[:-1, None], edges[1:, None]
        return (0.5 * (hi - lo) * x + 0.5 * (hi + lo)).ravel(), (0.5 * (hi - lo) * w).ravel()

    (xs, wx), (ys, wy) = axis(SIZE[0]), axis(SIZE[1])
    zx, zw = np.polynomial.legendre.leggauss(heights)
    zs, wz = 0.5 * THICKNESS * (zx + 1), 0.5 * THICKNESS * zw
    grid = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1).reshape(-1, 3)
    volume = np.einsum("i,j,k->ijk", wx, wy, wz).ravel()[:, None]
    # u and du_i / dx_j at each point, in 40 chunks of one size: one compiled program for
    # every chunk and both loads (the load is an argument, not a constant of the program)
    load = jax.tree.map(jnp.asarray, load)
    chunks = [_with_jacobian(chunk, load) for chunk in np.array_split(grid, 40)]
    u = np.concatenate([np.asarray(chunk[0]) for chunk in chunks])
    gradient = np.concatenate([np.asarray(chunk[1]) for chunk in chunks])
    omega = 0.5 * np.stack(
        [
            gradient[:, 2, 1] - gradient[:, 1, 2],
            gradient[:, 0, 2] - gradient[:, 2, 0],
            gradient[:, 1, 0] - gradient[:, 0, 1],
        ],
        axis=-1,
    )
    turned = np.cross(omega, POLARIZATION)
    out = []
    for point in points:
        offsets = point - grid
        h = 1e-7
        # -(u . grad_r) N J0 by differences of the dipole field along u
        along = (
            -(
                dipole_field(offsets + h * u / np.abs(u).max(), POLARIZATION)
                - dipole_field(offsets - h * u / np.abs(u).max(), POLARIZATION)
            )
            * np.abs(u).max()
            / (2 * h)
        )
        out.append(np.sum((along + dipole_field(offsets, turned)) * volume, axis=0))
    return np.array(out)


@pytest.mark.slow
@pytest.mark.parametrize("load", [CENTRED, SHEARED], ids=["centred", "sheared"])
def test_the_change_matches_an_independent_integral(load):
    resolution = (20, 20, 6)
    coarse = np.asarray(linear(CHIPS, load, resolution)) - block(CHIPS)
    fine = np.asarray(linear(CHIPS, load, finer(resolution))) - block(CHIPS)
    reference = reference_change(CHIPS, load)
    scale = np.max(np.abs(reference))
    # the finer resolution agrees with the reference to 0.6 % of the largest change (measured:
    # 0.40 % centred and 0.13 % sheared, both at the centre chip's Bz), and the coarser one within
    # its estimate (its distance to the finer one) plus that
    assert np.max(np.abs(fine - reference)) < 6e-3 * scale
    estimate = np.abs(coarse - fine)
    assert np.all(np.abs(coarse - reference) <= estimate + 6e-3 * scale)


@pytest.mark.slow
def test_the_rigid_cells_converge_to_it():
    # a load a thousandth of the one above (the cells' rigid moves are exact, so their
    # nonlinearity is of order u / depth, nil here): the cells at n_z = 4, 8, 16 through the
    # thickness (40 x 40 across, fine enough in the plane) approach the linear field as n_z^-2,
    # and Richardson's extrapolation agrees with it within its own estimate
    scale = 1e-3
    load = SurfaceLoad(
        centre=SHEARED.centre,
        radius=SHEARED.radius,
        normal_force=SHEARED.normal_force * scale,
        shear_force=SHEARED.shear_force * scale,
    )
    layers = {}
    for n_z in (4, 8, 16):
        grid = (40, 40, n_z)
        centres, dimension = layer_cells(size=SIZE, thickness=THICKNESS, cells=grid)
        u, rotation = layer_displacement_grid(
            layer=LAYER,
            load=load,
            size=jnp.asarray(SIZE),
            cells=grid,
            grid=spectral_grid(size=SIZE, thickness=THICKNESS, cells=grid),
        )
        moved, turned = carried_cells(
            centres,
            jnp.broadcast_to(jnp.asarray(POLARIZATION), centres.shape),
            u.reshape(-1, 3),
            rotation.reshape(-1, 3),
        )
        field = cells_field(CHIPS, centres=moved, dimension=dimension, polarization=turned)
        layers[n_z] = (np.asarray(field) - block(CHIPS)) / scale
    expected = (np.asarray(linear(CHIPS, load, (40, 40, 10))) - block(CHIPS)) / scale
    # the centre chip's Bz: successive differences in the ratio 4 of the n_z^-2 rate
    ratio = (layers[8] - layers[4])[0, 2] / (layers[16] - layers[8])[0, 2]
    assert 3.0 < ratio < 5.0
    extrapolated = layers[16] + (layers[16] - layers[8]) / 3.0
    estimate = np.abs(layers[16] - layers[8]) / 3.0
    assert np.all(np.abs(extrapolated - expected) <= estimate + 1e-3 * np.max(np.abs(expected)))
    # and the cells at n_z = 16 are still several times farther off than that
    assert np.max(np.abs(layers[16] - expected)) > 5 * np.max(np.abs(extrapolated - expected))
