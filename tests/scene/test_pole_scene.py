"""Seed 000's reduced model: the restoring force against tilt (PoleScene.tangential_force)."""

import equinox as eqx
import jax
import magpylib as magpy
import numpy as np

from magdesign.scene import parameters, scene_from_spec
from magdesign.units import MU0
from scene_helpers import example


def test_tangential_force_against_magpylib_and_hand_derived_lever():
    """-F_t(theta) against the same charge model evaluated with magpylib's plate field and
    the ends' velocities written by hand: tip = c + r_b (sin, 0, -cos), top = 2 c - tip, so
    d tip / d theta = r_b (cos, 0, sin) = -d top / d theta. Odd in theta and restoring."""
    scene = scene_from_spec(example("pole_plate"))
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
        tip, top = centre + r * out, centre - r * out
        velocity = r * np.array([np.cos(theta), 0, np.sin(theta)])
        b_tip, b_top = plate.getB(tip), plate.getB(top)
        charge = area * np.dot(b_tip, -out) / p["pole.demagnetizing_factor"]
        expected = -charge * np.dot(b_tip + b_top, velocity) / (MU0 * r)
        np.testing.assert_allclose(value, expected, rtol=1e-9)
    np.testing.assert_allclose(force[:2], -force[[5, 3]], rtol=1e-12)
    assert np.all(force[thetas > 0] < 0)
