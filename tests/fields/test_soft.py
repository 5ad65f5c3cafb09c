"""The method of moments for linear soft bodies (magdesign.fields.soft) against exact answers
that do not come from it: the sphere in a uniform field (M = 3 chi / (3 + chi) H0),
Aharoni's magnetometric factors of prisms and the closed-form factors of cylinders, and
the force and induced field of a soft sphere beside a point dipole from the exact multipole
series (all three computed at 40 digits, stored to 25, in references/soft.json,
make_soft_references.py).

Tolerances are the method's own discretisation error, measured (the cells in each test's
docstring); the tests of the factors and of the uniform field also assert that the error
falls as the cells shrink, so a tolerance cannot hide a method that does not converge.
"""

import json
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.fields import cuboid, cuboid_tensor, dipole, soft
from magdesign.units import MU0

REFERENCES = json.loads((pathlib.Path(__file__).parent / "references" / "soft.json").read_text())
demagnetizing = jax.jit(soft.demagnetizing_tensor)
solve = jax.jit(soft.magnetization)


@pytest.mark.slow
def test_the_cell_tensor_is_the_cuboid_field_for_each_direction_and_symmetric():
    """Consistency of the two entry points (cuboid is T J; its values are checked against
    references in test_cuboid.py) and the symmetry the moments system relies on."""
    rng = np.random.default_rng(0)
    points = rng.uniform(-3e-3, 3e-3, (50, 3))
    dimension = np.array([1e-3, 2e-3, 0.5e-3])
    tensor = np.asarray(cuboid_tensor(points, dimension=dimension))
    for axis in range(3):
        column = cuboid(points, dimension=dimension, polarization=np.eye(3)[axis])
        np.testing.assert_allclose(tensor[..., axis], column, rtol=0, atol=1e-15)
    np.testing.assert_allclose(tensor, np.swapaxes(tensor, -1, -2), rtol=0, atol=1e-14)


@pytest.mark.parametrize("case", REFERENCES["prism_demag"]["cases"], ids=lambda c: "x".join(map(str, c["half_sides"])))
@pytest.mark.slow
def test_prism_demagnetizing_factors_against_aharoni(case):
    """A prism is filled exactly by its cells: only the collocation's error remains. Measured:
    below 2e-7 for the compact prisms at 16 cells, 2e-3 where a side gets one or two cells."""
    exact = np.array([float(v) for v in case["N"]])
    sides = 2e-3 * np.array(case["half_sides"])
    errors = []
    for cells in (8, 16):
        tensor = np.asarray(demagnetizing(soft.soft_body("cuboid", dimension=sides, cells=cells, permeability=2.0)))
        errors.append(np.max(np.abs(np.diag(tensor) - exact)))
        np.testing.assert_allclose(tensor - np.diag(np.diag(tensor)), 0.0, atol=1e-14)
        np.testing.assert_allclose(np.trace(tensor), 1.0, atol=1e-12)
    compact = max(case["half_sides"]) / min(case["half_sides"]) <= 4
    assert errors[1] < (2e-6 if compact else 3e-3)
    assert errors[1] <= errors[0] + 1e-13


@pytest.mark.parametrize("case", REFERENCES["cylinder_demag"]["cases"][1:5], ids=lambda c: f"gamma{c['gamma']}")
@pytest.mark.slow
def test_cylinder_demagnetizing_factors_against_the_closed_form(case):
    """The staircase keeps the cylinder's volume; its factor converges like the cell size.
    Measured at 16 cells: 0.24-0.55 % for L / D from 0.25 to 2."""
    exact = float(case["N_z"])
    diameter = 1e-3
    errors = [
        abs(
            float(
                demagnetizing(
                    soft.soft_body(
                        "cylinder", radius=diameter / 2, height=case["gamma"] * diameter, cells=n, permeability=2.0
                    )
                )[2, 2]
            )
            / exact
            - 1
        )
        for n in (8, 16)
    ]
    assert errors[1] < 6e-3
    assert errors[1] < errors[0]


