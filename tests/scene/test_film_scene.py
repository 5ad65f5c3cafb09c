"""Seed 004: self-decoupling of the ideal film model and the Eq. 3 read-out."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.fields import film_angle
from magdesign.inverse import film_forces
from magdesign.scene import Loads, outputs, parameters, scene_from_spec, simulate, with_parameters
from magdesign.units import SpecError
from scene_helpers import example


@pytest.fixture(scope="module")
def ideal():
    # a pitch other than the period puts the taxels at different field angles
    scene = dataclasses.replace(scene_from_spec(example("film_hall")), effects=())
    return with_parameters(scene, {"sensor.pitch": 2.5e-3})


def _magnitude_and_angle(readings):
    return jnp.linalg.norm(readings, axis=-1), film_angle(readings[..., 0], readings[..., 2])


def test_normal_changes_magnitude_only_and_shear_angle_only(ideal):
    n = 6
    normal = simulate(ideal, Loads(np.linspace(0.0, 1.0, n))).readings
    shear = simulate(ideal, Loads(np.zeros(n), shear=np.stack([np.linspace(0, 0.3, n), np.zeros(n)], -1))).readings
    magnitude_n, angle_n = _magnitude_and_angle(normal)
    magnitude_s, angle_s = _magnitude_and_angle(shear)
    assert np.ptp(np.asarray(magnitude_n), axis=0).min() > 1e-4  # |B| changes (T)
    np.testing.assert_allclose(angle_n, np.broadcast_to(angle_n[:1], angle_n.shape), rtol=0, atol=1e-12)
    assert np.ptp(np.asarray(angle_s), axis=0).min() > 0.1  # angle changes (rad)
    np.testing.assert_allclose(magnitude_s / magnitude_s[:1], np.ones(magnitude_s.shape), rtol=0, atol=1e-12)


def test_eq3_readout_recovers_forces(ideal):
    fz, fx = np.linspace(0.0, 1.0, 5), np.linspace(0.0, 0.25, 5)
    loads = Loads(fz, shear=np.stack([fx, np.zeros(5)], -1))
    readings = simulate(ideal, loads).readings[:, 5]  # a taxel off the centre
    fz_hat, fx_hat = film_forces(ideal, readings[0], readings)
    np.testing.assert_allclose(fz_hat, fz, rtol=0, atol=1e-12)
    np.testing.assert_allclose(fx_hat, fx, rtol=0, atol=1e-12)


def test_outputs_match_closed_forms(ideal):
    out = outputs(ideal)
    k, h = 2 * np.pi / 6e-3, 3.5e-3
    assert np.isclose(out["field_fraction"], np.exp(-k * h), rtol=1e-14)
    # seed 004: |B| >= 0.02 |B|max for h <= ln(50) / k
    at_limit = outputs(with_parameters(ideal, {"mechanics.thickness": np.log(50) / k}))
    assert np.isclose(at_limit["field_fraction"], 0.02, rtol=1e-12)
    # Hooke layer: k_n = E S / h, k_s = G S / h
    area, youngs, nu = 36e-6, 83e3, 0.49
    assert np.isclose(out["normal_compliance"], h / (youngs * area), rtol=1e-12)
    assert np.isclose(out["shear_compliance"], h * 2 * (1 + nu) / (youngs * area), rtol=1e-12)


def test_parameters_are_traceable_and_differentiable(ideal):
    names = parameters(ideal)
    assert {"magnet.period", "mechanics.thickness", "mechanics.youngs_modulus"} <= set(names)

    def fraction(h):
        return outputs(with_parameters(ideal, {"mechanics.thickness": h}))["field_fraction"]

    k = 2 * np.pi / 6e-3
    grad = jax.jit(jax.grad(fraction))(3.5e-3)
    assert np.isclose(grad, -k * np.exp(-k * 3.5e-3), rtol=1e-12)
    batch = jax.vmap(fraction)(jnp.array([2e-3, 3e-3]))
    np.testing.assert_allclose(batch, np.exp(-k * np.array([2e-3, 3e-3])), rtol=1e-12)
    with pytest.raises(SpecError, match="magnet.period"):
        with_parameters(ideal, {"magnet.colour": 1.0})
