"""The linear field of a layer magnetised as the sinusoidal film's Halbach pattern.

Independent references: magpylib's Cuboids, many thin ones across x each carrying the
pattern's J at its centre (their midpoint error falls as the square of their width, so two
refinements Richardson-extrapolate to the layer's field); for a wide layer, the film's
closed forms (fields.film: the infinite film's, and the strip's of N periods); for the field's
change, rigid motions of the whole layer, whose first-order change is the undeformed field
moved or turned (B_0(r - u) - B_0(r), and omega x B_0 - ((omega x r) . grad) B_0), taken by
central differences of magpylib's layer."""

import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields.cells import layer_cells
from magdesign.fields.film import film
from magdesign.fields.layer_field import gauss_levels, layer_field, pattern, pattern_field
from magdesign.units import mm

SIZE, THICKNESS, DEPTH, PERIOD = np.array([12 * mm, 10 * mm]), 2 * mm, 1 * mm, 4 * mm
J0 = 0.02
# the film's pattern (strong side down): J = J0 (-sin kx, 0, -cos kx)
POLARIZATION = np.array([0.0, 0.0, -J0])
# a line 1 mm below the layer across both its x sides, and points off its axes
POINTS = np.concatenate(
    [
        np.stack([np.linspace(-8 * mm, 8 * mm, 17), np.full(17, 2 * mm), np.full(17, -DEPTH)], axis=-1),
        np.array([[0.5 * mm, -3 * mm, -2 * DEPTH], [-2.5 * mm, 4.5 * mm, -DEPTH]]),
    ]
)


def cuboids(points, slabs, size=SIZE, polarization=POLARIZATION, period=PERIOD):
    """magpylib: ``slabs`` cuboids across x, each with the pattern at its centre, written here."""
    width = size[0] / slabs
    x = -size[0] / 2 + (np.arange(slabs) + 0.5) * width
    k = 2 * np.pi / period
    # R_y(kx) J(0): turned about y by kx
    turned = np.stack(
        [
            np.cos(k * x) * polarization[0] + np.sin(k * x) * polarization[2],
            np.full(slabs, polarization[1]),
            np.cos(k * x) * polarization[2] - np.sin(k * x) * polarization[0],
        ],
        axis=-1,
    )
    layer = magpylib.Collection(
        *(
            magpylib.magnet.Cuboid(
                polarization=j, dimension=(width, size[1], THICKNESS), position=(c, 0.0, THICKNESS / 2)
            )
            for c, j in zip(x, turned)
        )
    )
    return magpylib.getB(layer, points)


def converged(points, slabs=1500):
    """magpylib's thin cuboids at ``slabs`` and twice as many, Richardson-extrapolated (the
    midpoint error ~ width^2), and that extrapolation's change (its error bound, nearly)."""
    coarse, fine = cuboids(points, slabs), cuboids(points, 2 * slabs)
    return fine + (fine - coarse) / 3, np.max(np.abs(fine - coarse)) / 3


def test_pattern_is_the_films():
    x = np.linspace(-5 * mm, 5 * mm, 11)
    k = 2 * np.pi / PERIOD
    expected = J0 * np.stack([-np.sin(k * x), 0 * x, -np.cos(k * x)], axis=-1)
    np.testing.assert_allclose(pattern(x, PERIOD, POLARIZATION), expected, atol=1e-15)
    # another direction in the x-z plane shifts the pattern's phase: d = x^ is a quarter period on
    quarter = pattern(x, PERIOD, np.array([J0, 0.0, 0.0]))
    np.testing.assert_allclose(quarter, -pattern(x + PERIOD / 4, PERIOD, POLARIZATION), atol=1e-15)


@pytest.mark.slow
def test_undeformed_against_magpylib():
    reference, spread = converged(POINTS)
    assert spread < 1e-6 * J0  # the reference's own error
    errors = {}
    for slabs in (48, 96):  # widths d / 2 and d / 4 ... of the 12 mm layer
        field = pattern_field(
            POINTS, size=SIZE, thickness=THICKNESS, polarization=POLARIZATION, period=PERIOD, slabs=slabs
        )
        errors[slabs] = np.max(np.abs(np.asarray(field) - reference))
    assert errors[96] < 2e-4 * J0
    # the error falls as the slab width squared (pattern_field's docstring)
    assert 3.0 < errors[48] / errors[96] < 5.0


def film_frame(points, periods, period, thickness=THICKNESS):
    """fields.film's (Bx, Bz) at ``points`` below the layer, in the scene's frame (z up)."""
    bx, bz = film(points[:, 0], -points[:, 2], period=period, thickness=thickness, polarization=J0, periods=periods)
    return np.stack([bx, 0 * bx, -bz], axis=-1)


