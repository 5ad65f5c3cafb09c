"""Physics and accuracy tests of magdesign.fields.cylinder and cylinder_on_axis."""

from decimal import Decimal, getcontext

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields import cylinder, cylinder_on_axis, dipole
from magdesign.fields._special import MULTIPOLE_SWITCH
from magdesign.units import MU0

R, D, J = 1.5e-3, 1e-3, 1.17


def field(points, radius=R, height=D, polarization=J, **kw):
    return np.asarray(cylinder(points, radius=radius, height=height, polarization=polarization, **kw))


def magpylib_field(points, radius=R, height=D, polarization=J):
    magnet = magpylib.magnet.Cylinder(polarization=(0, 0, polarization), dimension=(2 * radius, height))
    return magnet.getB(np.asarray(points))


def rel_err(a, b):
    return np.linalg.norm(a - b, axis=-1) / np.linalg.norm(b, axis=-1)


def on_axis_reference(z, radius, height, remanence):
    """Seed 001 Eq. 1 evaluated as written, in 60-digit decimal arithmetic."""
    getcontext().prec = 60
    z, r, h = Decimal(z), Decimal(radius), Decimal(height)
    u = h + z
    value = u / (r * r + u * u).sqrt() - z / (r * r + z * z).sqrt()
    return float(Decimal(remanence) / 2 * value)


def test_agrees_with_magpylib_in_the_near_box():
    rng = np.random.default_rng(1)
    points = rng.uniform(-10 * R, 10 * R, size=(10_000, 3))
    rho = np.hypot(points[:, 0], points[:, 1])
    edge_distance = np.min(np.hypot(rho - R, np.abs(points[:, 2:3]) - D / 2), axis=-1)
    points = points[edge_distance > 1e-6 * R]
    assert np.max(rel_err(field(points), magpylib_field(points))) < 1e-11


def test_inside_the_magnet_agrees_with_magpylib():
    rng = np.random.default_rng(2)
    radial = R * np.sqrt(rng.uniform(0, 0.98, 500))
    phi = rng.uniform(0, 2 * np.pi, 500)
    points = np.stack([radial * np.cos(phi), radial * np.sin(phi), rng.uniform(-0.49, 0.49, 500) * D], -1)
    assert np.max(rel_err(field(points), magpylib_field(points))) < 1e-11


def test_seed_001_saturation_distance():
    assert cylinder_on_axis(5.8458e-3, radius=1.5e-3, height=1e-3, remanence=1.17) == pytest.approx(4.800e-3, abs=5e-7)


@pytest.mark.parametrize("z_over_r", [-0.9, -0.5, -1e-3, 0.0, 1e-3, 0.3, 2.0, 37.0, 1e3, 1e6])
def test_on_axis_closed_form_is_precise_everywhere(z_over_r):
    z = z_over_r * R
    assert float(cylinder_on_axis(z, radius=R, height=D, remanence=J)) == pytest.approx(
        on_axis_reference(z, R, D, J), rel=1e-14
    )


def test_equals_on_axis_form_on_the_axis():
    z_top = np.concatenate([-np.linspace(0.01, 0.99, 7) * D, np.geomspace(1e-6, 1e6, 40) * R])
    points = np.stack([0 * z_top, 0 * z_top, z_top + D / 2], -1)
    b = field(points)
    expected = np.asarray(cylinder_on_axis(z_top, radius=R, height=D, remanence=J))
    assert np.all(b[:, :2] == 0)
    np.testing.assert_allclose(b[:, 2], expected, rtol=1e-13)


def test_rho_equal_radius_above_below_and_beside():
    # Above and below the magnet the field is continuous at rho = R; on the side wall
    # B_z jumps by J (surface current) and the convention is the mean of both sides.
    h = 1e-9 * R
    for z in [0.8 * D, -2 * D, 7 * R]:
        at, inside, outside = field([[R, 0, z], [R - h, 0, z], [R + h, 0, z]])
        np.testing.assert_allclose(at, magpylib_field([R, 0, z]), rtol=1e-11)
        assert np.linalg.norm(inside - outside) < 1e-7 * np.linalg.norm(at)
    at, inside, outside = field([[R, 0, 0.2 * D], [R - h, 0, 0.2 * D], [R + h, 0, 0.2 * D]])
    assert inside[2] - outside[2] == pytest.approx(J, rel=1e-6)
    assert at[2] == pytest.approx(0.5 * (inside[2] + outside[2]), rel=1e-6)
    np.testing.assert_allclose(at[0], 0.5 * (inside[0] + outside[0]), rtol=1e-6)


