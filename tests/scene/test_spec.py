"""Spec parsing: every bad input is a one-line SpecError naming the key."""

import copy

import numpy as np
import pytest

from magdesign.scene import loads_from_spec, scene_from_spec
from magdesign.units import SpecError
from scene_helpers import example


def _broken(edit):
    spec = example("film_hall")
    edit(spec)
    return spec


@pytest.mark.parametrize(
    "edit, key, expected",
    [
        (lambda s: s["magnet"].pop("period"), "magnet.period", "missing"),
        (lambda s: s["magnet"].update(period="6"), "magnet.period", "missing unit"),
        (lambda s: s["magnet"].update(period="6 T"), "magnet.period", "expected a quantity in m"),
        (lambda s: s["magnet"].update(colour="red"), "magnet.colour", "unknown key"),
        (lambda s: s["scene"].update(effects=["wobble"]), "scene.effects", "quantisation"),
        (lambda s: s["sensor"].update(preset="XYZ"), "sensor.preset", "'MLX90393'"),
        (lambda s: s.update(extra={}), "[extra]", "unknown table"),
        (lambda s: s["load"].update(normal=["0 N"]), "load.normal", "list of 2"),
    ],
)
def test_bad_input_names_the_key_on_one_line(edit, key, expected):
    spec = _broken(edit)
    with pytest.raises(SpecError) as error:
        scene_from_spec(spec)
        loads_from_spec(spec)
    message = str(error.value)
    assert message.startswith(key) and expected in message and "\n" not in message


def test_design_table_is_ignored_and_fidelity_overrides():
    spec = example("film_hall")
    spec["design"] = {"variables": ["anything"]}
    scene = scene_from_spec(spec, fidelity="bonded")
    assert scene.layer.fidelity == "bonded"
    with pytest.raises(SpecError, match="^fidelity"):
        scene_from_spec(spec, fidelity="reissner")


def test_loads_ramp_with_units():
    spec = example("film_hall")
    spec["load"] = {"normal": ["0 N", "500 mN"], "shear_y": ["0 N", "-1 N"], "points": 6, "duration": "50 ms"}
    loads = loads_from_spec(copy.deepcopy(spec))
    np.testing.assert_allclose(loads.normal, np.linspace(0, 0.5, 6))
    np.testing.assert_allclose(loads.shear[:, 1], np.linspace(0, -1, 6))
    np.testing.assert_allclose(loads.time, np.linspace(0, 0.05, 6))
    assert np.all(loads.shear[:, 0] == 0)


def test_a_scene_and_its_copy_with_new_parameters_share_one_compiled_program():
    """A built scene's float leaves are strongly typed, as with_parameters makes them, so
    a jitted function of the scene is not compiled again for a copy with new values (found
    by a study: weakly typed spec values against strongly typed replacements)."""
    import equinox as eqx
    import jax

    from magdesign.scene import parameters, with_parameters

    scene = scene_from_spec(example("pole_plate"))
    copy = with_parameters(scene, {name: float(value) * 1.01 for name, value in parameters(scene).items()})
    traces = []

    @eqx.filter_jit
    def attraction(s):
        traces.append(1)
        return s.gap * 2.0

    attraction(scene), attraction(copy)
    assert len(traces) == 1
