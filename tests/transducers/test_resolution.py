"""The Cramer-Rao bound against independent references: the normal equations' inverse in
numpy, the spread of least-squares fits to simulated noisy readings, and the mean of R
equally noisy readings."""

import jax
import numpy as np

from magdesign.transducers import cramer_rao


def test_the_bound_is_the_inverse_fisher_information():
    rng = np.random.default_rng(3)
    jacobian = rng.normal(size=(12, 4)) * np.array([1.0, 1e3, 1e-3, 5.0])  # mixed units
    noise = rng.uniform(0.5, 2.0, 12)
    bound = cramer_rao(jacobian, noise)
    weighted = jacobian / noise[:, None]
    reference = np.linalg.inv(weighted.T @ weighted)
    np.testing.assert_allclose(bound.covariance, reference, rtol=1e-10, atol=0)
    np.testing.assert_allclose(bound.deviation, np.sqrt(np.diag(reference)), rtol=1e-10)
    np.testing.assert_allclose(float(bound.conditioning), np.linalg.svd(weighted, compute_uv=False)[-1], rtol=1e-12)


def test_least_squares_fits_to_noisy_readings_spread_as_the_bound_says():
    """A linear model: the least-squares estimate is unbiased and efficient, so its spread
    over 20,000 noise draws is the bound (to the sampling error of a variance, ~1 %)."""
    rng = np.random.default_rng(11)
    jacobian = rng.normal(size=(15, 3))
    noise = 0.1
    truth = np.array([1.0, -2.0, 0.5])
    readings = jacobian @ truth + noise * rng.normal(size=(20000, 15))
    fits = np.linalg.lstsq(jacobian, readings.T, rcond=None)[0].T
    spread = np.cov(fits, rowvar=False)
    bound = cramer_rao(jacobian, noise)
    np.testing.assert_allclose(np.sqrt(np.diag(spread)), bound.deviation, rtol=0.03)
    np.testing.assert_allclose(fits.mean(axis=0), truth, atol=3 * float(np.max(bound.deviation)) / np.sqrt(20000))


def test_the_mean_of_r_readings():
    """One parameter read R times with noise s: s / sqrt(R)."""
    bound = cramer_rao(np.ones((25, 1)), 0.3)
    np.testing.assert_allclose(bound.deviation, [0.3 / 5.0], rtol=1e-14)


def test_a_direction_no_reading_sees_is_unresolved_not_exact():
    jacobian = np.array([[1.0, 0.0], [2.0, 0.0], [0.5, 0.0]])
    bound = cramer_rao(jacobian, 1.0)
    assert float(bound.conditioning) == 0.0
    assert float(bound.deviation[1]) > 1e6 * float(bound.deviation[0])
    assert np.all(np.isfinite(jax.jacfwd(lambda j: cramer_rao(j, 1.0).deviation[0])(jacobian)))
