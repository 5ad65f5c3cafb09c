"""Physics and accuracy tests of magdesign.fields.cuboid.

References: 50-digit values of the textbook corner sum (references/make_cuboid_references.py
writes references/cuboid.json), magpylib's Cuboid where it is accurate, the on-axis
closed form, the dipole far away, and identities (superposition, div B = curl B = 0)."""

import json
from pathlib import Path

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields import cuboid, dipole
from magdesign.fields.cuboid import FAR_SWITCH, ROD_SWITCH, _far, _near, _slab
from magdesign.units import MU0

SIDES = np.array([2e-3, 3e-3, 1e-3])
J = np.array([0.3, -0.5, 1.1])
N_POINTS = 512  # every batch is padded to this: one compilation serves the whole module


@jax.jit
def _field(points, dimension, polarization):
    return cuboid(points, dimension=dimension, polarization=polarization)


def field(points, dimension=SIDES, polarization=J):
    points = np.asarray(points, dtype=float)
    flat = points.reshape(-1, 3)
    out = [
        np.asarray(
            _field(
                np.resize(flat[k : k + N_POINTS], (N_POINTS, 3)),
                np.asarray(dimension, float),
                np.asarray(polarization, float),
            )
        )[: len(flat[k : k + N_POINTS])]
        for k in range(0, len(flat), N_POINTS)
    ]
    return np.concatenate(out).reshape(points.shape)


def magpylib_field(points, dimension=SIDES, polarization=J):
    return magpylib.magnet.Cuboid(polarization=polarization, dimension=dimension).getB(np.asarray(points))


def rel_err(a, b):
    return np.linalg.norm(a - b, axis=-1) / np.linalg.norm(b, axis=-1)


REFERENCES = json.loads((Path(__file__).parent / "references" / "cuboid.json").read_text())["cases"]
SHAPES = sorted({case["shape"] for case in REFERENCES})


@pytest.mark.parametrize("shape", SHAPES)
def test_equals_50_digit_references(shape):
    """Inside, near, 1e-9 off faces, 1e-6 off edges and corners, in the thin slabs, on
    both sides of 20 half diagonals (and of the far switch, 8), 1e3 away; cubes, flat (1e-6) and long (1e3) blocks,
    rods: 2e-13 relative (measured: 6e-14 beyond 5 half diagonals; nearer, 4.5e-16 of J
    where not 1e-13 relative; the bounds leave room for other CPUs' rounding), polarization along x, y, z and mixed."""
    cases = [case for case in REFERENCES if case["shape"] == shape]
    # the references' own float64 sides and points, unscaled: 1e-6 from an edge the field
    # is sensitive to an ulp of either (scale invariance is tested separately)
    dimension = 2.0 * np.array(cases[0]["half_sides"])
    points = np.array([case["point"] for case in cases])
    far = np.linalg.norm(points, axis=-1) > 5.0  # in half diagonals
    columns = {k: np.array([[float(v) for v in case[f"field_of_{k}"]] for case in cases]) for k in "xyz"}
    columns["mixed"] = 0.3 * columns["x"] - 0.5 * columns["y"] + 1.1 * columns["z"]
    polarizations = {"x": np.eye(3)[0], "y": np.eye(3)[1], "z": np.eye(3)[2], "mixed": J}
    for k, polarization in polarizations.items():
        error = np.linalg.norm(field(points, dimension, polarization) - columns[k], axis=-1)
        size = np.linalg.norm(columns[k], axis=-1)
        assert np.all(error[far] < 2e-13 * size[far])
        # near the block: 2e-13 relative, or 2e-15 of J where the field is small and its
        # terms are not (beside thin rods and planks, B ~ 1e-7 J)
        assert np.all(error[~far] < np.maximum(2e-13 * size[~far], 2e-15 * np.linalg.norm(polarization)))