def _divergence_and_curl(points, **params):
    jac = jax.vmap(jax.jacfwd(lambda p: cylinder(p, **params)))(jnp.asarray(points))
    div = jnp.trace(jac, axis1=-2, axis2=-1)
    curl = jnp.stack([jac[:, 2, 1] - jac[:, 1, 2], jac[:, 0, 2] - jac[:, 2, 0], jac[:, 1, 0] - jac[:, 0, 1]], -1)
    return np.asarray(div), np.linalg.norm(curl, axis=-1)


def test_divergence_and_curl_vanish_outside():
    rng = np.random.default_rng(3)
    points = rng.uniform(-4 * R, 4 * R, size=(300, 3))
    outside = (np.hypot(points[:, 0], points[:, 1]) > 1.02 * R) | (np.abs(points[:, 2]) > 0.52 * D)
    points = points[outside]
    scale = np.linalg.norm(field(points), axis=-1) / R
    div, curl = _divergence_and_curl(points, radius=R, height=D, polarization=J)
    assert np.max(np.abs(div) / scale) < 1e-9
    assert np.max(curl / scale) < 1e-9


@pytest.mark.parametrize("radius", [1e-6, 1e-4, 1e-1])
def test_scale_invariance(radius):
    unit = np.random.default_rng(4).uniform(-5, 5, size=(200, 3))
    reference = field(unit * R, radius=R, height=D)
    scaled = field(unit * radius, radius=radius, height=D / R * radius)
    np.testing.assert_allclose(scaled, reference, rtol=1e-13, atol=1e-13 * np.max(np.abs(reference)))


