"""The skin's saturation_force: the largest press before a chip axis leaves its range, against
a brute-force scan of the simulated readings over a dense grid of forces, its derivative
against a central difference, and the closed form of its secant crossings."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.design import Limit, Problem, Target, Variable, solve
from magdesign.scene import outputs
from magdesign.scene.core import simulate
from magdesign.scene.effects import Saturation
from magdesign.scene.loads import Loads
from magdesign.scene.skin_scene import SATURATION_FORCE_CAP, SkinScene, first_crossings
from magdesign.spec.design import SceneModel
from magdesign.transducers import mlx90393
from magdesign.units import mm, mT, uT

# Two chips on the x axis under a 20 x 20 x 2 mm layer of 20 mT. At rest the outer chip reads
# Bx = -533 uT and Bz = 2101 uT; with these ranges its Bz sits at 0.977 of the range and its
# Bx at 0.935, so that a press decides which axis saturates first.
CHIPS = np.array([[6 * mm, 0.0], [0.0, 0.0]])
LIMIT = np.array([570 * uT, 570 * uT, 2150 * uT])
SHEAR_RATIO = np.array([0.2, 0.0])  # the press's shear over its normal force
FORCES = np.linspace(0.0, 8.0, 801)  # N: the brute-force scan, 10 mN apart


def skin(**changes):
    values = dict(
        thickness=jnp.asarray(2 * mm),
        size=jnp.array([20 * mm, 20 * mm]),
        polarization=jnp.asarray(0.02),
        shear_modulus=jnp.asarray(100e3),
        poisson_ratio=jnp.asarray(0.49),
        sphere_radius=jnp.asarray(2 * mm),
        chips=jnp.asarray(CHIPS),
        depth=jnp.asarray(1 * mm),
        noise=jnp.full(3, 1 * uT),
        hall=mlx90393(),
        effects=(Saturation(jnp.asarray(LIMIT)),),
        map_grid=(1, 1),
        resolution=(20, 20, 4),
    )
    return SkinScene(**(values | changes))


def scanned(scene, contact):
    """(the first force of FORCES' grid at which a simulated reading leaves its range,
    interpolated linearly on that axis between the grid's neighbours (N); the largest
    |reading| / range at each force of the scan)."""
    loads = Loads(jnp.asarray(FORCES), shear=FORCES[:, None] * SHEAR_RATIO, contact=jnp.asarray(contact))
    fractions = np.abs(np.asarray(simulate(scene, loads).chip_field) / LIMIT).reshape(len(FORCES), -1)
    largest = fractions.max(axis=1)
    i = int(np.argmax(largest > 1.0))
    assert i > 0, "the scan's range holds no saturating force"
    axis = int(np.argmax(fractions[i]))
    below, above = fractions[i - 1, axis], fractions[i, axis]
    return FORCES[i - 1] + (1.0 - below) / (above - below) * (FORCES[i] - FORCES[i - 1]), largest


at_point = eqx.filter_jit(lambda scene, contact: scene.saturation_force_at(contact, jnp.asarray(SHEAR_RATIO), 0.5))


def test_the_crossings_closed_form():
    rest = jnp.array([0.5, 0.5, 0.5, -0.9, 1.2, -1.0])
    slope = jnp.array([0.25, -0.5, 0.0, -0.1, -1.0, 1.0])
    # 0.5 + 2 * 0.25 = 1; 0.5 - 3 * 0.5 = -1; never; -0.9 - 1 * 0.1 = -1; out of range at rest (twice)
    expected = [2.0, 3.0, SATURATION_FORCE_CAP, 1.0, 0.0, 0.0]
    np.testing.assert_allclose(first_crossings(rest, slope), expected, rtol=1e-14)


@pytest.mark.slow  # compiles the search through the layer's field: half a minute
@pytest.mark.parametrize("indenter", ["sphere", "flat"])
def test_the_saturating_force_is_the_brute_force_scans(indenter):
    """Pressed at the centre chip with a shear along +x, the outer chip's Bz (the largest
    reading at rest) falls while its Bx grows to the range: the largest |reading| dips before
    it saturates (not monotone), and the first crossing is the Bx axis's. The scan's linear
    interpolation is good to about (10 mN)^2 times the curvature: 1e-5 relative here."""
    scene = skin(indenter=indenter)
    expected, largest = scanned(scene, [0.0, 0.0])
    assert np.min(largest) < largest[0] - 1e-3  # the dip
    np.testing.assert_allclose(float(at_point(scene, jnp.zeros(2))), expected, rtol=1e-5)


@pytest.mark.slow  # two more scans and the output over the map and the sweep's contacts
def test_the_output_is_the_worst_over_the_map_and_the_sweeps_contacts():
    """The map's one point is the chips' box middle (3 mm, 0); the sweep presses at the
    centre: the output is the smaller of the two scans' forces."""
    scene = skin()
    forces = [scanned(scene, contact)[0] for contact in ([3 * mm, 0.0], [0.0, 0.0])]
    assert forces[0] != pytest.approx(forces[1], rel=1e-3)
    loads = Loads(jnp.array([0.0, 0.5]), shear=jnp.array([[0.0, 0.0], [0.1, 0.0]]), contact=jnp.zeros(2))
    got = eqx.filter_jit(lambda s, l: s.saturation_force(l))(scene, loads)
    np.testing.assert_allclose(float(got), min(forces), rtol=1e-5)