@pytest.mark.parametrize(
    "sides", [(2e-3, 3e-3, 1e-3), (1e-3, 1e-3, 1e-3), (5e-3, 1e-3, 2e-3), (4e-3, 4e-3, 0.4e-3), (0.5e-3, 0.5e-3, 6e-3)]
)
@pytest.mark.parametrize("polarization", [(0.0, 0.0, 1.2), (1.0, 0.0, 0.0), (0.3, -0.5, 1.1)])
def test_agrees_with_magpylib(sides, polarization):
    """Random points inside and outside within 3 sizes (where magpylib keeps its digits):
    1e-10 relative. Points within 1e-6 sizes of a face plane are left out (see the face
    test for those)."""
    sides = np.array(sides)
    rng = np.random.default_rng(int(1e6 * sides.sum()))
    points = rng.uniform(-1.5, 1.5, size=(1500, 3)) * sides.max()
    points = np.concatenate([points, rng.uniform(-0.5, 0.5, size=(300, 3)) * sides])  # inside
    gap = np.min(np.abs(np.abs(points) - sides / 2), axis=-1)
    points = points[gap > 1e-6 * sides.max()]
    assert np.max(rel_err(field(points, sides, polarization), magpylib_field(points, sides, polarization))) < 1e-10


def test_on_faces():
    """On a face the normal component is continuous (magpylib's value); the tangential
    ones jump by the surface current and take the mean of both sides."""
    rng = np.random.default_rng(3)
    for axis in range(3):
        points = rng.uniform(-0.45, 0.45, size=(50, 3)) * SIDES
        points[:, axis] = np.where(rng.uniform(size=50) < 0.5, -1, 1) * SIDES[axis] / 2
        normal = np.eye(3)[axis] * 1e-12
        at = field(points)
        mean = 0.5 * (magpylib_field(points + normal) + magpylib_field(points - normal))
        assert np.max(rel_err(at, mean)) < 1e-9
        np.testing.assert_allclose(at[:, axis], magpylib_field(points)[:, axis], rtol=1e-10, atol=1e-12)
        # and ours on both sides: the jump is mu0 times the surface current, J x n
        outward = np.sign(points[:, axis])[:, None] * np.eye(3)[axis]
        jump = field(points - outward * 1e-14) - field(points + outward * 1e-14)
        np.testing.assert_allclose(jump, J - np.sum(J * outward, -1, keepdims=True) * outward, atol=1e-9)


def on_axis(z, a, b, c, polarization):
    """B_z on the z axis of an a x b x c block polarized along z (textbook): with
    z1 = z - c/2 and z2 = z + c/2, (J / pi) [atan(a b / (2 z1 sqrt(4 z1^2 + a^2 + b^2)))
    - atan(a b / (2 z2 sqrt(...)))], plus J inside."""

    def term(t):
        return np.arctan(a * b / (2 * t * np.sqrt(4 * t * t + a * a + b * b)))

    inside = np.abs(z) < c / 2
    return polarization * (term(z - c / 2) - term(z + c / 2)) / np.pi + polarization * inside


@pytest.mark.parametrize("sides", [(1e-3, 1e-3, 1e-3), (2e-3, 3e-3, 1e-3)])
def test_on_the_axis_equals_the_textbook_formula(sides):
    a, b, c = sides
    z = np.concatenate([np.linspace(-0.49, 0.49, 9) * c, c / 2 + np.geomspace(1e-6, 20, 30) * c])
    points = np.stack([0 * z, 0 * z, z], -1)
    b_field = field(points, sides, (0.0, 0.0, 1.3))
    assert np.all(np.abs(b_field[:, :2]) < 1e-15)
    np.testing.assert_allclose(b_field[:, 2], on_axis(z, a, b, c, 1.3), rtol=1e-12)


