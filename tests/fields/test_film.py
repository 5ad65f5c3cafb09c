"""The sinusoidal film of Yan et al. (2021), against an independent integration
of its magnetic charges.

The references integrate, with scipy, the film's charges in 2-D (infinite along y): for
the polarization J = J0 (-sin kx, 0, cos kx) filling -d <= z <= 0 (z = depth, pointing
away from the film), the volume charge -div J = J0 k cos kx, the surface charges
J.n = -J0 cos kx on the top face (z = -d) and +J0 cos kx on the bottom face (z = 0),
and for a finite strip J0 (-sin kx) n_x on its two sides. A line charge q (T m) at w0
adds B = q (w - w0) / (2 pi |w - w0|^2); a row of them every T (the infinite film, one
period integrated) adds Bx - i Bz = q / (2 T) cot(pi (w - w0) / T), w = x + i z.
"""

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy import integrate

from magdesign.fields import film, film_angle, film_magnitude

T, THICKNESS, J0 = 6e-3, 0.5e-3, 0.1
K = 2 * np.pi / T
PARAMS = dict(period=T, thickness=THICKNESS, polarization=J0)
QUAD = dict(epsabs=0.0, epsrel=1e-12, limit=200)


def _line_charge(w, w0):
    return (w - w0) / (2 * np.pi * abs(w - w0) ** 2)


def _row_of_line_charges(w, w0):
    return np.conj(np.cos(np.pi * (w - w0) / T) / np.sin(np.pi * (w - w0) / T)) / (2 * T)


def _charge_field(x, z, kernel, left, right, sides):
    """B = Bx + i Bz (T) at depth z of the film's charges between x' = left and right."""
    w = x + 1j * z

    def part(integrand, a, b):
        # quad warns when rounding stops it short of 1e-12; the assertions check the result
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", integrate.IntegrationWarning)
            return _quad(integrand, a, b)

    def _quad(integrand, a, b):
        return (
            integrate.quad(lambda t: integrand(t).real, a, b, **QUAD)[0]
            + 1j * integrate.quad(lambda t: integrand(t).imag, a, b, **QUAD)[0]
        )

    def volume_column(xp):  # the volume charge of the column at x', integrated over depth
        return J0 * K * np.cos(K * xp) * part(lambda zp: kernel(w, xp + 1j * zp), -THICKNESS, 0.0)

    total = part(volume_column, left, right)
    total += part(lambda xp: J0 * np.cos(K * xp) * (kernel(w, xp) - kernel(w, xp - 1j * THICKNESS)), left, right)
    if sides:
        for xe, normal in ((left, -1.0), (right, 1.0)):
            total += part(lambda zp: -J0 * np.sin(K * xe) * normal * kernel(w, xe + 1j * zp), -THICKNESS, 0.0)
    return np.array([total.real, total.imag])


@pytest.mark.parametrize(("x", "z"), [(0.0, 3.5e-3), (1.1e-3, 0.7e-3), (-2.9e-3, 4e-5), (2.2e-3, 9e-3)])
def test_infinite_film_equals_its_integrated_charges(x, z):
    reference = _charge_field(x, z, _row_of_line_charges, 0.0, T, sides=False)
    ours = np.array(film(x, z, **PARAMS))
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-11 * np.linalg.norm(reference))


@pytest.mark.parametrize(
    ("x", "z", "periods"),
    [(0.0, 3.5e-3, 1), (1e-3, 3.5e-3, 3), (9e-3, 1e-3, 3), (8.9e-3, 1e-5, 3), (-2e-3, 2e-4, 2), (3e-2, 5e-3, 1)],
)
def test_finite_film_equals_its_integrated_charges(x, z, periods):
    half = periods * T / 2
    reference = _charge_field(x, z, _line_charge, -half, half, sides=True)
    ours = np.array(film(x, z, **PARAMS, periods=periods))
    np.testing.assert_allclose(ours, reference, rtol=0, atol=1e-11 * np.linalg.norm(reference))


def test_a_film_a_few_periods_wide_is_stronger_than_an_infinite_one():
    """1.76x (one period wide) and 1.09x (three) at 3.5 mm depth, as an outside integration of
    the strip's charges gives; wide -> infinite."""
    infinite = float(film_magnitude(3.5e-3, **PARAMS))
    ratios = [float(jnp.linalg.norm(jnp.stack(film(0.0, 3.5e-3, **PARAMS, periods=n)))) / infinite for n in (1, 3, 40)]
    assert ratios[0] == pytest.approx(1.764, abs=1e-3)
    assert ratios[1] == pytest.approx(1.089, abs=1e-3)
    assert ratios[2] == pytest.approx(1.0, abs=1e-4)


@pytest.mark.parametrize("periods", [None, 2])
def test_divergence_and_curl_vanish_below_the_film(periods):
    """In the film frame (x, depth): the depth axis carries Bz, so both vanish there."""

    def field(p):
        return jnp.stack(film(p[0], p[1], **PARAMS, periods=periods))

    points = np.stack(np.meshgrid(np.linspace(-9e-3, 9e-3, 7), np.geomspace(1e-5, 1e-2, 5)), -1).reshape(-1, 2)
    jac = np.asarray(jax.jit(jax.vmap(jax.jacfwd(field)))(jnp.asarray(points)))
    scale = K * np.linalg.norm(np.asarray(jax.vmap(field)(jnp.asarray(points))), axis=-1)
    assert np.max(np.abs(jac[:, 0, 0] + jac[:, 1, 1]) / scale) < 1e-12
    assert np.max(np.abs(jac[:, 0, 1] - jac[:, 1, 0]) / scale) < 1e-12