@pytest.mark.slow  # compiles the search through the layer's field
def test_a_chip_out_of_range_at_rest_gives_zero_and_a_wide_range_the_cap():
    low = skin(effects=(Saturation(jnp.asarray([570 * uT, 570 * uT, 2000 * uT])),))  # Bz 2101 uT at rest
    assert float(at_point(low, jnp.zeros(2))) == 0.0
    wide = skin(effects=(Saturation(jnp.asarray(LIMIT * 1e3)),))  # a kilonewton moves no reading that far
    assert float(at_point(wide, jnp.zeros(2))) == SATURATION_FORCE_CAP


@pytest.mark.slow  # the derivative through the search's last Newton step
def test_the_derivative_in_the_polarization_is_a_central_differences():
    """The search holds its answer fixed and takes one Newton step on the binding axis: its
    derivative is the implicit function's, which a central difference of the answer checks."""
    scene = skin()

    def force(polarization):
        return eqx.tree_at(lambda s: s.polarization, scene, polarization).saturation_force_at(
            jnp.zeros(2), jnp.asarray(SHEAR_RATIO), 0.5
        )

    # one compiled program (forward mode: the answer and its derivative) for the slope and
    # the central difference's two ends
    jet = jax.jit(lambda p: jax.jvp(force, (p,), (jnp.ones(()),)))
    slope, step = float(jet(jnp.asarray(0.02))[1]), 1e-6
    difference = (float(jet(jnp.asarray(0.02 + step))[0]) - float(jet(jnp.asarray(0.02 - step))[0])) / (2 * step)
    assert slope < 0.0  # more polarization: a larger rest field and response, an earlier saturation
    np.testing.assert_allclose(slope, difference, rtol=1e-5)


@pytest.mark.slow  # compiles a design through the layer's field and the search: minutes
def test_saturation_force_holds_as_a_designs_limit():
    """The readings are J0 times the 20 mT skin's over 20 mT (no background), and so are
    their ranges' fractions c(F): the skin at J0 saturates first where max |c_20(F)| = 20 mT
    / J0. From the scans at 20 mT (the map's point, 3 mm along x, and the sweep's contact,
    the centre), the largest J0 that keeps every press up to 3 N in range is J_3 = 20 mT /
    max_{F <= 3 N} max |c_20(F)|. The normal-force bound falls as 1 / J0: a target reached at
    0.995 J_3 is met, one that needs 1.005 J_3 is not (saturation_force >= 3 N binds)."""
    scene = skin()
    worst = max(np.max(scanned(scene, contact)[1][FORCES <= 3.0]) for contact in ([3 * mm, 0.0], [0.0, 0.0]))
    j3 = 20 * mT / worst
    assert 20 * mT < j3 < 21 * mT
    loads = Loads(jnp.array([0.0, 0.5]), shear=jnp.array([[0.0, 0.0], [0.1, 0.0]]), contact=jnp.zeros(2))
    bound = float(outputs(scene, loads)["force_resolution_normal"])  # at 20 mT
    for fraction in (0.995, 1.005):
        problem = Problem(
            SceneModel(scene, loads),
            [Variable("magnet.polarization", 15 * mT, 25 * mT)],
            targets=[Target("force_resolution_normal", bound * 20 * mT / (fraction * j3))],
            limits=[Limit("saturation_force", lower=3.0)],
        )
        got = solve(problem)
        if fraction < 1.0:
            assert str(got.status) == "successful", got.status
            assert got.parameters["magnet.polarization"] == pytest.approx(0.995 * j3, rel=1e-6)
            assert got.limits["saturation_force"]["achieved"] > 3.0
        else:
            assert str(got.status) in ("limit_violated", "infeasible_target"), got.status