def test_symmetries():
    p = np.random.default_rng(5).uniform(-3 * R, 3 * R, size=(200, 3))
    b = field(p)
    mirrored = field(p * [1, 1, -1])
    np.testing.assert_allclose(mirrored, b * [-1, -1, 1], rtol=1e-13, atol=1e-15)
    angle = 0.7
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    np.testing.assert_allclose(field(p @ rot.T), b @ rot.T, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(field(2.0 * p, polarization=-2 * J), -2 * field(2.0 * p), rtol=1e-15)


def test_far_field_tends_to_dipole():
    direction = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
    distances = np.geomspace(10, 1e6, 6) * R
    points = distances[:, None] * direction
    moment = J * np.pi * R**2 * D / MU0
    expected = np.asarray(dipole(points, np.array([0, 0, moment])))
    err = rel_err(field(points), expected)
    # The quadrupole vanishes by symmetry; the octupole falls off like (R / r)^2.
    assert np.all(err < 2 * (R / distances) ** 2)
    assert err[-1] < 1e-11
    np.testing.assert_allclose(field(points, fidelity="dipole"), expected, rtol=1e-15)


def test_continuity_across_the_multipole_switch():
    switch = MULTIPOLE_SWITCH * np.hypot(R, D / 2)
    direction = np.array([0.6, 0.0, 0.8])
    distances = switch * (1 + np.linspace(-20, 20, 41) * 1e-7)
    b = field(distances[:, None] * direction)
    smooth = np.polynomial.polynomial.polyfit(distances - switch, b, 3)
    residual = b - np.polynomial.polynomial.polyval(distances - switch, smooth).T
    assert np.max(np.abs(residual)) < 1e-12 * np.max(np.abs(b))
    second = np.diff(b, 2, axis=0)
    assert np.max(np.abs(second)) < 1e-12 * np.max(np.abs(b))


HARD_POINTS = np.array(
    [
        [0.0, 0.0, 0.0],  # centre
        [0.0, 0.0, 3 * D],  # on the axis
        [0.5 * R, 0.0, 0.5 * D],  # top face
        [0.0, 0.3 * R, -0.5 * D],  # bottom face
        [R, 0.0, 0.1 * D],  # side wall
        [R, 0.0, 0.5 * D],  # exactly on the top edge
        [0.0, -R, -0.5 * D],  # exactly on the bottom edge
        [R * (1 + 1e-12), 0.0, 0.5 * D],  # within 1e-12 radii of an edge
        [R, 0.0, 0.5 * D - 1e-12 * R],
        [0.0, 0.0, 1e6 * R],  # far, on the axis
        [3e5 * R, 4e5 * R, 2e5 * R],  # far, off the axis
    ]
)


def test_hard_cases_are_finite():
    # every hard point for magnets of radius 1 um and 10 cm, in one batch (few compilations)
    radii = np.repeat([1e-6, 0.1], len(HARD_POINTS))
    points = np.concatenate([HARD_POINTS / R * 1e-6, HARD_POINTS / R * 0.1])
    heights = D / R * radii

    def f(p, r, h, j):
        return cylinder(p, radius=r, height=h, polarization=j)

    args = (jnp.asarray(points), jnp.asarray(radii), jnp.asarray(heights), J)
    assert np.all(np.isfinite(jax.vmap(f, in_axes=(0, 0, 0, None))(*args)))
    for jac in (jax.jacfwd, jax.jacrev):
        derivs = jax.jit(jax.vmap(jac(f, argnums=(0, 1, 2, 3)), in_axes=(0, 0, 0, None)))(*args)
        assert all(np.all(np.isfinite(d)) for d in derivs)


def test_gradients_on_the_axis_are_correct():
    # B_x = x dB_x/dx + ...: on the axis dB_x/dx = dB_y/dy = -dB_z/dz / 2 (div B = 0)
    p = jnp.array([0.0, 0.0, 2 * D])
    jac = np.asarray(jax.jacrev(lambda q: cylinder(q, radius=R, height=D, polarization=J))(p))
    dbz = jax.grad(lambda z: cylinder_on_axis(z - D / 2, radius=R, height=D, remanence=J))(2 * D)
    np.testing.assert_allclose(np.diag(jac), [-dbz / 2, -dbz / 2, dbz], rtol=1e-12)


def test_jit_vmap_grad_agree_with_plain_evaluation():
    points = np.random.default_rng(6).uniform(-3 * R, 3 * R, size=(8, 3))
    plain = field(points)

    def bz(p, radius, height, polarization):
        return cylinder(p, radius=radius, height=height, polarization=polarization)[..., 2]

    jitted = jax.jit(lambda p: cylinder(p, radius=R, height=D, polarization=J))(points)
    mapped = jax.vmap(lambda p: cylinder(p, radius=R, height=D, polarization=J))(points)
    np.testing.assert_allclose(jitted, plain, rtol=0, atol=1e-13 * np.max(np.abs(plain)))
    np.testing.assert_allclose(mapped, plain, rtol=0, atol=1e-13 * np.max(np.abs(plain)))
    grads = jax.vmap(jax.grad(bz, argnums=(0, 1, 2, 3)), in_axes=(0, None, None, None))(points, R, D, J)
    # central differences of the (independently validated) field values
    for index, step in ((1, 1e-9), (2, 1e-9), (3, 1e-6)):
        args = [points, R, D, J]
        up, down = list(args), list(args)
        up[index] += step
        down[index] -= step
        fd = (np.asarray(bz(*up)) - np.asarray(bz(*down))) / (2 * step)
        np.testing.assert_allclose(grads[index], fd, rtol=1e-6, atol=1e-9 * np.max(np.abs(fd)))
    h = 1e-9
    fd_x = (np.asarray(bz(points + [h, 0, 0], R, D, J)) - np.asarray(bz(points - [h, 0, 0], R, D, J))) / (2 * h)
    np.testing.assert_allclose(grads[0][:, 0], fd_x, rtol=1e-6, atol=1e-9 * np.max(np.abs(fd_x)))


def test_on_axis_gradients_match_finite_differences():
    g = jax.grad(lambda r, h, z: cylinder_on_axis(z, radius=r, height=h, remanence=J), argnums=(0, 1, 2))(R, D, 2e-3)
    for i, base in enumerate((R, D, 2e-3)):
        step = 1e-8
        args = [R, D, 2e-3]
        up, down = list(args), list(args)
        up[i] += step
        down[i] -= step
        fd = (on_axis_reference(down[2] * 0 + up[2], up[0], up[1], J) - on_axis_reference(down[2], down[0], down[1], J)) / (2 * step)
        assert float(g[i]) == pytest.approx(fd, rel=1e-6)


def test_bad_input():
    with pytest.raises(ValueError, match="radius"):
        cylinder(np.zeros(3), radius=0.0, height=D, polarization=J)
    with pytest.raises(ValueError, match="height"):
        cylinder(np.zeros(3), radius=R, height=-1e-3, polarization=J)
    with pytest.raises(ValueError, match="points"):
        cylinder(np.zeros((4, 2)), radius=R, height=D, polarization=J)
    with pytest.raises(ValueError, match="exact"):
        cylinder(np.zeros(3), radius=R, height=D, polarization=J, fidelity="fem")
    with pytest.raises(ValueError, match="radius"):
        cylinder_on_axis(1e-3, radius=-R, height=D, remanence=J)
    with pytest.raises(ValueError, match="height"):
        cylinder_on_axis(1e-3, radius=R, height=0.0, remanence=J)