def test_far_field_is_the_dipole():
    """A cube has no quadrupole: beyond the dipole its field falls as r^-5, so at r the
    relative difference from the dipole is O((size / r)^2 ... ^4); at 1e3 sizes < 1e-12;
    a 2x3x1 block's quadrupole gives O((size / r)^2) there, < 1e-6."""
    rng = np.random.default_rng(4)
    directions = rng.normal(size=(50, 3))
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    for sides, bound in [((1e-3, 1e-3, 1e-3), 1e-12), (SIDES, 1e-6)]:
        sides = np.array(sides)
        for r in (1e3 * sides.max(), 1e2 * sides.max()):
            points = r * directions
            # magpylib's mu0 is 4 pi 1e-7, ours CODATA: compare with the moment J V / mu0 in ours
            expected = np.asarray(dipole(points, J * np.prod(sides) / MU0))
            error = np.max(rel_err(field(points, sides), expected))
            assert error < bound * (1e3 * sides.max() / r) ** (4 if bound < 1e-9 else 2)


def test_continuous_across_the_switches():
    """At the far-field switch (FAR_SWITCH) the corner sums and the point dipoles, and at
    the rod switch (ROD_SWITCH) the corner sums and the slab quadrature, agree at the
    same points: 5e-13 relative (the plain corner sums keep ~1e-13 there) (dimensionless frame of the kernel, third side the
    shortest, first the middle one)."""
    rng = np.random.default_rng(5)
    d = rng.normal(size=(40, 3))
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    # a block, a plate, and a rod (whose near form there is the slab quadrature)
    for sides, near_form in (([0.8, 0.5, 0.33], _near), ([0.3, 0.9, 1e-4], _near), ([0.01, 1.0, 0.005], _slab)):
        h = jnp.asarray(sides) / np.linalg.norm(sides)
        q = jnp.asarray(FAR_SWITCH * d)
        near, far = (np.asarray(jax.jit(form)(q, h)) @ J for form in (near_form, _far))
        assert np.max(rel_err(near, far)) < 5e-13  # the corner sums lose ~1e-13 at the switch
    # a rod: 0.02 x 0.01 cross-section (half sides a = 0.01, c = 0.005), 1 long; beside it
    # where the distance from [x - a, x + a] to i w (w = z -+ c, here c) is ROD_SWITCH a
    h = jnp.asarray([0.01, 1.0, 0.005])
    a, c = 0.01, 0.005
    y = rng.uniform(-0.8, 0.8, size=40)
    beside = np.sqrt((ROD_SWITCH * a) ** 2 - c**2)
    q = jnp.asarray(np.stack([a + beside + 0 * y, y, 0 * y], -1))
    near, slab = (np.asarray(jax.jit(form)(q, h)) @ J for form in (_near, _slab))
    assert np.max(rel_err(near, slab)) < 5e-13  # the plain difference loses ~1e-13 there


def test_superposition_of_two_halves():
    """Two half blocks side by side (along each axis in turn) make the whole block."""
    rng = np.random.default_rng(6)
    points = rng.uniform(-2, 2, size=(300, 3)) * SIDES.max()
    points = np.concatenate([points, rng.uniform(-0.45, 0.45, size=(100, 3)) * SIDES])
    whole = field(points)
    for axis in range(3):
        half = SIDES.copy()
        half[axis] /= 2
        shift = np.eye(3)[axis] * SIDES[axis] / 4
        gap = np.min(np.abs(np.abs(points - shift) - half / 2), -1)  # off the halves' faces
        keep = (gap > 1e-6 * SIDES.max()) & (np.min(np.abs(np.abs(points + shift) - half / 2), -1) > 1e-6 * SIDES.max())
        parts = field(points - shift, half) + field(points + shift, half)
        assert np.max(rel_err(parts[keep], whole[keep])) < 1e-12


N_DERIVATIVE = 64  # derivative batches are padded to this: one compilation each


@jax.jit
def _jacobians(points, sides, polarization):
    """dB/dpoints, dB/ddimension, dB/dpolarization (forward mode), each (N, 3, 3)."""
    return jax.vmap(
        jax.jacfwd(lambda p, d, j: cuboid(p, dimension=d, polarization=j), argnums=(0, 1, 2)), (0, None, None)
    )(points, sides, polarization)


