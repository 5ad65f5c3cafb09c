"""Every output of every example scene names an SI unit the spec parser reads."""

import jax
import pytest
from scene_helpers import EXAMPLES, example

from magdesign.scene import loads_from_spec, outputs, scene_from_spec
from magdesign.units import parse


@pytest.mark.parametrize("name", sorted(path.stem for path in EXAMPLES.glob("*.toml")))
def test_every_output_has_a_parsable_unit(name):
    spec = example(name)
    scene = scene_from_spec(spec)
    names = jax.eval_shape(outputs, scene, loads_from_spec(spec))
    assert set(names) == set(scene.output_units)
    for output, unit in scene.output_units.items():
        assert parse(f"1 {unit}", unit, key="x") == 1.0, output
