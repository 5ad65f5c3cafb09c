import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.signal import lfilter

from magdesign.mechanics import lag_filter, lag_pole, time_constant_from_pole
from magdesign.mechanics.viscoelastic import DOME_HALL_GAIN


def test_dome_hall_pole_is_a_half_second_lag():
    tau = time_constant_from_pole(0.9804, 100.0)
    assert abs(float(tau) - 0.5) < 0.01  # "about 0.5 s"
    np.testing.assert_allclose(float(tau), -0.01 / np.log(0.9804), rtol=1e-14)
    np.testing.assert_allclose(lag_pole(tau, 100.0), 0.9804, rtol=1e-14)
    # 0.01955 is not 1 - 0.9804 = 0.0196: DC gain 0.9974
    np.testing.assert_allclose(DOME_HALL_GAIN, 0.01955 / 0.0196, rtol=1e-12)


def test_reproduces_dome_hall_transfer_function():
    x = np.concatenate([np.linspace(0.0, 5.0, 300), np.full(400, 5.0), np.linspace(5.0, 0.0, 100)])
    tau = time_constant_from_pole(0.9804, 100.0)
    y = lag_filter(x, time_constant=tau, sample_rate=100.0, gain=DOME_HALL_GAIN)
    np.testing.assert_allclose(y, lfilter([0.01955], [1.0, -0.9804], x), rtol=1e-12, atol=1e-14)


def test_step_response_closed_form_and_channels():
    fs, tau = 200.0, 0.25
    n = np.arange(400)
    x = np.ones((400, 3)) * np.array([1.0, -2.0, 0.0])
    y = lag_filter(x, time_constant=tau, sample_rate=fs)
    a = np.exp(-1.0 / (tau * fs))
    np.testing.assert_allclose(y, (1.0 - a ** (n + 1))[:, None] * x, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(y[49, 0], 1.0 - np.exp(-1.0), rtol=1e-12)  # 63 % after one tau
    settled = lag_filter(x, time_constant=tau, sample_rate=fs, initial=x[0])
    np.testing.assert_allclose(settled, x, rtol=1e-13)


def test_jit_vmap_grad():
    x = jnp.linspace(0.0, 1.0, 50)

    def final(tau):
        return lag_filter(x, time_constant=tau, sample_rate=100.0)[-1]

    g = jax.jit(jax.grad(final))(0.3)
    fd = (final(0.3 + 1e-6) - final(0.3 - 1e-6)) / 2e-6
    np.testing.assert_allclose(g, fd, rtol=1e-6)
    taus = jnp.array([0.1, 0.3, 1.0])
    mapped = jax.vmap(final)(taus)
    np.testing.assert_allclose(mapped, [final(t) for t in taus], rtol=1e-13)
    assert np.all(
        np.isfinite(jax.grad(lambda t: jnp.sum(lag_filter(jnp.zeros(5), time_constant=t, sample_rate=1e3)))(1e-6))
    )


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(time_constant=0.0, sample_rate=100.0), "time_constant"),
        (dict(time_constant=0.5, sample_rate=-1.0), "sample_rate"),
    ],
)
def test_bad_input(kwargs, name):
    with pytest.raises(ValueError, match=name):
        lag_filter(jnp.zeros(4), **kwargs)