@pytest.mark.parametrize("permeability, tolerance", [(2.0, 4e-3), (10.0, 4e-2), (1000.0, 8e-2)])
@pytest.mark.slow
def test_sphere_in_a_uniform_field(permeability, tolerance):
    """M = 3 chi / (3 + chi) H0, uniform. The mean over the cells; measured at 12 cells:
    0.31 % (mu_r 2), 6.6 % (mu_r 1000: the high-permeability staircase converges slowly,
    like the cell size; 5.7 % at 16 cells)."""
    field = jnp.array([0.0, 0.0, 1e-3])
    chi = permeability - 1.0
    exact = 3.0 * chi / (3.0 + chi) * field[2] / MU0
    errors = []
    for cells in (8, 12):
        body = soft.soft_body("sphere", radius=1e-3, cells=cells, permeability=permeability)
        magnetization = np.asarray(solve(body, jnp.broadcast_to(field, (len(body.index), 3))))
        errors.append(abs(magnetization[:, 2].mean() / exact - 1))
        np.testing.assert_allclose(magnetization[:, :2].mean(0), 0.0, atol=1e-9 * exact)
    assert errors[1] < tolerance
    assert errors[1] < errors[0]


def _sphere_beside_dipole(body, position):
    return dipole(body.centres + position, jnp.array([0.0, 0.0, 1.0]))


@jax.jit
def _force(body, position):
    """jax.grad of the co-energy with respect to the sphere's position: the force (N)."""
    return jax.grad(lambda p: soft.coenergy(body, _sphere_beside_dipole(body, p)))(position)


@pytest.mark.parametrize(
    "case",
    [c for c in REFERENCES["sphere_dipole"]["cases"] if c["d_over_a"] == 2.0],
    ids=lambda c: f"mu{c['mu_r']:g}-d{c['d_over_a']:g}",
)
@pytest.mark.slow
def test_force_on_a_soft_sphere_beside_a_dipole(case):
    """The co-energy's gradient against the exact multipole series, on the dipole's axis and
    in its equatorial plane, centre two radii from the dipole. Measured at 12 cells: within
    2.7 % (mu_r 2) and 14.4 % (mu_r 1000, the slow high-permeability convergence above;
    1.8 % and 11.5 % at 16 cells; the staircase's error is not monotone in the cells, so
    the convergence is asserted on the uniform field above)."""
    tolerance = 3.5e-2 if case["mu_r"] < 10 else 0.17
    d = case["d_over_a"] * 1e-3
    for axis, key in ((2, "F_z"), (0, "F_x")):
        position = jnp.zeros(3).at[axis].set(d)
        body = soft.soft_body("sphere", radius=1e-3, cells=12, permeability=case["mu_r"])
        force = np.asarray(_force(body, position))
        assert abs(force[axis] / float(case[key]) - 1) < tolerance, (key, force)
        assert np.all(np.abs(np.delete(force, axis)) < 1e-9 * abs(force[axis]))


@pytest.mark.parametrize(
    "case", [c for c in REFERENCES["sphere_dipole"]["cases"] if c["d_over_a"] == 2.0], ids=lambda c: f"mu{c['mu_r']:g}"
)
@pytest.mark.slow
def test_induced_field_of_a_soft_sphere_beside_a_dipole(case):
    """The sphere's own field beyond it on the axis and beside it, against the series."""
    tolerance = 2e-2 if case["mu_r"] < 10 else 0.12
    position = jnp.array([0.0, 0.0, 2e-3])
    body = soft.soft_body("sphere", radius=1e-3, cells=12, permeability=case["mu_r"])
    magnetization = solve(body, _sphere_beside_dipole(body, position))
    for key in ("B_beyond", "B_beside"):
        exact = np.array([float(v) for v in case[key]["B"]])
        point = np.array(case[key]["point"]) - np.asarray(position)
        value = np.asarray(soft.field(body, magnetization, point))
        assert np.linalg.norm(value - exact) < tolerance * np.linalg.norm(exact), (key, value, exact)


