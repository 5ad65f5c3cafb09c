"""One chain: every example design, solved, then built and simulated, measures on the
simulation exactly what the solve reported, for every target and limit; with the
examples' own effects and with more effects switched on.

The measurements below are written from the simulation's arrays (displacement, field in
each chip's frame) by the output definitions of docs/outputs.md, not by the scenes' code.
"""

import copy
from pathlib import Path

import jax
import numpy as np
import pytest

from magdesign.design import solve
from magdesign.scene import Loads, loads_from_spec, simulate, with_parameters
from magdesign.spec.design import load_spec, problem_from_spec

EXAMPLES = Path(__file__).parents[2] / "examples"
DESIGNS = sorted(path.stem for path in EXAMPLES.glob("*.toml") if "[design" in path.read_text())
RTOL = 1e-9
# A derivative at rest measured by a central difference of two simulations (N).
FORCE_STEP = 1e-3

# Effects switched on beside each example's own, with values that move every output.
MORE_EFFECTS = {
    "temperature_drift": {"temperature_change": "-40 K"},
    "background": {"background": ["20 uT", "-10 uT", "50 uT"]},
    "placement": {"placement": ["60 um", "-40 um", "0 um"]},
    "chip_tilt": {"tilt": ["2 deg", "-1 deg", "3 deg"]},
}


def _with_more_effects(spec):
    spec = copy.deepcopy(spec)
    scene = spec.setdefault("scene", {})
    names = scene.setdefault("effects", [])
    for name, options in MORE_EFFECTS.items():
        # the on-axis field level holds on the axis only: no placement there
        if name not in names and not (name == "placement" and spec["magnet"].get("fidelity") == "axis"):
            names.append(name)
            scene.update(options)
    return spec


def _magnet_measures(sim, parameters, scene):
    normal = np.asarray(sim.loads.normal)
    top = int(np.argmax(normal))
    press = normal[top] - normal[0]
    uz = np.asarray(sim.displacement)[:, 2]
    chip = np.asarray(sim.chip_field)
    gap = parameters.get("geometry.gap", float(scene.gap))
    mechanics = scene.mechanics
    thickness = parameters.get("mechanics.thickness", float(mechanics.thickness))
    height = parameters.get("magnet.height", float(scene.height))
    if hasattr(mechanics, "outer_radius"):  # a dome bottoms out at its inner height
        room = parameters.get("mechanics.outer_radius", float(mechanics.outer_radius)) - thickness
        summit = room + thickness  # the dome's outer apex
        floor = room  # the inner apex: below it the cavity
    else:  # a layer when pressed to nothing
        room = summit = thickness  # its top face
        floor = 0.0  # solid down to the sensor plane
    ideal = chip if scene.reading_unit == "T" else np.asarray(scene.transducer(sim.chip_field))[..., None]
    return {
        "travel_fraction": np.max(-uz) / room,
        "embed": summit - gap,
        "reach": gap + height - floor,
        "saturation_ratio": np.max(np.abs(ideal) / _chip_range(scene)),
        "compliance": (uz[0] - uz[top]) / press,
        "closest_gap": gap + uz.min(),
        "field_rest": chip[0, 0, 2],
        "field_closest": chip[top, 0, 2],
        "sensitivity": (chip[top, 0, 2] - chip[0, 0, 2]) / press,
        "field_max": np.abs(chip).max(),
        "inplane_field_max": np.abs(chip[..., 0]).max(),
        "inplane_field_min": chip[..., 0].min(),
        "outer_radius": parameters.get("mechanics.outer_radius"),
        "wall_fraction": thickness
        / parameters.get("mechanics.outer_radius", float(getattr(mechanics, "outer_radius", np.nan))),
    }


def _chip_range(scene):
    """The range the readings are judged against: the saturation effect's limit, else a
    Hall chip's full scale (its preset's)."""
    listed = [e.limit for e in scene.effects if e.name == "saturation"]
    return np.asarray(listed[0] if listed else getattr(scene, "hall", getattr(scene, "transducer", None)).full_scale)


def _film_measures(sim, parameters, scene, simulate_at):
    rows, cols = scene.grid
    centre = (rows // 2) * cols + cols // 2
    period = parameters.get("magnet.period", float(scene.period))
    k = 2 * np.pi / period
    # |B| of an infinite film at its own face: J0 (1 - e^{-kd}) (magdesign.fields.film), J0 drifted
    drift = [e for e in scene.effects if e.name == "temperature_drift"]
    j0 = float(scene.magnetization) * (1 + float(drift[0].coefficient * drift[0].temperature_change) if drift else 1.0)
    face = j0 * (1 - np.exp(-k * float(scene.film_thickness)))
    around_rest = np.linalg.norm(
        np.asarray(simulate_at(Loads(np.array([-FORCE_STEP, 0.0, FORCE_STEP]))).field)[:, centre], axis=-1
    )
    return {
        "field_fraction": around_rest[1] / face,
        "normal_sensitivity": (around_rest[2] - around_rest[0]) / (2 * FORCE_STEP),
        "shear_phase_max": k * np.abs(np.asarray(sim.displacement)[:, 0]).max(),
        "saturation_ratio": np.max(np.abs(np.asarray(sim.chip_field)) / _chip_range(scene)),
    }


def _check_agreement(spec):
    problem, scene = problem_from_spec(spec)
    result = solve(problem)
    assert result.status == "successful", result.table()
    solved = with_parameters(scene, result.parameters)
    key = jax.random.key(1)
    sim = simulate(solved, loads_from_spec(spec), key=key)
    if hasattr(scene, "grid"):
        measured = _film_measures(sim, result.parameters, scene, lambda loads: simulate(solved, loads, key=key))
    else:
        measured = _magnet_measures(sim, result.parameters, scene)
    rtol = {"normal_sensitivity": 1e-6}  # a central difference
    for name, target in result.targets.items():
        assert target["achieved"] == pytest.approx(measured[name], rel=rtol.get(name, RTOL)), name
    for name, limit in result.limits.items():
        assert limit["achieved"] == pytest.approx(measured[name], rel=RTOL), name
    for name in problem.report:
        if measured.get(name) is not None:
            assert result.outputs[name] == pytest.approx(measured[name], rel=RTOL), name
    return result


@pytest.mark.parametrize("name", DESIGNS)
def test_solve_and_simulate_agree(name):
    _check_agreement(load_spec(EXAMPLES / f"{name}.toml"))


@pytest.mark.parametrize("name", ["dome_hall", "film_hall", "spin_valve_matrix"])
@pytest.mark.slow
def test_solve_and_simulate_agree_with_effects_on(name):
    spec = load_spec(EXAMPLES / f"{name}.toml")
    plain = solve(problem_from_spec(spec)[0])
    more = _check_agreement(_with_more_effects(spec))
    # the effects change the design: a solve that ignored them would give the same answer
    moved = [abs(more.parameters[n] / plain.parameters[n] - 1) for n in plain.parameters]
    assert max(moved) > 1e-4
