"""The magnetic-suspension sensor: the reduced model's restoring force against the same charge model
evaluated with magpylib, and the method-of-moments level's fields and forces against
magpylib's cuboids and the Kelvin force and torque on its cells (PoleScene)."""

import equinox as eqx
import jax
import magpylib as magpy
import numpy as np
import pytest
from scene_helpers import example
from scipy.spatial.transform import Rotation

from magdesign.fields import soft
from magdesign.scene import parameters, scene_from_spec, with_parameters
from magdesign.units import MU0, SpecError


def reduced_spec():
    """The example at the reduced (charge) level."""
    spec = example("pole_plate")
    spec["pole"] = {k: v for k, v in spec["pole"].items() if k not in ("permeability", "cells")}
    spec["pole"].update(fidelity="reduced", demagnetizing_factor=0.1)
    return spec


@pytest.mark.parametrize("half", [False, True])
@pytest.mark.slow
def test_tangential_force_against_magpylib_and_hand_derived_lever(half):
    """-F_t(theta) against the same charge model evaluated with magpylib's plate field and
    the ends' velocities written by hand: tip = c + r_b out, out = (sin, 0, -cos), top =
    tip - L out for a rod of length L (2 r_b: the whole diameter, the default; r_b: to the
    centre), so d tip / d theta = r_b (cos, 0, sin) and d top / d theta = (r_b - L) (cos,
    0, sin). Odd in theta and restoring."""
    scene = scene_from_spec(reduced_spec())
    if half:
        scene = with_parameters(scene, {"pole.length": float(scene.ball_radius)})
    p = {key: float(value) for key, value in parameters(scene).items()}
    thetas = np.deg2rad([-50.0, -10.0, 1.0, 10.0, 40.0, 50.0])
    force = np.asarray(eqx.filter_jit(lambda s, t: jax.vmap(s.tangential_force)(t))(scene, thetas))

    plate = magpy.magnet.Cylinder(
        polarization=(0, 0, p["magnet.remanence"]),
        dimension=(2 * p["magnet.radius"], p["magnet.height"]),
        position=(0, 0, -p["magnet.height"] / 2),
    )
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


def _plate(p):
    return magpy.magnet.Cylinder(
        polarization=(0, 0, p["magnet.remanence"]),
        dimension=(2 * p["magnet.radius"], p["magnet.height"]),
        position=(0, 0, -p["magnet.height"] / 2),
    )


field = eqx.filter_jit(lambda scene, points, displacement: scene.source_field(points, displacement))
# The moments tests share their programs (one compile each for the 8-cell scene): the
# tilt forces at four tilts, the outputs (the attraction among them) and the field at
# three points.
tilt_forces = eqx.filter_jit(lambda s, t: jax.vmap(s.tangential_force)(t))
moments_outputs = eqx.filter_jit(lambda s: s.outputs(None))
FIELD_POINTS = np.array([[0.5e-3, 0.0, 0.1e-3], [-0.7e-3, 0.2e-3, 0.3e-3], [1.5e-3, -0.4e-3, 0.2e-3]])


def _moments_scene(cells=8):
    spec = example("pole_plate")
    spec["pole"]["cells"] = cells
    return scene_from_spec(spec)


def _rod_in_magpylib(scene, theta):
    """The rod's cells as magpylib cuboids at their world poses, magnetised as the scene's
    solve says, and the rod's centre, rotation, cells and their magnetisation (A/m)."""
    rod = scene.rod
    centre, turn = (np.asarray(v) for v in scene._rod_pose(theta, np.zeros(3)))
    magnetization = np.asarray(soft.magnetization(rod, scene._rod_external(theta, np.zeros(3))))
    orientation = Rotation.from_matrix(turn)
    cells = [
        magpy.magnet.Cuboid(
            polarization=MU0 * m, dimension=np.asarray(rod.cell), position=centre + turn @ q, orientation=orientation
        )
        for q, m in zip(np.asarray(rod.centres), magnetization)
    ]
    return magpy.Collection(*cells), centre, turn, np.asarray(rod.centres), magnetization


@pytest.mark.slow
def test_moments_field_against_magpylib_cuboids():
    """The scene's field (plate + the rod's cells, at tilt 10 deg) against magpylib's
    cylinder and cuboids placed at the same poses with the same magnetisation: checks the
    cells' kernel, the rod's pose and the frame turns."""
    scene = _moments_scene()
    p = {key: float(value) for key, value in parameters(scene).items()}
    theta = np.deg2rad(10.0)
    cells, *_ = _rod_in_magpylib(scene, theta)
    points = FIELD_POINTS
    displacement = scene.tip(theta) - scene.tip(0.0)
    value = np.asarray(field(scene, points, displacement))
    expected = _plate(p).getB(points) + cells.getB(points)
    np.testing.assert_allclose(value, expected, rtol=1e-9, atol=1e-12)


