"""Spec parsing: every bad input is a one-line SpecError naming the key."""

import copy

import numpy as np
import pytest
from scene_helpers import example

from magdesign.scene import loads_from_spec, outputs, scene_from_spec
from magdesign.units import SpecError


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


# A magnet rides on the part that carries it: on or in a layer, at a dome's apex.
@pytest.mark.parametrize(
    "name, edit, fragment",
    [
        # the 9.06 mm gap on a 4.69 mm layer: the magnet would float 4.37 mm above the silicone
        (
            "spin_valve_matrix",
            lambda s: (s["geometry"].update(gap="9.06 mm"), s["mechanics"].update(thickness="4.69 mm")),
            "floats above the 4.69 mm layer",
        ),
        ("gmr_inductor", lambda s: s["geometry"].update(gap="15.5 mm"), "floats above the 15 mm layer"),
        # an 8 mm dome with a 2 mm wall carries a 1 mm magnet whose face lies from 5 to 8 mm up
        ("dome_hall", lambda s: s["geometry"].update(gap="8.2 mm"), "expected a gap from 5 to 8 mm"),
        ("dome_hall", lambda s: s["geometry"].update(gap="4.9 mm"), "expected a gap from 5 to 8 mm"),
    ],
)
def test_a_magnet_that_misses_its_layer_or_dome_is_refused(name, edit, fragment):
    spec = example(name)
    edit(spec)
    with pytest.raises(SpecError, match="^geometry.gap: ") as error:
        scene_from_spec(spec)
    assert fragment in str(error.value) and "\n" not in str(error.value)


@pytest.mark.parametrize(
    "name, gap, embed",
    [
        ("spin_valve_matrix", "2.5 mm", 3.5e-3 - 2.5e-3),  # 3.5 mm of PDMS, the magnet's face 1 mm into it
        ("gmr_inductor", "15 mm", 0.0),  # the magnet rests on the 15 mm gel
        ("dome_hall", "7.4 mm", 8e-3 - 7.4e-3),  # 0.6 mm below the 8 mm dome's outer apex
        ("dome_hall", "5 mm", 8e-3 - 5e-3),  # hanging under the inner apex (8 - 2 mm): its top face at 6 mm
    ],
)
@pytest.mark.slow
def test_embed_is_the_depth_of_the_magnet_below_the_top_of_its_part(name, gap, embed):
    spec = example(name)
    spec["geometry"]["gap"] = gap
    assert float(outputs(scene_from_spec(spec), loads_from_spec(spec))["embed"]) == pytest.approx(embed, abs=1e-15)
