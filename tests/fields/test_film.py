"""The sinusoidal film of seed 004 (PHYSICS.md 1.2)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.fields import film, film_angle, film_magnitude

T, THICKNESS, M0 = 6e-3, 0.5e-3, 0.1
PARAMS = dict(period=T, thickness=THICKNESS, magnetization=M0)


@pytest.mark.parametrize(("z_mm", "attenuation"), [(2.861, 0.95), (3.736, 0.98), (4.398, 0.99)])
def test_published_attenuation_depths(z_mm, attenuation):
    ratio = film_magnitude(z_mm * 1e-3, **PARAMS) / film_magnitude(0.0, **PARAMS)
    assert 1 - float(ratio) == pytest.approx(attenuation, abs=5e-5)


def test_magnitude_formula_and_thin_film():
    k = 2 * np.pi / T
    expected = M0 * (np.exp(k * THICKNESS) - 1) * np.exp(-k * 2e-3)
    assert float(film_magnitude(2e-3, **PARAMS)) == pytest.approx(expected, rel=1e-14)
    thin = float(film_magnitude(0.0, period=T, thickness=1e-12, magnetization=M0))
    assert thin == pytest.approx(M0 * k * 1e-12, rel=1e-9)


def test_ratio_is_tan_kx_and_independent_of_z():
    k = 2 * np.pi / T
    x = np.linspace(-0.4, 0.4, 9) * T / 2
    for z in (0.5e-3, 3e-3):
        bx, bz = film(x, z, **PARAMS)
        np.testing.assert_allclose(np.asarray(bx) / np.asarray(bz), np.tan(k * x), rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(film_angle(bx, bz), k * x, atol=1e-14)


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


def test_bad_input():
    with pytest.raises(ValueError, match="period"):
        film(0.0, 0.0, period=0.0, thickness=THICKNESS, magnetization=M0)
    with pytest.raises(ValueError, match="thickness"):
        film(0.0, 0.0, period=T, thickness=-1.0, magnetization=M0)