@pytest.mark.slow
def test_moments_coenergy_gradient_is_the_kelvin_force_and_torque():
    """dW'/dtheta (the scene's tangential force times r_b) against the torque about the
    ball's centre of the plate's forces (m . grad) B and torques m x B on the solved cells,
    with magpylib's plate field and its central differences; and the attraction against
    the vertical force. Holds because equal cells make the moments system symmetric."""
    scene = _moments_scene()
    p = {key: float(value) for key, value in parameters(scene).items()}
    plate = _plate(p)
    theta = np.deg2rad(15.0)
    _, centre, turn, local, magnetization = _rod_in_magpylib(scene, theta)
    volume = float(scene.rod.cell_volume)
    positions = centre + local @ turn.T
    moments = volume * magnetization @ turn.T  # A m^2, world frame
    step = 1e-7
    gradient = np.stack(
        [(plate.getB(positions + step * e) - plate.getB(positions - step * e)) / (2 * step) for e in np.eye(3)], axis=1
    )  # [cell, d/dx_k, B_j]
    forces = np.einsum("ck,ckj->cj", moments, gradient)  # (m . grad) B, curl-free B
    ball = np.array([0.0, 0.0, p["geometry.gap"] + p["pole.ball_radius"]])
    torque = np.sum(np.cross(positions - ball, forces) + np.cross(moments, plate.getB(positions)), axis=0)
    # the force at theta among four tilts: the program of the outputs test below
    force_t = float(tilt_forces(scene, np.array([theta, -theta, -0.3, 0.3]))[0])
    # a tilt theta turns the ball about -y (its bottom moves to +x): dW'/dtheta = -torque_y
    np.testing.assert_allclose(force_t * p["pole.ball_radius"], -torque[1], rtol=1e-5)
    _, _, turn0, local0, m0 = _rod_in_magpylib(scene, 0.0)
    centre0 = np.asarray(scene._rod_pose(0.0, np.zeros(3))[0])
    pos0, mom0 = centre0 + local0 @ turn0.T, volume * m0 @ turn0.T
    fz = sum(
        np.dot(m, (plate.getB(x + step * np.eye(3)[2]) - plate.getB(x - step * np.eye(3)[2])) / (2 * step))
        for x, m in zip(pos0, mom0)
    )
    np.testing.assert_allclose(float(moments_outputs(scene)["attraction"]), -fz, rtol=1e-5)


@pytest.mark.slow
def test_moments_outputs_restore_and_their_differences_hold():
    """The spring coefficient and the field sensitivity (five-point differences of W' and
    of the chain's field) against central differences of the exact force and of the GMR's
    field over a smaller step, and the force odd in theta and restoring."""
    scene = _moments_scene()
    h = 4e-4
    f = np.asarray(tilt_forces(scene, np.array([-h, h, -0.3, 0.3])))
    out = {k: float(v) for k, v in moments_outputs(scene).items()}
    np.testing.assert_allclose(out["spring_coefficient"], -(f[1] - f[0]) / (2 * h), rtol=1e-6)
    # the GMR's field among the three points of the field test's program
    points = np.concatenate([scene.sensor_poses()[0], FIELD_POINTS[1:]])
    b = [np.asarray(field(scene, points, scene.tip(t) - scene.tip(0.0)))[0, 0] for t in (-h, h)]
    np.testing.assert_allclose(out["field_sensitivity"], (b[1] - b[0]) / (2 * h), rtol=1e-5)
    np.testing.assert_allclose(f[2], -f[3], rtol=1e-10)
    assert f[3] < 0 < out["spring_coefficient"] and out["attraction"] > 0


def test_moments_spec_errors_name_the_key():
    spec = example("pole_plate")
    spec["pole"]["demagnetizing_factor"] = 0.1  # the reduced level's only
    with pytest.raises(SpecError, match="demagnetizing_factor"):
        scene_from_spec(spec)
    spec = example("pole_plate")
    spec["pole"]["permeability"] = -3
    with pytest.raises(SpecError, match="pole.permeability"):
        scene_from_spec(spec)
    spec = example("pole_plate")
    spec["pole"]["cells"] = 200  # 200 x 60 x 60 cells: more than a dense solve holds
    with pytest.raises(SpecError, match="pole.cells"):
        scene_from_spec(spec)


@pytest.mark.slow
def test_a_saturating_rod():
    """[pole] saturation: the rod's cells stay below J_s where the linear solve passes it,
    the key is a design parameter, and bad values name the key."""
    spec = example("pole_plate")
    linear = scene_from_spec(spec)
    spec["pole"]["saturation"] = "0.05 T"
    scene = scene_from_spec(spec)
    assert "pole.saturation" in scene.parameter_paths and "pole.saturation" not in linear.parameter_paths
    peaks = [
        MU0 * float(np.linalg.norm(soft.magnetization(s.rod, s._rod_external(0.0, np.zeros(3))), axis=-1).max())
        for s in (linear, scene)
    ]
    assert peaks[0] > 0.1 and peaks[1] < 0.05, peaks
    for value, match in (("0 T", "pole.saturation"), ("1 mm", "pole.saturation")):
        spec["pole"]["saturation"] = value
        with pytest.raises(SpecError, match=match):
            scene_from_spec(spec)
    spec["pole"]["saturation"] = "0.8 T"
    spec["pole"]["permeability"] = 1
    with pytest.raises(SpecError, match="pole.saturation"):
        scene_from_spec(spec)
