"""The film-Hall sensor (Yan et al. 2021) in the scene frame: a valid field, the self-decoupling of the ideal film
model, the Eq. 3 read-out, and the example design against its closed form."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.optimize
from scene_helpers import example

from magdesign.design import solve
from magdesign.fields import film_angle
from magdesign.inverse import film_forces
from magdesign.scene import Loads, outputs, parameters, scene_from_spec, simulate, with_parameters
from magdesign.spec.design import problem_from_spec
from magdesign.units import SpecError

REST = Loads(np.zeros(1))  # one unloaded point


@pytest.fixture(scope="module")
def ideal():
    # a pitch other than the period puts the taxels at different field angles
    scene = dataclasses.replace(scene_from_spec(example("film_hall")), effects=())
    return with_parameters(scene, {"sensor.pitch": 2.5e-3})


def _magnitude_and_angle(readings):
    # the film frame's angle: its depth axis is the scene's -z
    return jnp.linalg.norm(readings, axis=-1), film_angle(readings[..., 0], -readings[..., 2])


@pytest.mark.parametrize("periods", [None, 3])
def test_field_is_divergence_and_curl_free_in_the_scene_frame(ideal, periods):
    scene = dataclasses.replace(ideal, periods=periods)
    rng = np.random.default_rng(0)
    points = np.concatenate([rng.uniform(-12e-3, 12e-3, (40, 2)), rng.uniform(-5e-3, 3.4e-3, (40, 1))], -1)
    displacement = jnp.array([0.4e-3, 0.0, -0.2e-3])

    def field(p):
        return scene.source_field(p, displacement)

    jac = np.asarray(jax.jit(jax.vmap(jax.jacfwd(field)))(jnp.asarray(points)))
    scale = 2 * np.pi / 6e-3 * np.linalg.norm(np.asarray(jax.vmap(field)(jnp.asarray(points))), axis=-1)
    curl = np.stack([jac[:, 2, 1] - jac[:, 1, 2], jac[:, 0, 2] - jac[:, 2, 0], jac[:, 1, 0] - jac[:, 0, 1]], -1)
    assert np.max(np.abs(np.trace(jac, axis1=1, axis2=2)) / scale) < 1e-12
    assert np.max(np.linalg.norm(curl, axis=-1) / scale) < 1e-12


def test_scene_field_signs_below_an_infinite_film(ideal):
    """z up: below the film Bx / Bz = -tan(kx) for J = J0 (-sin kx, 0, -cos kx) (magdesign.fields.film's
    pattern with J0 -> -J0), and a background given in the scene frame adds with its own sign."""
    k, h, d, j0 = 2 * np.pi / 6e-3, 3.5e-3, 0.5e-3, 85e-3
    x = np.linspace(-1.4e-3, 1.4e-3, 5)
    points = np.stack([x, 0 * x, 0 * x], -1)
    field = np.asarray(ideal.source_field(jnp.asarray(points), jnp.zeros(3)))
    magnitude = j0 * (1 - np.exp(-k * d)) * np.exp(-k * h)
    np.testing.assert_allclose(field, magnitude * np.stack([np.sin(k * x), 0 * x, -np.cos(k * x)], -1), rtol=1e-13)
    with_background = dataclasses.replace(scene_from_spec(example("film_hall")), effects=())
    spec = example("film_hall")
    spec["scene"] = {"effects": ["background"], "background": ["0 T", "0 T", "-50 uT"]}
    loads = Loads(np.zeros(1))
    plain = simulate(with_background, loads).field
    shifted = simulate(scene_from_spec(spec), loads).field
    np.testing.assert_allclose(shifted - plain, np.broadcast_to([0.0, 0.0, -50e-6], plain.shape), atol=1e-18)
    centre = np.asarray(plain)[0, 4]  # the centre taxel, x = 0: the film's field points down there
    assert centre[2] < 0 and np.linalg.norm(shifted[0, 4]) > np.linalg.norm(centre)


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


FRACTION, SENSITIVITY, J0, D, YOUNGS, AREA = 0.02, 1e-3, 85e-3, 0.5e-3, 83e3, 36e-6


def test_example_design_reaches_its_closed_form():
    """examples/film_hall.toml without effects: e^{-kh} = f fixes k h = ln(1/f); then the
    normal sensitivity k |B|(h) / k_n = J0 (1 - e^{-kd}) f ln(1/f) / (E S) (Hooke layer,
    k_n = E S / h) fixes T."""
    spec = example("film_hall")
    spec["scene"] = {"effects": []}
    result = solve(problem_from_spec(spec)[0])
    kd = -np.log(1 - SENSITIVITY * YOUNGS * AREA / (J0 * FRACTION * np.log(1 / FRACTION)))
    period = 2 * np.pi * D / kd
    assert result.status == "successful"
    assert result.parameters["magnet.period"] == pytest.approx(period, rel=1e-9)
    assert result.parameters["mechanics.thickness"] == pytest.approx(
        np.log(1 / FRACTION) * period / (2 * np.pi), rel=1e-9
    )


def test_example_design_sees_its_background_field():
    """examples/film_hall.toml as written, with the Earth's +50 uT (scene z, up) beside the
    film's downward field at the centre taxel: |B| = A e^{-kh} - b, A = J0 (1 - e^{-kd}), so
    field_fraction = e^{-kh} - b / A and d|B|/dFz = k A e^{-kh} h / (E S). With q = e^{-kh}
    = f + b / A: h = ln(1/q) / k and the sensitivity k A q ln(1/q) / (k E S) = A q ln(1/q) /
    (E S) fixes k (one root, by bisection)."""
    background = 50e-6

    def sensitivity_error(k):
        amplitude = J0 * (1 - np.exp(-k * D))
        q = FRACTION + background / amplitude
        return amplitude * q * np.log(1 / q) / (YOUNGS * AREA) - SENSITIVITY

    k = scipy.optimize.brentq(sensitivity_error, 2 * np.pi / 12e-3, 2 * np.pi / 3e-3, xtol=1e-14, rtol=1e-15)
    q = FRACTION + background / (J0 * (1 - np.exp(-k * D)))
    result = solve(problem_from_spec(example("film_hall"))[0])
    assert result.status == "successful"
    assert result.parameters["magnet.period"] == pytest.approx(2 * np.pi / k, rel=1e-9)
    assert result.parameters["mechanics.thickness"] == pytest.approx(np.log(1 / q) / k, rel=1e-9)


def test_outputs_match_closed_forms(ideal):
    out = outputs(ideal, REST)
    k, h = 2 * np.pi / 6e-3, 3.5e-3
    assert np.isclose(out["field_fraction"], np.exp(-k * h), rtol=1e-14)
    # Yan et al.: |B| >= 0.02 |B|max for h <= ln(50) / k
    at_limit = outputs(with_parameters(ideal, {"mechanics.thickness": np.log(50) / k}), REST)
    assert np.isclose(at_limit["field_fraction"], 0.02, rtol=1e-12)
    # Hooke layer: k_n = E S / h, k_s = G S / h
    area, youngs, nu = 36e-6, 83e3, 0.49
    assert np.isclose(out["normal_compliance"], h / (youngs * area), rtol=1e-12)
    assert np.isclose(out["shear_compliance"], h * 2 * (1 + nu) / (youngs * area), rtol=1e-12)


def test_parameters_are_traceable_and_differentiable(ideal):
    names = parameters(ideal)
    assert {"magnet.period", "mechanics.thickness", "mechanics.youngs_modulus"} <= set(names)

    def fraction(h):
        return outputs(with_parameters(ideal, {"mechanics.thickness": h}), REST)["field_fraction"]

    k = 2 * np.pi / 6e-3
    grad = jax.jit(jax.grad(fraction))(3.5e-3)
    assert np.isclose(grad, -k * np.exp(-k * 3.5e-3), rtol=1e-12)
    batch = jax.vmap(fraction)(jnp.array([2e-3, 3e-3]))
    np.testing.assert_allclose(batch, np.exp(-k * np.array([2e-3, 3e-3])), rtol=1e-12)
    with pytest.raises(SpecError, match="magnet.period"):
        with_parameters(ideal, {"magnet.colour": 1.0})