def test_the_system_is_symmetric_and_the_solution_linear_in_the_field():
    body = soft.soft_body("cylinder", radius=0.5e-3, height=3e-3, cells=6, permeability=50.0)
    matrix = np.asarray(soft.interaction(body))
    np.testing.assert_allclose(matrix, matrix.T, atol=1e-14)
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(2, len(body.index), 3)) * 1e-3
    np.testing.assert_allclose(solve(body, a + 2 * b), solve(body, a) + 2 * solve(body, b), rtol=1e-10, atol=1e-6)


def test_a_cube_turned_by_90_degrees_answers_the_same():
    """A cube's cells are the same along x and z: a field along x gives M along x with the
    value a field along z gives along z."""
    body = soft.soft_body("cuboid", dimension=[1e-3] * 3, cells=5, permeability=300.0)
    n = len(body.index)
    along_z = np.asarray(solve(body, jnp.broadcast_to(jnp.array([0.0, 0.0, 1e-3]), (n, 3))))
    along_x = np.asarray(solve(body, jnp.broadcast_to(jnp.array([1e-3, 0.0, 0.0]), (n, 3))))
    np.testing.assert_allclose(along_x[:, 0].mean(), along_z[:, 2].mean(), rtol=1e-12)


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: soft.soft_body("torus", radius=1e-3, cells=4, permeability=2.0), "shape"),
        (
            lambda: soft.soft_body("cylinder", radius=1e-3, cells=4, permeability=2.0),
            "cylinder takes radius= and height=",
        ),
        (lambda: soft.soft_body("sphere", radius=-0.5e-3, cells=4, permeability=2.0), "radius"),
        (lambda: soft.soft_body("sphere", radius=0.5e-3, cells=0, permeability=2.0), "cells"),
        (lambda: soft.soft_body("cuboid", dimension=[1e-3] * 3, cells=20, permeability=2.0), "cells"),
        (lambda: soft.soft_body("sphere", radius=0.5e-3, cells=4, permeability=0.0), "permeability"),
        (
            lambda: soft.magnetization(
                soft.soft_body("sphere", radius=0.5e-3, cells=4, permeability=2.0), np.zeros((3, 3))
            ),
            "external",
        ),
    ],
)
def test_bad_input_is_a_clear_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_size_is_the_deprecated_way_to_size_a_body():
    """``soft_body(shape, size)`` (diameters, as a spec writes them) still works and warns
    naming the keywords; it builds the body the keywords build, whose cells hold the
    body's own volume (4/3 pi r^3, pi r^2 h, the box's)."""
    cases = [
        ("sphere", 2e-3, {"radius": 1e-3}, 4 / 3 * np.pi * 1e-9),
        ("cylinder", [1e-3, 3e-3], {"radius": 0.5e-3, "height": 3e-3}, np.pi * 0.25e-6 * 3e-3),
        ("cuboid", [1e-3, 2e-3, 3e-3], {"dimension": [1e-3, 2e-3, 3e-3]}, 6e-9),
    ]
    for shape, size, keywords, volume in cases:
        with pytest.warns(DeprecationWarning, match=" and ".join(f"{name}=" for name in keywords)):
            old = soft.soft_body(shape, size, cells=6, permeability=2.0)
        new = soft.soft_body(shape, **keywords, cells=6, permeability=2.0)
        assert old.grid == new.grid and old.index == new.index
        np.testing.assert_array_equal(old.cell, new.cell)
        assert float(new.volume) == pytest.approx(volume, rel=1e-12), shape
    with pytest.raises(ValueError, match=r"radius must be a scalar"):
        soft.soft_body("sphere", radius=[1e-3, 2e-3], cells=4, permeability=2.0)
