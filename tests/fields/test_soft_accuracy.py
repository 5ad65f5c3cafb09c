"""The surface formulation of linear soft bodies (magdesign.fields.soft_surface): its answer
against the sphere's closed form, its error estimate against the true error (closed form)
and against much finer solves (cylinders), and the rtol ladder.

References: a linear sphere in a uniform field H0 has the uniform magnetisation
M = 3 chi / (3 + chi) H0 (e.g. Jackson, "Classical Electrodynamics", 3rd ed., 1999,
section 5.10); in a field with a uniform gradient its dipole moment is the same (the
gradient drives the l = 2 response, which carries no dipole moment). The cylinders'
values come from the same method at a finer level (labelled: a convergence check, not an
independent reference) and from an independent axisymmetric surface-charge solve in numpy
and scipy (tests/fields/reference_axisymmetric_charges.py: ring charges on the generatrix,
elliptic-integral kernels, extrapolated in the panel count), itself checked here against
the sphere's closed form and for its convergence.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import reference_axisymmetric_charges as reference
from scipy import integrate, special

from magdesign.fields import soft_surface
from magdesign.units import MU0

RADIUS = 1e-3
# The reference's extrapolations from 10, 20, 40 and 20, 40, 80 panels differ by at most this
# (relative; measured 2e-4 (length/diameter 0.5, 1), 5e-4 (5), mu_r 10 and 1000).
REFERENCE_AGREEMENT = 1e-3


def sphere_exact(permeability):
    chi = permeability - 1.0
    return 3.0 * chi / (3.0 + chi)  # M / H0


@pytest.mark.parametrize("permeability", [10.0, 100.0, 1000.0])
def test_sphere_within_half_a_percent_and_the_estimate_bounds_the_error(permeability):
    """Measured at level 2 (432 and 768 panels): -8e-4 (mu_r 10) to -1.0e-3 (mu_r 1000),
    estimate ~2e-2."""
    answer = soft_surface.mean_magnetization(
        "sphere", permeability=permeability, external=[0.0, 0.0, MU0], radius=RADIUS, level=2
    )
    error = abs(float(answer.magnetization[2]) / sphere_exact(permeability) - 1.0)
    assert error < 5e-3
    assert float(answer.error) >= error
    np.testing.assert_allclose(answer.magnetization[:2], 0.0, atol=1e-9 * sphere_exact(permeability))
    assert answer.panels == 768 and answer.level == 2


def test_sphere_in_a_gradient_field_keeps_the_uniform_fields_moment():
    """B_ext = B0 + G x with G symmetric and traceless (a field of outside sources)."""
    permeability = 500.0
    b0 = MU0 * np.array([0.3, -0.2, 1.0])  # H0 = (0.3, -0.2, 1) A/m
    gradient = MU0 * np.array([[2.0, 1.0, 0.5], [1.0, -3.0, 0.2], [0.5, 0.2, 1.0]]) / RADIUS

    def external(points):
        return b0 + points @ gradient.T

    answer = soft_surface.mean_magnetization(
        "sphere", permeability=permeability, external=external, radius=RADIUS, level=2
    )
    exact = sphere_exact(permeability) * b0 / MU0
    error = float(jnp.linalg.norm(answer.magnetization - exact) / np.linalg.norm(exact))
    assert error < 5e-3
    assert float(answer.error) >= error


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0, 5.0])
def test_cylinder_estimate_bounds_the_error_of_a_finer_solve(ratio):
    """Length/diameter 0.5..5, mu_r 1000, along and across the axis: level 2 against level 4
    (level 3 for length/diameter 5). Measured: |difference| <= 1.8e-3, estimate 6e-3..1.6e-2."""
    sizes = {"radius": RADIUS, "height": 2.0 * RADIUS * ratio}
    for axis in (0, 2):
        external = MU0 * np.eye(3)[axis]
        coarse = soft_surface.mean_magnetization("cylinder", permeability=1000.0, external=external, level=2, **sizes)
        fine = soft_surface.mean_magnetization(
            "cylinder", permeability=1000.0, external=external, level=3 if ratio > 2 else 4, **sizes
        )
        difference = abs(float(coarse.magnetization[axis] / fine.magnetization[axis]) - 1.0)
        assert difference < 5e-3
        assert float(coarse.error) >= difference


def test_demagnetizing_factor_of_the_sphere_and_its_error():
    """N = 1/3 for a sphere at any permeability."""
    factor, error = soft_surface.demagnetizing_factor("sphere", permeability=1000.0, radius=RADIUS, level=2)
    assert abs(float(factor) - 1.0 / 3.0) < 5e-3 / 3.0
    assert float(error) >= abs(float(factor) - 1.0 / 3.0)


def test_cylinder_levels_one_and_two_agree_within_their_estimate():
    """Length/diameter 1, mu_r 10 and 1000, along the axis (the quick form of the test above)."""
    for permeability in (10.0, 1000.0):
        answers = [
            soft_surface.mean_magnetization(
                "cylinder",
                permeability=permeability,
                external=[0.0, 0.0, MU0],
                radius=RADIUS,
                height=2 * RADIUS,
                level=level,
            )
            for level in (1, 2)
        ]
        difference = abs(float(answers[0].magnetization[2] / answers[1].magnetization[2]) - 1.0)
        assert difference <= float(answers[0].error)
        assert difference < 5e-3


def test_rtol_picks_the_first_level_that_meets_it_or_says_none_does():
    kwargs = {"permeability": 1000.0, "external": [0.0, 0.0, MU0], "radius": RADIUS}
    answer = soft_surface.mean_magnetization("sphere", rtol=0.03, level=4, **kwargs)
    assert bool(answer.converged) and float(answer.error) <= 0.03
    assert answer.level == 2  # level 1's estimate is 3.4e-2 (measured)
    with pytest.raises(RuntimeError, match="no level up to 2 meets rtol=1e-06"):
        soft_surface.mean_magnetization("sphere", rtol=1e-6, level=2, **kwargs)
    quiet = soft_surface.mean_magnetization("sphere", rtol=1e-6, level=2, throw=False, **kwargs)
    assert not bool(quiet.converged) and quiet.level == 2


def test_cube_is_the_same_along_each_axis_and_bad_input_is_refused():
    along = [
        soft_surface.mean_magnetization(
            "cuboid", permeability=100.0, external=MU0 * np.eye(3)[axis], dimension=[2e-3] * 3, level=1
        ).magnetization[axis]
        for axis in range(3)
    ]
    np.testing.assert_allclose(along, along[0], rtol=1e-9)
    with pytest.raises(ValueError, match="level"):
        soft_surface.mean_magnetization("sphere", permeability=10.0, external=[0, 0, 1.0], radius=1.0, level=0)
    with pytest.raises(ValueError, match="shape"):
        soft_surface.mean_magnetization("cone", permeability=10.0, external=[0, 0, 1.0], radius=1.0)


def test_the_answer_is_differentiable_in_the_permeability():
    """d(M/H0)/d mu_r = 9 / (3 + chi)^2 for the sphere; measured -5.5e-3 at level 1."""

    def ratio(permeability):
        return soft_surface.mean_magnetization(
            "sphere", permeability=permeability, external=[0.0, 0.0, MU0], radius=RADIUS, level=1
        ).magnetization[2]

    slope = float(jax.grad(ratio)(100.0))
    np.testing.assert_allclose(slope, 9.0 / (3.0 + 99.0) ** 2, rtol=1e-2)


def test_reference_ring_field_is_minus_the_gradient_of_its_potential():
    """A unit ring charge's potential K(m) / (2 pi^2 sqrt((rho + a)^2 + dz^2)) (the integral of
    1 / (4 pi |x - y|) around the ring, m = 4 rho a / ((rho + a)^2 + dz^2)), differentiated by
    central differences."""

    def potential(rho, z, radius, height):
        plus = (rho + radius) ** 2 + (z - height) ** 2
        return special.ellipk(4.0 * rho * radius / plus) / (2.0 * np.pi**2 * np.sqrt(plus))

    step = 1e-6
    for rho, z, radius, height in [(0.7, 0.3, 1.1, -0.2), (1.5, -0.4, 1.0, 0.1), (0.2, 2.0, 0.9, 0.0)]:
        h_rho, h_z = reference.ring_field(rho, z, radius, height)
        fd_rho = -(potential(rho + step, z, radius, height) - potential(rho - step, z, radius, height)) / (2 * step)
        fd_z = -(potential(rho, z + step, radius, height) - potential(rho, z - step, radius, height)) / (2 * step)
        np.testing.assert_allclose([h_rho, h_z], [fd_rho, fd_z], rtol=1e-7)


@pytest.mark.parametrize("permeability", [10.0, 1000.0])
def test_reference_solve_meets_the_sphere_closed_form(permeability):
    """The reference on the sphere: N_m = 1/3 and <M> = 3 chi / (3 + chi) H0. Measured: <M>
    -3.5e-4 (mu_r 10) and -3.8e-4 (mu_r 1000) at 40 panels, 2.3e-5 and 2.9e-5 extrapolated from
    10, 20, 40; N_m + 1.5e-4 and + 1.3e-4 at 40 panels."""
    values = [
        reference.mean_magnetization(reference.sphere(panels), permeability) / sphere_exact(permeability)
        for panels in (10, 20, 40)
    ]
    assert abs(values[2] - 1.0) < 5e-4
    assert abs(reference.extrapolated(values) - 1.0) < 5e-5
    factor = reference.demagnetizing_factor(reference.sphere(40), permeability)
    assert abs(factor - 1.0 / 3.0) < 2e-4


@pytest.fixture(scope="module")
def cylinder_references():
    """The reference's N_m (mu_r 10, 1000) by length/diameter, extrapolated from 10, 20, 40 panels."""
    return {ratio: reference.cylinder_factors(ratio, (10.0, 1000.0)) for ratio in (0.5, 1.0, 2.0, 5.0)}