@jax.jit
def _gradients(points, sides, polarization):
    """Reverse mode: the gradients of sum |B|^2 with respect to all three arguments."""
    return jax.grad(lambda p, d, j: jnp.sum(cuboid(p, dimension=d, polarization=j) ** 2), argnums=(0, 1, 2))(
        points, sides, polarization
    )


def jacobians(points, sides=SIDES, polarization=J):
    points = np.asarray(points, dtype=float)
    padded = np.resize(points, (N_DERIVATIVE, 3))
    out = _jacobians(padded, np.asarray(sides, float), np.asarray(polarization, float))
    return [np.asarray(o)[: len(points)] for o in out]


@pytest.mark.parametrize("sides", [(2e-3, 3e-3, 1e-3), (1e-3, 1e-3, 1e-9), (1e-3, 1e-3, 1.0)])
@pytest.mark.slow
def test_divergence_and_curl_vanish_outside(sides):
    """By jax derivatives (jacfwd), for a block, a flat one (1e-6) and a long one (1e3)."""
    sides = np.array(sides)
    rng = np.random.default_rng(7)
    points = rng.uniform(-1, 1, size=(400, 3)) * np.maximum(sides, 0.3 * sides.max())
    points = points[np.any(np.abs(points) > 0.51 * sides, axis=-1)]
    jac = jacobians(points[:N_DERIVATIVE], sides)[0]
    points = points[:N_DERIVATIVE]
    values = np.linalg.norm(field(points, sides), axis=-1)
    distance = np.linalg.norm(np.maximum(np.abs(points) - sides / 2, 0.0), axis=-1)
    scale = values / np.minimum(distance, sides.max())  # |B| / length
    div = np.trace(jac, axis1=-2, axis2=-1)
    curl = np.stack([jac[:, 2, 1] - jac[:, 1, 2], jac[:, 0, 2] - jac[:, 2, 0], jac[:, 1, 0] - jac[:, 0, 1]], -1)
    assert np.max(np.abs(div) / scale) < 1e-9
    assert np.max(np.linalg.norm(curl, axis=-1) / scale) < 1e-9


def _hard_points(sides):
    a, b, c = np.asarray(sides) / 2
    size = max(a, b, c)
    return np.array(
        [
            [a, 0.1 * b, -0.3 * c],  # on faces
            [0.2 * a, b, 0.4 * c],
            [-0.3 * a, 0.1 * b, -c],
            [a, b, 0.2 * c],  # on edges
            [0.1 * a, -b, c],
            [-a, 0.5 * b, c],
            [a, b, c],  # on corners
            [-a, -b, -c],
            [a + 2 * size, 0.0, c],  # on an edge's extension
            [0.0, 0.0, 0.0],  # centre
            [1e3 * size, 0.0, 0.0],  # far, on the axes and off them
            [0.0, 0.0, -1e3 * size],
            [7e2 * size, -5e2 * size, 3e2 * size],
            [FAR_SWITCH * np.sqrt(a * a + b * b + c * c), 0.0, 0.0],  # on the switch
        ]
    )


@pytest.mark.parametrize(
    "sides", [(2e-3, 3e-3, 1e-3), (1e-3, 1e-3, 1e-9), (1e-6, 1e-3, 1e-3), (1e-3, 1e-3, 1.0), (1e-6, 1e-6, 1e-3)]
)
@pytest.mark.slow
def test_no_nan_in_values_or_gradients(sides):
    """Faces, edges, corners, an edge's extension, 1e3 sizes away, flat (1e-6) and long
    (1e3) blocks: finite values and finite derivatives with respect to the points, the
    dimension and the polarization."""
    points = _hard_points(sides)
    assert np.all(np.isfinite(field(points, sides)))
    assert all(np.all(np.isfinite(jac)) for jac in jacobians(points, sides))
    padded = np.resize(points, (N_DERIVATIVE, 3))
    assert all(np.all(np.isfinite(np.asarray(g))) for g in _gradients(padded, np.asarray(sides, float), J))