@pytest.mark.parametrize(("z_mm", "attenuation"), [(2.861, 0.95), (3.736, 0.98), (4.398, 0.99)])
def test_published_attenuation_depths(z_mm, attenuation):
    ratio = film_magnitude(z_mm * 1e-3, **PARAMS) / film_magnitude(0.0, **PARAMS)
    assert 1 - float(ratio) == pytest.approx(attenuation, abs=5e-5)


def test_magnitude_from_the_bottom_face_and_thin_film():
    expected = J0 * (1 - np.exp(-K * THICKNESS)) * np.exp(-K * 2e-3)
    assert float(film_magnitude(2e-3, **PARAMS)) == pytest.approx(expected, rel=1e-14)
    # Yan et al.'s printed Eq. 1 is e^{kd} larger: it measures z from the top face
    assert float(film_magnitude(2e-3 - THICKNESS, **PARAMS)) == pytest.approx(
        J0 * (np.exp(K * THICKNESS) - 1) * np.exp(-K * 2e-3), rel=1e-14
    )
    thin = float(film_magnitude(0.0, period=T, thickness=1e-12, polarization=J0))
    assert thin == pytest.approx(J0 * K * 1e-12, rel=1e-9)


def test_ratio_is_tan_kx_and_independent_of_z():
    x = np.linspace(-0.4, 0.4, 9) * T / 2
    for z in (0.5e-3, 3e-3):
        bx, bz = film(x, z, **PARAMS)
        np.testing.assert_allclose(np.asarray(bx) / np.asarray(bz), np.tan(K * x), rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(film_angle(bx, bz), K * x, atol=1e-14)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_quarter_period_is_finite_and_exact(sign):
    x = sign * T / 4

    def angle(x, z):
        return film_angle(*film(x, z, **PARAMS))

    assert float(angle(x, 1e-3)) == sign * np.pi / 2
    grads = jax.grad(angle, argnums=(0, 1))(x, 1e-3)
    assert all(np.isfinite(g) for g in grads)
    assert float(grads[0]) == pytest.approx(2 * np.pi / T, rel=1e-12)
    jac = jax.jacfwd(lambda x: jnp.stack(film(x, 1e-3, **PARAMS)))(x)
    assert np.all(np.isfinite(jac))


def test_finite_film_is_finite_on_its_face_and_at_its_corners():
    half = 1.5 * T
    points = [(half, 0.0), (-half, 0.0), (0.3e-3, 0.0), (half, 1e-12), (half + 1e-3, 0.0), (0.0, 1.0)]

    def field(x, z):
        return jnp.stack(film(x, z, **PARAMS, periods=3))

    field_and_jacobian = jax.jit(lambda x, z: (field(x, z), jax.jacfwd(field, argnums=(0, 1))(x, z)))
    for x, z in points:
        values, jac = field_and_jacobian(x, z)
        assert np.all(np.isfinite(values)) and all(np.all(np.isfinite(j)) for j in jac), (x, z)


def test_bad_input():
    with pytest.raises(ValueError, match="period"):
        film(0.0, 0.0, period=0.0, thickness=THICKNESS, polarization=J0)
    with pytest.raises(ValueError, match="thickness"):
        film(0.0, 0.0, period=T, thickness=-1.0, polarization=J0)
    with pytest.raises(ValueError, match="periods"):
        film(0.0, 0.0, **PARAMS, periods=0)
    with pytest.raises(ValueError, match=r"z has shape \(3,\), which does not broadcast with x of shape \(5,\)"):
        film(np.zeros(5), np.ones(3) * 1e-3, **PARAMS)


def test_magnetization_is_the_deprecated_name_of_polarization():
    """``magnetization=`` (J0 in T) still works, warns naming ``polarization=`` and gives
    the closed form J0 (1 - e^{-kd}) e^{-kz} (sin kx, cos kx)."""
    x, z = T / 8, 2e-3
    magnitude = J0 * (1 - np.exp(-K * THICKNESS)) * np.exp(-K * z)
    with pytest.warns(DeprecationWarning, match="use polarization="):
        bx, bz = film(x, z, period=T, thickness=THICKNESS, magnetization=J0)
    with pytest.warns(DeprecationWarning, match="use polarization="):
        old = film_magnitude(z, period=T, thickness=THICKNESS, magnetization=J0)
    assert float(old) == pytest.approx(magnitude, rel=1e-14)
    np.testing.assert_allclose([bx, bz], [magnitude * np.sin(K * x), magnitude * np.cos(K * x)], rtol=1e-14)
    with pytest.raises(TypeError, match="give polarization= only"):
        film(x, z, period=T, thickness=THICKNESS, magnetization=J0, polarization=J0)