@pytest.mark.slow
def test_reference_cylinder_factors_converge():
    """The reference's extrapolations from 10, 20, 40 and from 20, 40, 80 panels agree (its own
    accuracy, ample against the 0.5 % asked of soft_surface). Measured: see REFERENCE_AGREEMENT."""
    for ratio in (0.5, 1.0, 2.0, 5.0):
        coarse = reference.cylinder_factors(ratio, (10.0, 1000.0))
        fine = reference.cylinder_factors(ratio, (10.0, 1000.0), counts=(20, 40, 80))
        np.testing.assert_allclose(coarse, fine, rtol=REFERENCE_AGREEMENT)


@pytest.mark.parametrize("ratio", [0.5, 1.0, 2.0, 5.0])
@pytest.mark.slow
def test_cylinder_demagnetizing_factor_against_the_independent_reference(ratio, cylinder_references):
    """soft_surface.demagnetizing_factor at level 2 within 0.5 % of the reference (mu_r 10 and
    1000, along the axis), its error estimate above the difference. Measured: +0.05 % (length/
    diameter 5) to +0.27 % (1), the estimate 4 to 24 times the difference."""
    for permeability, expected in zip((10.0, 1000.0), cylinder_references[ratio]):
        factor, error = soft_surface.demagnetizing_factor(
            "cylinder", permeability=permeability, radius=RADIUS, height=2.0 * RADIUS * ratio, level=2
        )
        assert abs(float(factor) / expected - 1.0) < 5e-3
        assert float(error) >= abs(float(factor) - expected)