@pytest.mark.slow  # compiles the field's forward Jacobians and reverse gradients in the points and sides
def test_derivatives_match_finite_differences():
    """Forward mode (points, dimension) and reverse mode against central differences."""
    rng = np.random.default_rng(8)
    points = rng.uniform(-2, 2, size=(40, 3)) * SIDES.max()
    points = points[np.any(np.abs(points) > 0.55 * SIDES, axis=-1)]
    along_points, along_dimension, _ = jacobians(points)
    step = 1e-6 * SIDES.max()
    for k in range(3):
        e = np.eye(3)[k] * step
        fd = (field(points, SIDES + e) - field(points, SIDES - e)) / (2 * step)
        np.testing.assert_allclose(along_dimension[:, :, k], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
        fd = (field(points + e) - field(points - e)) / (2 * step)
        np.testing.assert_allclose(along_points[:, :, k], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(fd)))
    padded = np.resize(points, (N_DERIVATIVE, 3))
    reverse = _gradients(padded, SIDES, J)[1]
    forward = 2 * np.einsum("ni,nik->k", field(padded), jacobians(padded)[1])
    np.testing.assert_allclose(reverse, forward, rtol=1e-10)


def test_symmetry_and_scale():
    """Mirror symmetry (B of the mirrored point, polarization mirrored as a vector) and
    scale invariance from 1 um to 1 m."""
    rng = np.random.default_rng(9)
    unit = rng.uniform(-2, 2, size=(200, 3))
    shape = SIDES / SIDES.max()
    reference = field(unit * 1e-3, shape * 1e-3)
    for scale in (1e-6, 1.0):
        np.testing.assert_allclose(field(unit * scale, shape * scale), reference, rtol=1e-12, atol=1e-15)
    mirror = np.array([1.0, -1.0, 1.0])
    np.testing.assert_allclose(
        field(unit * mirror * 1e-3, SIDES, J * mirror), field(unit * 1e-3) * mirror, rtol=1e-12, atol=1e-15
    )


@pytest.mark.slow
def test_batched_dimensions_and_vmap():
    """Cells of a method-of-moments grid: dimension and polarization (..., 3) broadcast."""
    rng = np.random.default_rng(10)
    points = rng.uniform(-3, 3, size=(8, 3)) * 1e-3
    sides = rng.uniform(0.5, 2, size=(8, 3)) * 1e-3
    polarization = rng.normal(size=(8, 3))
    batched = np.asarray(jax.jit(lambda p, s, j: cuboid(p, dimension=s, polarization=j))(points, sides, polarization))
    one_by_one = np.stack([field(p[None], s, j)[0] for p, s, j in zip(points, sides, polarization)])
    np.testing.assert_allclose(batched, one_by_one, rtol=1e-13, atol=1e-18)
    mapped = jax.jit(jax.vmap(lambda p, s, j: cuboid(p, dimension=s, polarization=j)))(points, sides, polarization)
    np.testing.assert_allclose(mapped, one_by_one, rtol=1e-13, atol=1e-18)


def test_bad_arguments():
    with pytest.raises(ValueError, match="points"):
        cuboid(np.zeros(2), dimension=SIDES, polarization=J)
    with pytest.raises(ValueError, match="dimension"):
        cuboid(np.zeros(3), dimension=(1.0, 0.0, 1.0), polarization=J)
    with pytest.raises(ValueError, match="polarization"):
        cuboid(np.zeros(3), dimension=SIDES, polarization=1.0)
    points = np.zeros((5, 3)) + [0.0, 0.0, 1e-2]
    with pytest.raises(ValueError, match=r"dimension has shape \(4, 3\), which does not broadcast with points"):
        cuboid(points, dimension=np.ones((4, 3)) * 1e-3, polarization=J)
    with pytest.raises(ValueError, match=r"polarization has shape \(4, 3\), which does not broadcast with points"):
        cuboid(points, dimension=SIDES, polarization=np.ones((4, 3)))
