import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from magdesign.transducers import SpinValve, chip_frame, inesc_spin_valve, panasonic_meander, rotation_matrix
from magdesign.units import MU0, deg, mT


def test_spin_valve_chip_voltages():
    chip = inesc_spin_valve()
    field = jnp.array([[0.0, 0.0, 0.0], [-1 * mT, 0.0, 0.0], [1 * mT, 0.0, 0.0]])
    volts = chip.voltage(field)
    # 1 mA * 2 kOhm * (1 + 0.0072 * B/mT): the precision 0.72 %/mT implies
    np.testing.assert_allclose(volts, [2.0, 1.9856, 2.0144], rtol=1e-12)
    # the paper's rounded 1.985 / 2.015 V
    np.testing.assert_allclose(volts[1:], [1.985, 2.015], atol=1e-3)
    # in-plane b and out-of-plane c components do not change an untilted chip's output
    np.testing.assert_allclose(chip.voltage(jnp.array([0.0, 3 * mT, -3 * mT])), 2.0, rtol=1e-14)


def test_linear_range_then_smooth_saturation():
    chip = inesc_spin_valve()
    inside = jnp.linspace(-2.5 * mT, 2.5 * mT, 11)
    along_a = jnp.stack([inside, 0 * inside, 0 * inside], axis=-1)
    np.testing.assert_allclose(chip.relative_change(along_a), 7.2 * inside, rtol=1e-13, atol=1e-18)
    beyond = jnp.linspace(2.5 * mT, 50 * mT, 200)
    rel = chip.relative_change(jnp.stack([beyond, 0 * beyond, 0 * beyond], axis=-1))
    assert np.all(np.diff(rel[:20]) > 0) and np.all(np.diff(rel) >= 0)
    assert np.all(rel <= 0.025)  # MR 5 % swing: at most +2.5 %
    np.testing.assert_allclose(rel[-1], 0.025, rtol=1e-6)
    slope = jax.vmap(jax.grad(lambda h: chip.relative_change(jnp.array([h, 0.0, 0.0]))))(
        jnp.array([2.5 * mT - 1e-12, 2.5 * mT + 1e-12])
    )
    np.testing.assert_allclose(slope, 7.2, rtol=1e-6)


def test_rotation_is_eq4_rx_ry_rz():
    rng = np.random.default_rng(0)
    angles = rng.uniform(-np.pi, np.pi, size=(20, 3))
    expected = Rotation.from_euler("XYZ", angles).as_matrix()  # intrinsic X, Y, Z = Rx Ry Rz
    np.testing.assert_allclose(rotation_matrix(*angles.T), expected, atol=1e-14)


def test_tilt_alpha_mixes_components_as_eq4():
    h = jnp.array([0.3, -0.7, 0.5])
    alpha = 10 * deg
    ca, sa = np.cos(alpha), np.sin(alpha)
    # Eq. 4 with beta = gamma = 0: H_a = H_x, H_b = cos a H_y - sin a H_z, H_c = sin a H_y + cos a H_z
    np.testing.assert_allclose(chip_frame(h, alpha), [0.3, -0.7 * ca - 0.5 * sa, -0.7 * sa + 0.5 * ca], rtol=1e-14)
    beta = -7 * deg
    # the sensitive component with beta only: H_a = cos b H_x + sin b H_z
    chip = inesc_spin_valve()
    b = jnp.array([1 * mT, 0.4 * mT, -0.8 * mT])
    h_a = np.cos(beta) * 1e-3 + np.sin(beta) * -0.8e-3
    np.testing.assert_allclose(chip.voltage(b, beta=beta), 2.0 * (1 + 7.2 * h_a), rtol=1e-13)


def test_equivalent_field_inverts_eqs_1_2():
    chip = inesc_spin_valve()
    # Eq. 2: dR% = 0.72 % over 0.72 %/mT is 1 mT
    np.testing.assert_allclose(chip.equivalent_field(2e3 * 1.0072), 1e-3, rtol=1e-12)
    fields = jnp.array([[-2e-3, 0, 0], [0.5e-3, 1e-3, 0], [1.7e-3, 0, 2e-3]])
    volts = chip.voltage(fields)
    np.testing.assert_allclose(chip.equivalent_field(volts, reference=2.0), fields[:, 0], rtol=1e-12)


def test_suspension_meander():
    meander = panasonic_meander()
    one_amp_per_metre = jnp.array([MU0 * 1.0, 0.0, 0.0])
    np.testing.assert_allclose(meander.voltage(jnp.zeros(3)), 0.6, rtol=1e-14)
    np.testing.assert_allclose(meander.voltage(one_amp_per_metre) - 0.6, 0.131e-3, rtol=1e-10)
    np.testing.assert_allclose(panasonic_meander(resistance=5e3).voltage(one_amp_per_metre) - 0.6, 0.131e-3, rtol=1e-10)


def test_jit_vmap_grad_finite_at_zero_tilt_and_zero_field():
    chip = inesc_spin_valve()
    alphas = jnp.linspace(-10 * deg, 10 * deg, 8)
    b = jnp.array([0.7 * mT, -0.2 * mT, 0.4 * mT])
    mapped = jax.jit(jax.vmap(lambda a: chip.voltage(b, alpha=a, beta=a)))(alphas)
    looped = np.array([chip.voltage(b, alpha=a, beta=a) for a in alphas])
    np.testing.assert_allclose(mapped, looped, rtol=1e-14)
    for field in (jnp.zeros(3), b, jnp.array([10 * mT, 0.0, 0.0])):
        grads = jax.grad(lambda f, a, bb, g: chip.voltage(f, a, bb, g), argnums=(0, 1, 2, 3))(field, 0.0, 0.0, 0.0)
        assert all(np.all(np.isfinite(g)) for g in grads)
    # d V / d beta at zero tilt: I R0 s H_z (from H_a = cos b H_x + sin b H_z)
    d_beta = jax.grad(lambda bb: chip.voltage(b, beta=bb))(0.0)
    np.testing.assert_allclose(d_beta, 2.0 * 7.2 * 0.4e-3, rtol=1e-12)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(resistance=2e3, sensitivity=7.2, bias_current=-1e-3), "bias_current"),
        (dict(resistance=0.0, sensitivity=7.2, bias_current=1e-3), "resistance"),
        (dict(resistance=2e3, sensitivity=-7.2, bias_current=1e-3), "sensitivity"),
        (
            dict(resistance=2e3, sensitivity=7.2, bias_current=1e-3, linear_range=2e-3, saturation_field=1e-3),
            "linear_range",
        ),
    ],
)
def test_bad_configuration_names_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):
        SpinValve(**kwargs)
