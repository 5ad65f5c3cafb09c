import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.mechanics import LinearElastic, MooneyRivlin, layer_stiffness, shape_factor
from magdesign.units import kPa, mm

ECOFLEX = LinearElastic(E=83 * kPa, nu=0.49)  # Yan et al. (2021)'s Ecoflex 00-50


def test_hooke_is_yan_pressure_relation():
    h, S = 3.5 * mm, 36 * mm**2
    k = layer_stiffness(thickness=h, area=S, material=ECOFLEX)
    dz, dx = 0.1 * mm, 0.05 * mm
    # dP = E dz / h ; Fx = S G dx / h with G = E / (2 (1 + nu))
    np.testing.assert_allclose(k.normal * dz / S, 83e3 * dz / h, rtol=1e-14)
    np.testing.assert_allclose(k.shear * dx, S * 83e3 / (2 * 1.49) * dx / h, rtol=1e-14)


def test_bonded_disc_shape_factor_correction():
    E, nu = 83e3, 0.49
    K = E / (3 * (1 - 2 * nu))
    radius, h = 3 * mm, 1.5 * mm
    S = np.pi * radius**2
    np.testing.assert_allclose(shape_factor(thickness=h, area=S), 1.0, rtol=1e-14)  # a / 2h
    Ec = 3.0 * E  # E (1 + 2 * 1^2)
    k = layer_stiffness(thickness=h, area=S, material=ECOFLEX, fidelity="bonded")
    np.testing.assert_allclose(k.normal, S / h / (1 / Ec + 1 / K), rtol=1e-13)
    np.testing.assert_allclose(k.shear, S / h * E / (2 * (1 + nu)), rtol=1e-14)


def test_bonded_limits_and_ordering():
    material = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)
    S = 10 * mm**2
    thickness = jnp.geomspace(1e-9, 1e3, 25)  # 1 nm .. 1 km
    hooke = layer_stiffness(thickness=thickness, area=S, material=material).normal
    bonded = layer_stiffness(thickness=thickness, area=S, material=material, fidelity="bonded").normal
    E, K = material.youngs_modulus, material.bulk_modulus
    assert np.all(np.isfinite(bonded)) and np.all(np.diff(bonded * thickness) < 0)
    # thick layer: E K / (E + K), the free-layer value less the (small) bulk compliance
    np.testing.assert_allclose(bonded[-1] * thickness[-1] / S, E * K / (E + K), rtol=1e-9)
    np.testing.assert_allclose(bonded[-1], hooke[-1], rtol=E / K)
    assert np.all(bonded[:15] > hooke[:15])  # up to h = 1 cm, S_f > 0.09
    # thin layer: the bulk modulus takes over
    np.testing.assert_allclose(bonded[0] * thickness[0] / S, material.bulk_modulus, rtol=1e-6)


def test_jit_vmap_grad_finite():
    def normal(h, c10):
        material = MooneyRivlin(c10=c10, c01=0.1769e6)
        return layer_stiffness(thickness=h, area=20 * mm**2, material=material, fidelity="bonded").normal

    for h in (1e-9, 2 * mm, 1e3):
        g = jax.jit(jax.grad(normal, argnums=(0, 1)))(h, 0.1182e6)
        assert all(np.isfinite(v) for v in g)
    hs = jnp.array([1 * mm, 2 * mm, 4 * mm])
    np.testing.assert_allclose(jax.vmap(normal, in_axes=(0, None))(hs, 0.1182e6), [normal(h, 0.1182e6) for h in hs])
    h0, c = 2 * mm, 0.1182e6
    fd = (normal(h0 * (1 + 1e-6), c) - normal(h0 * (1 - 1e-6), c)) / (2e-6 * h0)
    np.testing.assert_allclose(jax.grad(normal)(h0, c), fd, rtol=1e-6)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(thickness=0.0, area=1e-6), r"thickness .*\(in m\)"),
        (dict(thickness=-1e-3, area=1e-6), "thickness"),
        (dict(thickness=1e-3, area=0.0), r"area .*\(in m\^2\)"),
        (dict(thickness=1e-3, area=1e-6, fidelity="exact"), "fidelity"),
    ],
)
def test_bad_input(kwargs, name):
    with pytest.raises(ValueError, match=name):
        layer_stiffness(material=ECOFLEX, **kwargs)
