"""Physics and accuracy tests of magdesign.fields.cylinder and cylinder_axial.

References: 40-digit values from an independent integration over the side wall
(references/make_cylinder_references.py writes references/cylinder.json), magpylib, and
closed forms."""

import importlib
import json
from decimal import Decimal, getcontext
from pathlib import Path

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest

from magdesign.fields import cylinder, cylinder_axial, cylinder_on_axis, dipole
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


def on_axis_reference(z, radius, height, polarization):
    """The dome-Hall paper's Eq. 1 (on-axis field) evaluated as written, in 60-digit decimal
    arithmetic, at ``z`` from the magnet's centre (u, v: heights above the bottom and top face)."""
    getcontext().prec = 60
    z, r, h = Decimal(z), Decimal(radius), Decimal(height)
    u, v = z + h / 2, z - h / 2
    value = u / (r * r + u * u).sqrt() - v / (r * r + v * v).sqrt()
    return float(Decimal(polarization) / 2 * value)


REFERENCES = json.loads((Path(__file__).parent / "references" / "cylinder.json").read_text())["cases"]
ASPECTS = sorted({case["height_over_radius"] for case in REFERENCES}, key=float)
REFERENCE_POINTS = max(sum(case["height_over_radius"] == aspect for case in REFERENCES) // 2 for aspect in ASPECTS)


@jax.jit
def _unit_magnet(points, radius, aspect, polarization):
    """The field of a magnet of the given radius and height / radius; radius and aspect are
    traced, so one compilation serves every magnet."""
    return cylinder(points, radius=radius, height=aspect * radius, polarization=polarization)


@pytest.mark.parametrize("aspect", ASPECTS)
@pytest.mark.slow
def test_equals_40_digit_references(aspect):
    """Thin discs (height / radius 1e-6) to long rods (1e3), on the axis, at faces, 1e-9
    radii from an edge, beside the wall, far away and inside: 1e-12 relative."""
    cases = [case for case in REFERENCES if case["height_over_radius"] == aspect]
    points = np.array([case["point"] for case in cases if case["direction"] == "z"])
    along_z, along_x = (
        np.array([[float(v) for v in case["field"]] for case in cases if case["direction"] == direction])
        for direction in ("z", "x")
    )
    radius = 2.5e-3  # the references are in radii: any scale
    padded = np.resize(points, (REFERENCE_POINTS, 3))  # one shape: one compilation for every magnet
    field = lambda polarization: np.asarray(_unit_magnet(padded * radius, radius, float(aspect), polarization))[
        : len(points)
    ]  # noqa: E731
    np.testing.assert_array_less(rel_err(field(1.0), along_z), 1e-12)  # scalar: polarized along +z
    np.testing.assert_array_less(rel_err(field(jnp.array([1.0, 0.0, 0.0])), along_x), 1e-12)
    mixed = 0.6 * along_x - 0.8 * along_z  # the field is linear in the polarization
    np.testing.assert_array_less(rel_err(field(jnp.array([0.6, 0.0, -0.8])), mixed), 1e-12)


def test_a_thin_disc_on_its_axis_keeps_its_digits():
    """The issue's example: a disc of radius 1 mm and height 1 nm, 3.16 mm from its centre."""
    reference = next(c for c in REFERENCES if c["height_over_radius"] == "1e-6" and c["point"] == [0.0, 0.0, 3.16])
    expected = float(reference["field"][2])
    value = cylinder(jnp.array([0.0, 0.0, 3.16e-3]), radius=1e-3, height=1e-9, polarization=1.0)[2]
    assert float(value) == pytest.approx(expected, rel=1e-12)
    # and the on-axis closed form (its two terms evaluated without cancellation) agrees
    assert float(cylinder_axial(3.16e-3, radius=1e-3, height=1e-9, polarization=1.0)) == pytest.approx(
        expected, rel=1e-12
    )


@pytest.mark.parametrize(("radius", "height"), [(1.5e-3, 1e-3), (2e-3, 4e-3), (1e-3, 0.4e-3)])
@pytest.mark.slow
def test_any_direction_agrees_with_magpylib(radius, height):
    """Axial plus diametral polarization, 1e-10 relative in a box of +-5 radii. Points
    within 0.1 radii of the axis are left out: there magpylib's diametral field switches
    to a three-term series in rho (1.3e-10 from the references at 0.06 radii, where ours
    agrees with them to 1e-13, see test_equals_40_digit_references)."""
    rng = np.random.default_rng(11)
    polarization = np.array([0.7, -0.4, 1.1])
    points = rng.uniform(-5, 5, size=(5000, 3)) * radius
    rho = np.hypot(points[:, 0], points[:, 1])
    edge_distance = np.hypot(rho - radius, np.abs(points[:, 2]) - height / 2)
    points = points[(rho > 0.1 * radius) & (edge_distance > 1e-6 * radius)]
    ours = np.asarray(_unit_magnet(points, radius, height / radius, jnp.asarray(polarization)))
    theirs = magpylib.magnet.Cylinder(polarization=polarization, dimension=(2 * radius, height)).getB(points)
    assert np.max(rel_err(ours, theirs)) < 1e-10


@pytest.mark.slow
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


def test_dome_hall_saturation_distance():
    """5.8458 mm above the top face of the 1 mm magnet: 6.3458 mm from its centre."""
    assert cylinder_axial(6.3458e-3, radius=1.5e-3, height=1e-3, polarization=1.17) == pytest.approx(4.800e-3, abs=5e-7)


@pytest.mark.parametrize("z_over_r", [-0.9, -0.5, -1e-3, 0.0, 1e-3, 0.3, 2.0, 37.0, 1e3, 1e6])
def test_on_axis_closed_form_is_precise_everywhere(z_over_r):
    z = D / 2 + z_over_r * R  # z_over_r radii above the top face
    assert float(cylinder_axial(z, radius=R, height=D, polarization=J)) == pytest.approx(
        on_axis_reference(z, R, D, J), rel=1e-14
    )


def test_equals_on_axis_form_on_the_axis():
    z_top = np.concatenate([-np.linspace(0.01, 0.99, 7) * D, np.geomspace(1e-6, 1e6, 40) * R])
    points = np.stack([0 * z_top, 0 * z_top, z_top + D / 2], -1)
    b = field(points)
    expected = np.asarray(cylinder_axial(z_top + D / 2, radius=R, height=D, polarization=J))
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


@pytest.mark.parametrize("height", [D, 1e-6 * R, 1e3 * R])
@pytest.mark.parametrize("polarization", [J, (0.4, -0.9, 0.7)])
@pytest.mark.slow
def test_divergence_and_curl_vanish_outside(height, polarization):
    """By jax derivatives (the closed-form derivatives of the custom JVP), for the dome-Hall
    magnet, a thin disc and a long rod, polarized along the axis or in any direction."""
    rng = np.random.default_rng(3)
    extent = max(4 * R, height)
    points = rng.uniform(-extent, extent, size=(300, 3))
    outside = (np.hypot(points[:, 0], points[:, 1]) > 1.02 * R) | (np.abs(points[:, 2]) > 0.52 * height)
    points = points[outside]
    params = dict(radius=R, height=height, polarization=jnp.asarray(polarization))
    scale = np.linalg.norm(field(points, **params), axis=-1) / np.minimum(R, np.linalg.norm(points, axis=-1))
    div, curl = _divergence_and_curl(points, **params)
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


def test_any_direction_turns_with_the_magnet():
    """Rotating the points and the transverse polarization about the axis rotates B;
    the mirror z -> -z maps (Jx, Jy, Jz) to (-Jx, -Jy, Jz) and B to (-Bx, -By, Bz)."""
    p = np.random.default_rng(5).uniform(-3 * R, 3 * R, size=(200, 3))
    polarization = np.array([0.5, 0.2, 1.1])
    angle = 0.7
    rot = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    b = field(p, polarization=jnp.asarray(polarization))
    np.testing.assert_allclose(
        field(p @ rot.T, polarization=jnp.asarray(rot @ polarization)), b @ rot.T, rtol=1e-12, atol=1e-14
    )
    mirrored = field(p * [1, 1, -1], polarization=jnp.asarray(polarization * [-1, -1, 1]))
    np.testing.assert_allclose(mirrored, b * [-1, -1, 1], rtol=1e-12, atol=1e-14)


def test_axis_fidelity_with_any_direction_is_exact_on_the_axis():
    z = np.concatenate([np.linspace(-0.45, 0.45, 7) * D, D / 2 + np.geomspace(1e-3, 1e2, 9) * R])
    points = np.stack([0 * z, 0 * z, z], -1)
    polarization = jnp.array([0.3, -0.6, 1.1])
    np.testing.assert_allclose(
        field(points, polarization=polarization, fidelity="axis"),
        field(points, polarization=polarization),
        rtol=1e-12,
        atol=1e-15,
    )


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
    polarization = np.array([0.8, -0.3, 0.5])
    expected = np.asarray(dipole(points, polarization * np.pi * R**2 * D / MU0))
    err = rel_err(field(points, polarization=jnp.asarray(polarization)), expected)
    assert np.all(err < 2 * (R / distances) ** 2) and err[-1] < 1e-11


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


@pytest.mark.slow
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


def _in_small_calls(f, *arrays, size=143):
    """``f`` over the points in calls of ``size`` points (below the partitioned size)."""
    return np.concatenate([np.asarray(f(*(a[i : i + size] for a in arrays))) for i in range(0, len(arrays[0]), size)])


@pytest.mark.slow
@pytest.mark.parametrize("aspect", [1e-3, 2 / 3, 10.0])
def test_a_large_call_evaluates_each_point_in_its_own_zone(aspect, monkeypatch):
    """A call of at least 2 PARTITION_CHUNK points runs the far series at every point and
    the near kernel (and the near-axis series) only on its near points, in chunks (256
    points here, the last one padded), or, when most of its points are near, both kernels
    at every point.
    Against magpylib (independent; points off the axis, see
    test_any_direction_agrees_with_magpylib) and against the same points in small calls,
    which select per point, with and without points on the axis, for values, derivatives
    along the points and the height, and vmap(jacfwd) (one point per lane)."""
    monkeypatch.setattr(importlib.import_module("magdesign.fields._partition"), "PARTITION_CHUNK", 256)
    radius, height = 1e-3, aspect * 1e-3
    polarization = jnp.array([0.7, -0.4, 1.1])
    rng = np.random.default_rng(12)
    count = 6 * 256 + 37  # 11 small calls of 143
    # a box about as wide as the multipole switch sphere: about half the points near
    switch = MULTIPOLE_SWITCH * np.hypot(radius, height / 2)
    points = rng.uniform(-1, 1, size=(count, 3)) * switch
    with_axis = points.copy()
    with_axis[::50, :2] = 0.0
    mostly_near = 0.5 * points  # every point inside the switch sphere: both kernels, selected
    directions = rng.normal(size=(count, 3))

    def value(p):
        return cylinder(p, radius=radius, height=height, polarization=polarization)

    @jax.jit
    def tangent(p, d):
        return jax.jvp(
            lambda q, h: cylinder(q, radius=radius, height=h, polarization=polarization),
            (p, height),
            (d, 1e-3 * height),
        )[1]

    for p in (points, with_axis, mostly_near):
        ours = np.asarray(jax.jit(value)(p))
        scale = np.linalg.norm(ours, axis=-1)
        np.testing.assert_array_less(np.linalg.norm(ours - _in_small_calls(jax.jit(value), p), axis=-1), 1e-13 * scale)
        derivative = np.asarray(tangent(p, directions))
        expected = _in_small_calls(tangent, p, directions)
        assert np.max(np.abs(derivative - expected)) < 1e-12 * np.max(np.abs(expected))
    # vmap(jacfwd) runs the JVP rule one point per lane: its batch is evaluated as one call
    jacobians = jax.jit(jax.vmap(jax.jacfwd(value)))
    expected = _in_small_calls(jacobians, with_axis)
    assert np.max(np.abs(np.asarray(jacobians(with_axis)) - expected)) < 1e-12 * np.max(np.abs(expected))
    if aspect == 2 / 3:
        rho = np.hypot(points[:, 0], points[:, 1])
        edge_distance = np.hypot(rho - radius, np.abs(points[:, 2]) - height / 2)
        kept = (rho > 0.1 * radius) & (edge_distance > 1e-6 * radius)
        theirs = magpylib.magnet.Cylinder(polarization=np.asarray(polarization), dimension=(2 * radius, height)).getB(
            points[kept]
        )
        assert np.max(rel_err(np.asarray(jax.jit(value)(points))[kept], theirs)) < 1e-10


def test_gradients_on_the_axis_are_correct():
    # B_x = x dB_x/dx + ...: on the axis dB_x/dx = dB_y/dy = -dB_z/dz / 2 (div B = 0)
    p = jnp.array([0.0, 0.0, 2 * D])
    jac = np.asarray(jax.jacrev(lambda q: cylinder(q, radius=R, height=D, polarization=J))(p))
    dbz = jax.grad(lambda z: cylinder_axial(z, radius=R, height=D, polarization=J))(2 * D)
    np.testing.assert_allclose(np.diag(jac), [-dbz / 2, -dbz / 2, dbz], rtol=1e-12)


def test_on_axis_derivatives_equal_their_closed_forms():
    """First derivatives in z, R and D and the second in z of B_z on the axis, against the
    bracket's derivatives worked out by hand (float64, at distances where they lose no
    digits): inside the magnet, at its centre (where the same-sign form's denominator
    vanishes), on both faces, above it and below it."""
    z = np.array([0.0, -0.4 * D, 0.4 * D, -D / 2, D / 2, 0.500001 * D, 0.8 * D, 2.5 * D, 7.9e-3, -0.8 * D, -2.5 * D])
    u, v = z + D / 2, z - D / 2  # the heights above the bottom and the top face
    s_u, s_v = np.hypot(R, u), np.hypot(R, v)
    expected = {
        "z": R**2 * (1 / s_u**3 - 1 / s_v**3),
        "radius": -R * (u / s_u**3 - v / s_v**3),
        "height": R**2 * (1 / s_u**3 + 1 / s_v**3) / 2,  # the faces move apart by dD / 2 each
        "zz": -3 * R**2 * (u / s_u**5 - v / s_v**5),
    }

    def bracket(z, radius, height):
        return 2 * cylinder_axial(z, radius=radius, height=height, polarization=1.0)

    first = jax.vmap(jax.grad(bracket, argnums=(0, 1, 2)), in_axes=(0, None, None))(z, R, D)
    second = jax.vmap(jax.grad(jax.grad(bracket)), in_axes=(0, None, None))(z, R, D)
    for name, value in zip(("z", "radius", "height", "zz"), (*first, second)):
        np.testing.assert_allclose(
            value, expected[name], rtol=1e-12, atol=1e-12 * np.max(np.abs(expected[name])), err_msg=name
        )


@pytest.mark.slow
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


def _fourth_order_difference(f, x, step):
    """d f / d x by the 4th-order central difference, for each component of x (last axis)."""
    columns = []
    for k in range(np.size(x)):
        e = np.zeros(np.shape(x))
        e.flat[k] = step
        columns.append((-f(x + 2 * e) + 8 * f(x + e) - 8 * f(x - e) + f(x - 2 * e)) / (12 * step))
    return np.stack(columns, -1)


@pytest.mark.parametrize("aspect", [1e-3, 2 / 3, 100.0])
@pytest.mark.parametrize("polarization", [1.3, (0.4, -0.7, 1.1)])
@pytest.mark.slow
def test_derivatives_match_finite_differences(aspect, polarization):
    """The closed-form derivatives (custom JVP) against 4th-order central differences of the
    values, with respect to the points (jacfwd and jacrev), the height, the radius and the
    polarization, for a thin disc, the dome-Hall magnet's shape and a long rod."""
    radius, height = 1.0, aspect
    polarization = jnp.asarray(polarization)
    rng = np.random.default_rng(8)
    points = [rng.uniform(-3, 3, 3) * max(1.0, height) for _ in range(4)]
    points += [
        np.array([0.0, 0.0, height / 2 + 0.5]),
        np.array([1e-4, 0.0, height / 2 + 0.3]),
        np.array([1.5, 0.2, 0.1 * height]),
    ]

    def f(p, r=radius, h=height, j=polarization):
        return cylinder(p, radius=r, height=h, polarization=j)

    value = jax.jit(f)
    jacobians = jax.jit(lambda p: (jax.jacfwd(f)(p), jax.jacrev(f)(p)))
    others = jax.jit(jax.jacfwd(f, argnums=(1, 2, 3)))
    for point in points:
        forward, reverse = (np.asarray(j) for j in jacobians(point))
        numeric = _fourth_order_difference(lambda p: np.asarray(value(p)), point, 1e-3)
        scale = np.max(np.abs(numeric))
        assert np.max(np.abs(forward - numeric)) < 1e-8 * scale, point
        assert np.max(np.abs(forward - reverse)) < 1e-12 * scale, point
        d_radius, d_height, d_polarization = (np.asarray(d) for d in others(point, radius, height, polarization))
        scale = np.max(np.abs(np.asarray(value(point))))
        numeric = _fourth_order_difference(lambda r: np.asarray(f(point, r=r[0])), np.array([radius]), 1e-4)[..., 0]
        assert np.max(np.abs(d_radius - numeric)) < 1e-8 * scale, point
        numeric = _fourth_order_difference(
            lambda h: np.asarray(f(point, h=h[0])), np.array([height]), 1e-4 * min(height, radius)
        )[..., 0]
        assert np.max(np.abs(d_height - numeric)) < 1e-8 * scale / height, point
        if np.ndim(polarization):  # linear in the polarization: the derivative is the unit fields
            unit = np.stack([np.asarray(f(point, j=jnp.eye(3)[k])) for k in range(3)], -1)
            np.testing.assert_allclose(d_polarization, unit, rtol=1e-13, atol=1e-15 * scale)


@pytest.mark.slow
def test_second_derivatives_on_and_near_the_axis_are_finite_and_agree():
    """The design solver differentiates the field twice (sensors on the axis): the second
    derivatives there and 1e-7 radii off it are finite and continuous."""
    hessian = jax.jit(jax.hessian(lambda p: cylinder(p, radius=R, height=D, polarization=J)[2]))
    on_axis = np.asarray(hessian(jnp.array([0.0, 0.0, 3 * D])))
    near = np.asarray(hessian(jnp.array([1e-7 * R, 0.0, 3 * D])))
    assert np.all(np.isfinite(on_axis)) and np.all(np.isfinite(near))
    # off the axis the mixed derivatives grow like (rho / distance) |H|: 1e-7 of it here
    np.testing.assert_allclose(near, on_axis, rtol=1e-6, atol=1e-6 * np.max(np.abs(on_axis)))
    dz2 = jax.grad(jax.grad(lambda z: cylinder_axial(z, radius=R, height=D, polarization=J)))(3 * D)
    assert on_axis[2, 2] == pytest.approx(float(dz2), rel=1e-10)


def test_on_axis_gradients_match_finite_differences():
    g = jax.grad(lambda r, h, z: cylinder_axial(z, radius=r, height=h, polarization=J), argnums=(0, 1, 2))(R, D, 2e-3)
    for i in range(3):
        step = 1e-8
        args = [R, D, 2e-3]
        up, down = list(args), list(args)
        up[i] += step
        down[i] -= step
        fd = (
            on_axis_reference(down[2] * 0 + up[2], up[0], up[1], J) - on_axis_reference(down[2], down[0], down[1], J)
        ) / (2 * step)
        assert float(g[i]) == pytest.approx(fd, rel=1e-6)


def test_bad_input():
    # the message names the argument and its unit
    with pytest.raises(ValueError, match=r"radius must be positive and finite \(in m\)"):
        cylinder(np.zeros(3), radius=0.0, height=D, polarization=J)
    with pytest.raises(ValueError, match=r"height .*\(in m\)"):
        cylinder(np.zeros(3), radius=R, height=-1e-3, polarization=J)
    with pytest.raises(ValueError, match="points"):
        cylinder(np.zeros((4, 2)), radius=R, height=D, polarization=J)
    with pytest.raises(ValueError, match="exact"):
        cylinder(np.zeros(3), radius=R, height=D, polarization=J, fidelity="fem")
    with pytest.raises(ValueError, match="radius"):
        cylinder_axial(1e-3, radius=-R, height=D, polarization=J)
    with pytest.raises(ValueError, match="height"):
        cylinder_axial(1e-3, radius=R, height=0.0, polarization=J)


def test_shapes_that_do_not_broadcast_name_the_argument():
    """A radius per point is no cylinder field's input (one magnet per call); on the axis
    the sizes broadcast with z, and a mismatch names the argument, not jnp's internals."""
    points = np.zeros((5, 3)) + [0.0, 0.0, 2 * D]
    for fidelity in ("exact", "axis", "dipole"):
        with pytest.raises(ValueError, match=r"radius must be a scalar \(one magnet per call.*got shape \(3,\)"):
            cylinder(points, radius=np.full(3, R), height=D, polarization=J, fidelity=fidelity)
    with pytest.raises(ValueError, match=r"polarization has shape \(4, 3\), which does not broadcast with points"):
        cylinder(points, radius=R, height=D, polarization=np.ones((4, 3)))
    with pytest.raises(ValueError, match=r"radius has shape \(3,\), which does not broadcast with z of shape \(5,\)"):
        cylinder_axial(np.full(5, 2 * D), radius=np.full(3, R), height=D, polarization=J)
    # sizes that do broadcast: one magnet per z, each its own closed form
    radii = np.array([1.0, 2.0, 3.0]) * R
    values = cylinder_axial(2 * D, radius=radii, height=D, polarization=J)
    expected = [on_axis_reference(2 * D, r, D, J) for r in radii]
    np.testing.assert_allclose(values, expected, rtol=1e-14)


def test_cylinder_on_axis_is_deprecated_and_unchanged():
    """The old on-axis function (z above the top face, ``remanence=``) still returns Eq. 1
    in its own coordinate, and warns naming cylinder_axial; ``polarization=`` is accepted."""
    z_top = 5.8458e-3
    # the paper's Eq. 1 written out, with z measured from the top face
    expected = J / 2 * ((D + z_top) / np.sqrt(R**2 + (D + z_top) ** 2) - z_top / np.sqrt(R**2 + z_top**2))
    with pytest.warns(DeprecationWarning, match=r"cylinder_axial\(z \+ height / 2.*polarization="):
        old = float(cylinder_on_axis(z_top, radius=R, height=D, remanence=J))
    with pytest.warns(DeprecationWarning, match="cylinder_axial"):
        renamed = float(cylinder_on_axis(z_top, radius=R, height=D, polarization=J))
    new = float(cylinder_axial(z_top + D / 2, radius=R, height=D, polarization=J))
    assert old == pytest.approx(expected, rel=1e-14)
    assert renamed == old and new == pytest.approx(expected, rel=1e-14)
    with pytest.raises(TypeError, match="give polarization="):
        cylinder_on_axis(z_top, radius=R, height=D, polarization=J, remanence=J)


@pytest.mark.slow
def test_points_as_a_nested_list_holding_traced_values():
    """A list of [x, y, z] whose entries are traced (vmap over z) is read like an array."""
    field = jax.vmap(lambda z: cylinder([[0.0, 0.0, z]], radius=R, height=D, polarization=J))(jnp.array([2 * D, 3 * D]))
    expected = cylinder(np.array([[0.0, 0.0, 2 * D], [0.0, 0.0, 3 * D]]), radius=R, height=D, polarization=J)
    np.testing.assert_allclose(field[:, 0], expected, rtol=1e-14)
    with pytest.raises(ValueError, match="points"):
        cylinder([[0.0, 0.0]], radius=R, height=D, polarization=J)