@pytest.mark.slow
def test_wide_layer_is_the_film():
    # 40 periods of 2 mm across x, 200 along y: the strip's field (exact across x), and the
    # infinite film's near the middle, off by the strip's own sides (4.4e-4 of the peak)
    period, periods = 2 * mm, 40
    size = np.array([periods * period, 200 * period])
    x = np.linspace(-3 * mm, 3 * mm, 13)
    points = np.stack([x, 0 * x, np.full(13, -DEPTH)], axis=-1)
    field = np.asarray(
        pattern_field(points, size=size, thickness=THICKNESS, polarization=POLARIZATION, period=period, slabs=640)
    )
    strip, infinite = film_frame(points, periods, period), film_frame(points, None, period)
    peak = np.max(np.abs(infinite))
    np.testing.assert_allclose(field, strip, atol=2e-5 * peak)
    np.testing.assert_allclose(field, infinite, atol=1e-3 * peak)


def moved(points, displacement, rotation, resolution):
    """layer_field's pattern with u and omega at its nodes (broadcast to (n_x, n_y, n_z, 3))."""
    nodes = (*resolution, 3)
    return layer_field(
        points,
        size=SIZE,
        thickness=THICKNESS,
        polarization=POLARIZATION,
        displacement=jnp.broadcast_to(displacement, nodes),
        rotation=jnp.broadcast_to(rotation, nodes),
        period=PERIOD,
    )


def nodes(resolution):
    """layer_field's nodes (n_x, n_y, n_z, 3) (m): the in-plane cell centres at the Gauss heights."""
    nx, ny, nz = resolution
    plane, _ = layer_cells(size=SIZE, thickness=THICKNESS, cells=(nx, ny, 1))
    heights, _ = gauss_levels(nz)
    return np.concatenate(
        [
            np.broadcast_to(np.asarray(plane)[:, :2].reshape(nx, ny, 1, 2), (nx, ny, nz, 2)),
            np.broadcast_to((heights * THICKNESS)[None, None, :, None], (nx, ny, nz, 1)),
        ],
        axis=-1,
    )


# 2 mm (two depths) or more inside the sides: dB's midpoint rule is O(node spacing^2) under a
# side, as for a uniform layer
INNER = POINTS[np.abs(POINTS[:, 0]) <= 4 * mm]
RESOLUTIONS = ((24, 20, 6), (48, 40, 6))  # nodes d / 2 and d / 4 apart


def rigid_change(motion):
    """magpylib's layer moved by ``motion(collection, +-1)`` (a small rigid motion): its field's
    first-order change, by central differences."""
    fields = []
    for sign in (1, -1):
        width = SIZE[0] / 800
        x = -SIZE[0] / 2 + (np.arange(800) + 0.5) * width
        layer = magpylib.Collection(
            *(
                magpylib.magnet.Cuboid(
                    polarization=j, dimension=(width, SIZE[1], THICKNESS), position=(c, 0.0, THICKNESS / 2)
                )
                for c, j in zip(x, np.asarray(pattern(x, PERIOD, POLARIZATION)))
            )
        )
        motion(layer, sign)
        fields.append(layer.getB(INNER))
    return (fields[0] - fields[1]) / 2


@pytest.mark.slow
def test_translation_moves_the_field():
    # B_0(r - u) - B_0(r) to first order
    u = np.array([0.7, -0.4, 0.5]) * 1e-6
    expected = rigid_change(lambda layer, sign: layer.move(sign * u))
    errors = []
    for resolution in RESOLUTIONS:
        change = moved(INNER, u, np.zeros(3), resolution) - moved(INNER, np.zeros(3), np.zeros(3), resolution)
        errors.append(np.max(np.abs(np.asarray(change) - expected)) / np.max(np.abs(expected)))
    # measured 7.9e-3 and 2.0e-3 (rotation: 4.7e-3 and 1.1e-3): the midpoint rule's spacing^2
    assert errors[1] < 3e-3
    assert 3.0 < errors[0] / errors[1] < 5.0


@pytest.mark.slow
def test_rotation_turns_the_field():
    # the whole layer turned by omega about the origin: u = omega x r', each particle turned by omega
    omega = np.array([0.3, -0.5, 0.8]) * 1e-6
    angle, axis = np.linalg.norm(omega), omega / np.linalg.norm(omega)
    expected = rigid_change(
        lambda layer, sign: layer.rotate_from_angax(np.degrees(sign * angle), axis, anchor=(0.0, 0.0, 0.0))
    )
    errors = []
    for resolution in RESOLUTIONS:
        u = np.cross(omega, nodes(resolution))
        change = moved(INNER, u, omega, resolution) - moved(INNER, np.zeros(3), np.zeros(3), resolution)
        errors.append(np.max(np.abs(np.asarray(change) - expected)) / np.max(np.abs(expected)))
    assert errors[1] < 3e-3
    assert 3.0 < errors[0] / errors[1] < 5.0
