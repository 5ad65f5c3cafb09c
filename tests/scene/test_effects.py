"""Effects: an effect not listed is not in the traced program (jax.make_jaxpr)."""

import dataclasses
from collections import Counter

import jax
import numpy as np
import pytest
from scene_helpers import equations, example

from magdesign.scene import EFFECT_NAMES, Loads, scene_from_spec
from magdesign.scene.core import chain

LOADS = Loads(np.linspace(0.0, 1.0, 4), shear=np.array([0.1, 0.0]))
RANDOM = {"random_bits", "random_wrap", "random_seed", "threefry2x32", "random_unwrap"}


def _scene(names):
    spec = example("film_hall")
    spec["scene"] = {"effects": list(names), "quadrature": 2}
    return scene_from_spec(spec)


def _primitives(names):
    scene = _scene(names)
    key = jax.random.key(0) if "noise" in names else None

    def run(scene):
        return chain(scene, scene.displacement(LOADS)[0], time=LOADS.time, key=key).readings

    jaxpr = jax.make_jaxpr(run)(scene)
    return Counter(eqn.primitive.name for eqn in equations(jaxpr)), jaxpr


def test_no_random_numbers_without_noise():
    plain, _ = _primitives([n for n in EFFECT_NAMES if n != "noise"])
    noisy, _ = _primitives(["noise"])
    assert not RANDOM & set(plain)
    assert RANDOM & set(noisy)


def test_no_quadrature_without_area_averaging():
    sizes = {}
    for names in ([], ["area_averaging"]):
        _, jaxpr = _primitives(names)
        sizes[bool(names)] = max(v.aval.size for eqn in equations(jaxpr) for v in eqn.outvars)
    # 4 loads x 9 taxels x 3 components without; x 4 quadrature nodes (2 x 2) with
    assert sizes[False] == 4 * 9 * 3
    assert sizes[True] == 4 * 9 * 4 * 3


def test_each_effect_adds_only_its_own_operations():
    base, _ = _primitives([])
    added = {}
    for name in EFFECT_NAMES:
        counts, _ = _primitives([name])
        assert counts - base, f"{name} adds no operations"
        assert not base - counts, f"{name} removes operations"
        added[name] = counts - base
    everything, _ = _primitives(EFFECT_NAMES)
    # area averaging multiplies the field kernel's work but not its equation count,
    # so the equations of all effects together are the base plus each effect's own
    expected = base + sum(added.values(), Counter())
    assert sum(everything.values()) == pytest.approx(sum(expected.values()), rel=0.1)


def test_noise_needs_a_key():
    scene = _scene(["noise"])
    with pytest.raises(ValueError, match="key"):
        chain(scene, scene.displacement(LOADS)[0], time=LOADS.time)


def test_effects_are_applied_in_chain_order():
    ideal = dataclasses.replace(_scene([]), effects=())
    ordered = _scene(["quantisation", "background", "saturation"])
    assert [e.name for e in ordered.effects] == ["background", "saturation", "quantisation"]
    readings = chain(ordered, ordered.displacement(LOADS)[0], time=LOADS.time).readings
    ideal_readings = chain(ideal, ideal.displacement(LOADS)[0], time=LOADS.time).readings
    lsb = ordered.effects[2].lsb
    # background (50 uT on z) then rounding to the LSB: within half an LSB of the truth
    np.testing.assert_allclose(readings[..., 2], ideal_readings[..., 2] + 50e-6, atol=float(lsb[2]) / 2 + 1e-15)
    np.testing.assert_allclose(readings / lsb, np.round(readings / lsb), atol=1e-9)