def end_charge_factor(ratio):
    """N_m at chi -> 0 of a cylinder of unit radius and length/diameter ``ratio``: a uniformly
    magnetised cylinder's field is that of its end discs' charges +-M, and its magnetostatic
    energy gives N_m = (2 / L) * integral_0^inf J1(k)^2 (1 - exp(-k L)) / k^2 dk (L = 2 ratio;
    the discs' Fourier-Bessel transforms 2 pi J1(k) / k). A check independent of both solves
    (its limits: 1 for a thin disc, 0 for a long rod)."""
    length = 2.0 * ratio

    def integrand(k):
        return special.j1(k) ** 2 * -np.expm1(-k * length) / k**2

    edges = np.pi * np.arange(2001)
    total = sum(integrate.quad(integrand, a, b, epsabs=0.0, epsrel=1e-12)[0] for a, b in zip(edges[:-1], edges[1:]))
    total += 1.0 / (2.0 * np.pi * edges[-1] ** 2)  # the tail: J1(k)^2 averages 1 / (pi k)
    return 2.0 / length * total


@pytest.mark.slow
def test_reference_cylinder_meets_the_end_charge_factor_as_chi_goes_to_zero():
    """mu_r 1.0001 (chi N_m ~ 3e-5: N_m within ~1e-5 of its chi = 0 value). Measured, against
    end_charge_factor: 80 panels +1.1e-3 (length/diameter 1) and +3.4e-3 (2); extrapolated
    from 20, 40, 80: -6.9e-5 and -2.4e-4."""
    for ratio in (1.0, 2.0):
        extrapolated = reference.cylinder_factors(ratio, (1.0001,), counts=(20, 40, 80))[0]
        assert abs(extrapolated / end_charge_factor(ratio) - 1.0) < 5e-4
