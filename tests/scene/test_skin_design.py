"""The skin's chips as design parameters: each listed chip's (x, y) and a grid's pitch, read
against magpylib's block at the moved chips, a derivative of the outputs with respect to the
pitch against a central difference, and a design that solves for a pitch."""

import functools

import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest
from scene_helpers import example

from magdesign.design import solve
from magdesign.scene import loads_from_spec, outputs, parameters, scene_from_spec, with_parameters
from magdesign.spec.design import problem_from_spec, solved_spec
from magdesign.spec.table import parameter_unit


def grid_skin(pitch="8 mm", cells=(4, 4, 1)):
    """The example's skin with a 2 x 2 grid of chips at ``pitch`` and one map point."""
    spec = example("skin")
    spec["sensor"].pop("chips")
    spec["sensor"].update(grid=[2, 2], pitch=pitch, map_grid=[1, 1])
    spec["magnet"].update(field="cells", cells=list(cells))
    return spec


def block_field(chips, depth=1e-3):
    """magpylib's field of the example's undeformed layer (a 30 x 30 x 2 mm block of 20 mT
    along z) at chips (S, 2) (m) ``depth`` below the board, plus the example's 50 uT background."""
    block = magpylib.magnet.Cuboid(polarization=(0, 0, 0.02), dimension=(0.03, 0.03, 0.002), position=(0, 0, 0.001))
    points = np.concatenate([np.asarray(chips), np.full((len(chips), 1), -depth)], axis=-1)
    return block.getB(points).reshape(-1, 3) + np.array([0.0, 0.0, 50e-6])


@pytest.mark.slow
def test_each_listed_chip_is_a_parameter_and_a_design_moves_it():
    scene = scene_from_spec(example("skin"))
    names = [f"sensor.chips[{i}][{k}]" for i in range(5) for k in range(2)]
    assert set(names) <= set(parameters(scene)) and "sensor.pitch" not in parameters(scene)
    assert parameter_unit("sensor.chips[3][1]") == "m"
    moved = with_parameters(scene, {"sensor.chips[1][0]": 12e-3, "sensor.chips[3][1]": 7e-3})
    chips = [[0.0, 0.0], [0.012, 0.0], [-0.01, 0.0], [0.0, 0.007], [0.0, -0.01]]
    np.testing.assert_allclose(moved.chip_positions(), chips, atol=1e-15)
    # one compiled program (the readings at rest and their derivative along chip 1's x) for
    # both checks: the readings' operations one by one take longer than compiling them
    reading = jax.jit(
        lambda x, y: jax.jvp(
            lambda xx: with_parameters(scene, {"sensor.chips[1][0]": xx, "sensor.chips[3][1]": y}).readings_at(
                jnp.zeros(5)
            ),
            (x,),
            (jnp.ones(()),),
        )
    )
    readings, _ = reading(jnp.asarray(12e-3), jnp.asarray(7e-3))
    np.testing.assert_allclose(readings, block_field(chips), rtol=1e-9, atol=1e-15)
    # the derivative of a chip's reading along its x against magpylib's central difference
    step = 1e-6
    slope = reading(jnp.asarray(0.01), jnp.asarray(0.01))[1][1]
    ends = [block_field([[0.01 + sign * step, 0.0]])[0] for sign in (1, -1)]
    np.testing.assert_allclose(slope, (ends[0] - ends[1]) / (2 * step), rtol=1e-6, atol=1e-6)
    # a solved chip's position is written back where the spec states it, in its unit
    solved = solved_spec(example("skin"), {"sensor.chips[1][0]": 0.012})
    assert solved["sensor"]["chips"][1] == ["12.0 mm", "0 mm"]


def test_a_grid_is_its_unit_offsets_times_the_pitch_parameter():
    scene = scene_from_spec(grid_skin())
    assert "sensor.pitch" in parameters(scene) and not any(
        name.startswith("sensor.chips") for name in parameters(scene)
    )
    assert float(parameters(scene)["sensor.pitch"]) == pytest.approx(8e-3, rel=1e-15)
    wider = with_parameters(scene, {"sensor.pitch": 11e-3})
    corners = [[-5.5e-3, -5.5e-3], [5.5e-3, -5.5e-3], [-5.5e-3, 5.5e-3], [5.5e-3, 5.5e-3]]
    np.testing.assert_allclose(wider.chip_positions(), corners, atol=1e-15)
    np.testing.assert_allclose(wider.readings_at(jnp.zeros(5)), block_field(corners), rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(wider.map_points(), [[0.0, 0.0]], atol=1e-15)


# The outputs the pitch's tests read, and the cells they take: 2 x 2 x 1 rigid cells, the
# coarsest the scene builds: a derivative's agreement with a central difference, and a
# design's reaching a target the same model sets, hold at any cells.
NAMES = ("localisation_median", "force_resolution_normal")
PITCH_CELLS = (2, 2, 1)


@functools.cache
def pitch_jet():
    """One compiled program for the pitch's tests: pitch (m) -> (the outputs NAMES (m, N),
    their derivative in the pitch (forward mode, as a design takes its derivatives:
    magdesign.design's jets)) of the 2 x 2 grid skin on PITCH_CELLS."""
    spec = grid_skin(cells=PITCH_CELLS)
    scene, loads = scene_from_spec(spec), loads_from_spec(spec)

    def at(pitch):
        got = outputs(with_parameters(scene, {"sensor.pitch": pitch}), loads)
        return jnp.stack([got[name] for name in NAMES])

    jet = jax.jit(lambda p: jax.jvp(at, (p,), (jnp.ones(()),)))
    return lambda pitch: tuple(np.asarray(part) for part in jet(jnp.asarray(pitch)))


@pytest.mark.slow  # the derivative of the outputs' Jacobians through the layer: a minute to compile
def test_the_outputs_derivative_in_the_pitch_matches_a_central_difference():
    """Forward mode, as a design takes its derivatives (magdesign.design's jets): one
    compiled program gives the outputs and their derivative, at the pitch and at the
    central difference's two ends."""
    pitch, step = 8e-3, 1e-6
    slope = pitch_jet()(pitch)[1]
    ends = [pitch_jet()(pitch + sign * step)[0] for sign in (1, -1)]
    difference = (ends[0] - ends[1]) / (2 * step)
    assert np.all(np.isfinite(slope)) and np.all(np.abs(slope) > 0)
    np.testing.assert_allclose(slope, difference, rtol=1e-5)


@pytest.mark.slow  # compiles the outputs' Jacobians and their derivatives through the layer
def test_a_design_finds_the_pitch_that_localises_to_a_target():
    """The localisation at a 10 mm pitch, from a simulation (the program of the test
    above), is the target of a design that starts at 8 mm: the solve reaches it, at 10 mm
    (the bound falls steadily with the pitch between 6 and 12 mm in this skin: checked at
    the ends)."""
    start = grid_skin(cells=PITCH_CELLS)
    median = NAMES.index("localisation_median")
    target, ends = float(pitch_jet()(10e-3)[0][median]), [float(pitch_jet()(p)[0][median]) for p in (6e-3, 12e-3)]
    assert ends[0] > target > ends[1]
    start["design"] = {
        "variables": {"sensor.pitch": {"lower": "6 mm", "upper": "12 mm"}},
        "targets": {"localisation_median": f"{target!r} m"},
    }
    problem, _ = problem_from_spec(start)
    result = solve(problem)
    assert str(result.status) == "successful", result.status
    assert float(result.parameters["sensor.pitch"]) == pytest.approx(10e-3, rel=1e-6)
