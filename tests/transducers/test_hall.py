import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.transducers import Hall3D, ak8963, mlx90393, soft_clip
from magdesign.units import mT, uT


def test_ak8963_saturates_at_4_8_mT():
    sensor = ak8963()
    reading = sensor(jnp.array([[10 * mT, -10 * mT, 4.9 * mT], [4.8 * mT, -4.8 * mT, 0.0]]))
    np.testing.assert_allclose(reading, [[4.8e-3, -4.8e-3, 4.8e-3], [4.8e-3, -4.8e-3, 0.0]], rtol=1e-14, atol=0)


def test_ak8963_steps_by_0_15_uT():
    sensor = ak8963()
    sweep = jnp.linspace(-2 * uT, 2 * uT, 4001)
    reading = sensor(jnp.stack([sweep, -sweep, 0.5 * sweep], axis=-1))
    levels = np.unique(np.asarray(reading[:, 0]))
    np.testing.assert_allclose(np.diff(levels), 0.15e-6, rtol=1e-9)
    assert len(levels) == 27  # -1.95 .. +1.95 uT in 0.15 uT steps
    assert np.max(np.abs(reading[:, 0] - sweep)) <= 0.075e-6 * (1 + 1e-9)
    counts = sensor.counts(jnp.array([1.0 * uT, 0.0, -4.8 * mT]))
    np.testing.assert_array_equal(counts, [7.0, 0.0, -32000.0])


def test_mlx90393_preset_matches_datasheet_table():
    sensor = mlx90393()
    np.testing.assert_allclose(sensor.lsb, [0.150e-6, 0.150e-6, 0.242e-6], rtol=1e-12)
    np.testing.assert_allclose(sensor(jnp.array([1.0, -1.0, 1.0])), 32767 * np.array([0.150e-6, -0.150e-6, 0.242e-6]))
    widest = mlx90393(gain_sel=0, resolution=1)
    # Datasheet: dynamic range 5..50 mT over the gain settings.
    assert 45 * mT < float(widest.full_scale[0]) <= 50 * mT
    assert 4.5 * mT < float(sensor.full_scale[0]) < 5.5 * mT


def test_gain_offset_and_noise():
    sensor = Hall3D(lsb=1e-9, full_scale=10 * mT, gain=[1.0, 2.0, 0.5], offset=[1 * uT, 0.0, -1 * uT], noise_std=2 * uT)
    b = jnp.array([1 * mT, 1 * mT, 1 * mT])
    np.testing.assert_allclose(sensor(b), [1.001e-3, 2e-3, 0.499e-3], rtol=1e-9)
    noisy = sensor(jnp.broadcast_to(b, (20000, 3)), key=jax.random.PRNGKey(0))
    np.testing.assert_allclose(np.std(noisy, axis=0), 2e-6, rtol=0.03)
    np.testing.assert_allclose(np.mean(noisy, axis=0), [1.001e-3, 2e-3, 0.499e-3], atol=0.1e-6)


def test_soft_clip_is_identity_then_smooth_and_bounded():
    x = jnp.linspace(-5.0, 5.0, 1001)
    y = soft_clip(x, 1.0, 2.0)
    inside = np.abs(x) <= 1.0
    np.testing.assert_array_equal(y[inside], x[inside])
    assert np.all(np.abs(y) < 2.0) and np.all(np.diff(y) > 0)
    slope = jax.vmap(jax.grad(lambda v: soft_clip(v, 1.0, 2.0)))(jnp.array([1.0 - 1e-9, 1.0 + 1e-9, -1.0 - 1e-9]))
    np.testing.assert_allclose(slope, 1.0, rtol=1e-6)
    np.testing.assert_allclose(soft_clip(50.0, 1.0, 2.0), 2.0, rtol=1e-12)


def test_smooth_reading_has_gradients_hard_reading_does_not():
    sensor = ak8963()
    b = jnp.array([1.0 * mT, 4.7 * mT, 5.0 * mT])
    np.testing.assert_allclose(sensor(b, smooth=True)[0], sensor(b)[0])
    assert float(sensor(jnp.full(3, 20 * mT), smooth=True)[2]) <= 4.8 * mT
    smooth = jax.jacfwd(lambda v: sensor(v, smooth=True))(b)
    hard = jax.jacfwd(lambda v: sensor(v))(b)
    assert np.all(np.isfinite(smooth))
    np.testing.assert_allclose(smooth[0, 0], 1.0)
    assert 0.0 < smooth[2, 2] < smooth[1, 1] < 1.0
    np.testing.assert_array_equal(hard, 0.0)


def test_jit_vmap_grad_and_zero_field():
    sensor = mlx90393()
    b = jnp.array([[0.0, 0.0, 0.0], [1 * mT, -2 * mT, 3 * mT]])
    jitted = eqx.filter_jit(lambda s, v: s(v, smooth=True))(sensor, b)
    mapped = jax.vmap(lambda v: sensor(v, smooth=True))(b)
    np.testing.assert_array_equal(jitted, mapped)
    grad = jax.grad(lambda v: jnp.sum(sensor(v, smooth=True) ** 2))(b)
    assert np.all(np.isfinite(grad))
    # gradient with respect to the sensor's own parameters (gain) exists too
    grad_gain = eqx.filter_grad(lambda s: jnp.sum(s(b, smooth=True)))(sensor).gain
    np.testing.assert_allclose(grad_gain, np.sum(b, axis=0))


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(lsb=0.0, full_scale=1e-3), "lsb"),
        (dict(lsb=1e-7, full_scale=-1e-3), "full_scale"),
        (dict(lsb=1e-7, full_scale=1e-3, noise_std=-1e-6), "noise_std"),
    ],
)
def test_bad_configuration_names_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):
        Hall3D(**kwargs)


def test_bad_mlx_setting():
    with pytest.raises(ValueError, match="gain_sel"):
        mlx90393(gain_sel=8)
    with pytest.raises(ValueError, match="resolution"):
        mlx90393(resolution=2)
