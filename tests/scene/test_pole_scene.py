"""Seed 000's reduced model: the restoring force against tilt (PoleScene.tangential_force)."""

import equinox as eqx
import jax
import magpylib as magpy
import numpy as np
import pytest

from magdesign.scene import parameters, scene_from_spec, with_parameters
from magdesign.units import MU0, SpecError
from scene_helpers import example


@pytest.mark.parametrize("half", [False, True])
def test_tangential_force_against_magpylib_and_hand_derived_lever(half):
    """-F_t(theta) against the same charge model evaluated with magpylib's plate field and
    the ends' velocities written by hand: tip = c + r_b out, out = (sin, 0, -cos), top =
    tip - L out for a rod of length L (2 r_b: the whole diameter, the default; r_b: to the
    centre), so d tip / d theta = r_b (cos, 0, sin) and d top / d theta = (r_b - L) (cos,
    0, sin). Odd in theta and restoring."""
    scene = scene_from_spec(example("pole_plate"))
    if half:
        scene = with_parameters(scene, {"pole.length": float(scene.ball_radius)})
    p = {key: float(value) for key, value in parameters(scene).items()}
    thetas = np.deg2rad([-50.0, -10.0, 1.0, 10.0, 40.0, 50.0])
    force = np.asarray(eqx.filter_jit(lambda s, t: jax.vmap(s.tangential_force)(t))(scene, thetas))

    plate = magpy.magnet.Cylinder(polarization=(0, 0, p["magnet.remanence"]),
                                  dimension=(2 * p["magnet.radius"], p["magnet.height"]),
                                  position=(0, 0, -p["magnet.height"] / 2))
    r, centre = p["pole.ball_radius"], np.array([0, 0, p["geometry.gap"] + p["pole.ball_radius"]])
    area = np.pi * p["pole.diameter"] ** 2 / 4
    for theta, value in zip(thetas, force):
        out = np.array([np.sin(theta), 0, -np.cos(theta)])
        length, along = p["pole.length"], np.array([np.cos(theta), 0, np.sin(theta)])
        tip = centre + r * out
        top = tip - length * out
        b_tip, b_top = plate.getB(tip), plate.getB(top)
        charge = area * np.dot(b_tip, -out) / p["pole.demagnetizing_factor"]
        # charges -Q at the tip, +Q at the top, each pulled by Q B / mu0
        expected = charge * (-np.dot(b_tip, r * along) + np.dot(b_top, (r - length) * along)) / (MU0 * r)
        np.testing.assert_allclose(value, expected, rtol=1e-9)
    np.testing.assert_allclose(force[:2], -force[[5, 3]], rtol=1e-12)
    assert np.all(force[thetas > 0] < 0)


def test_a_rod_longer_than_the_ball_is_a_spec_error():
    spec = example("pole_plate")
    spec["pole"]["length"] = "5 mm"  # the example's ball is 4 mm across
    with pytest.raises(SpecError, match="pole.length"):
        scene_from_spec(spec)
