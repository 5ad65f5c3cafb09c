"""A skin whose layer is neo-Hookean: the press from the finite-strain layer
(magdesign.mechanics.finite_layer), the shear from the linear layer, superposed.

References: the linear skin (whose layer test_skin_layer.py checks against closed forms
and an independent finite-element model) at a small strain; at a skin's load the
finite-strain layer's own departure, measured in tests/mechanics/test_finite_layer.py.
"""

import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scene_helpers import example

from magdesign.scene import MECHANICS_CONVERGED, loads_from_spec, scene_from_spec, simulate
from magdesign.scene.core import simulation_table
from magdesign.scene.skin_scene import SkinScene
from magdesign.spec.checks import PlausibilityWarning
from magdesign.transducers import mlx90393
from magdesign.units import SpecError, mm, uT

MU, K = 100e3, 100e6  # Pa
NU = (3 * K - 2 * MU) / (2 * (3 * K + MU))  # 0.4995


def neo_hookean_spec(**mechanics):
    spec = example("skin")
    spec["mechanics"].pop("poisson_ratio")
    spec["mechanics"].update(material="neo_hookean", bulk_modulus="100 MPa", **mechanics)
    spec["magnet"].update(field="cells", cells=[8, 8, 2])
    return spec


@pytest.mark.parametrize(
    "edit, key, expected",
    [
        (lambda s: s["mechanics"].update(poisson_ratio=0.49), "mechanics.poisson_ratio", "takes bulk_modulus"),
        (lambda s: s["mechanics"].update(material="linear", poisson_ratio=0.49), "mechanics.bulk_modulus", "linear"),
        (lambda s: s["mechanics"].pop("bulk_modulus"), "mechanics.bulk_modulus", "missing"),
        (lambda s: s["indenter"].update(shape="flat"), "indenter.shape", "sphere only"),
        (lambda s: [s["magnet"].pop(k) for k in ("field", "cells")], "mechanics.material", "magnet.field"),
        (lambda s: s["mechanics"].update(material="mooney_rivlin"), "mechanics.material", "'neo_hookean'"),
    ],
)
def test_a_neo_hookean_skins_bad_input_names_the_key(edit, key, expected):
    spec = neo_hookean_spec()
    edit(spec)
    with pytest.raises(SpecError) as error:
        scene_from_spec(spec)
    message = str(error.value)
    assert message.startswith(key) and expected in message and "\n" not in message, message


def test_a_neo_hookean_skin_builds_and_warns_only_of_its_linear_shear():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = scene_from_spec(neo_hookean_spec())
    assert scene.material == "neo_hookean" and float(scene.bulk_modulus) == K
    np.testing.assert_allclose(float(scene.poisson_ratio), NU, rtol=1e-15)
    # the example's 0.2 N press (a / R = 0.46) is the finite-strain layer's: no warning says the
    # layer is linear under it. Its 0.05 N shear, linear and superposed, moves the patch's centre
    # 3 (2 - nu) F_t / (16 G a) over Hertz's a = 0.909 mm: a strain of 0.17, which warns
    strained = [
        str(w.message) for w in caught if w.category is PlausibilityWarning and "strain under" in str(w.message)
    ]
    assert len(strained) == 1 and strained[0].startswith("load.shear_x: at 0.2 N (shear (0.05, 0) N) the shear's own")
    assert "is 0.17 " in strained[0] and "mechanics.material" in strained[0]
    spec = neo_hookean_spec()
    spec["load"]["shear_x"] = ["0 N", "0.02 N"]  # a strain of 0.068
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene_from_spec(spec)


def _skin(**changes):
    chips = np.array([[0.0, 0.0], [4 * mm, 0.0], [-4 * mm, 0.0], [0.0, 4 * mm], [0.0, -4 * mm]])
    values = dict(
        thickness=jnp.asarray(2 * mm),
        size=jnp.array([16 * mm, 16 * mm]),
        polarization=jnp.asarray(0.02),
        shear_modulus=jnp.asarray(MU),
        poisson_ratio=jnp.asarray(NU),
        sphere_radius=jnp.asarray(2 * mm),
        chips=jnp.asarray(chips),
        depth=jnp.asarray(1 * mm),
        noise=jnp.full(3, 1 * uT),
        hall=mlx90393(),
        effects=(),
        field="cells",
        cells=(32, 32, 8),
        map_grid=(2, 2),
    )
    return SkinScene(**(values | changes))


@pytest.mark.slow
def test_a_neo_hookean_skin_reads_as_the_linear_one_at_small_strain_and_deeper_at_a_skins_load():
    """Expected before running: at a small strain (a / R = 0.018, a 40 mm sphere pressing
    5 mN, a / h = 0.36) the two layers' displacements agree to the finite-strain layer's
    discretisation and the Hertz pressure's misfit on a layer (about 1-2 % of the peak near
    the contact, tests/mechanics/test_finite_layer.py), and so do the chips' changes. At the
    example's press (0.2 N on a 2 mm sphere, a / R = 0.46) the finite-strain layer goes 3.4 %
    deeper at the centre than its own linearisation, and the sphere's own contact (not
    Hertz's pressure at Hertz's radius, 3.6 % short at the centre at a / h = 0.5) deeper
    still: the chip under the contact sees a larger change of Bz."""
    contact = jnp.array([1e-3, 0.5e-3])
    results = {}
    for radius, force in ((40 * mm, 0.005), (2 * mm, 0.2)):
        linear = _skin(sphere_radius=jnp.asarray(radius))
        neo = _skin(sphere_radius=jnp.asarray(radius), material="neo_hookean", bulk_modulus=jnp.asarray(K))
        state = jnp.concatenate([contact, jnp.array([force, 0.1 * force, 0.0])])
        rest = jnp.concatenate([contact, jnp.zeros(3)])
        read = jax.jit(lambda scene, s: scene.readings_at(s))
        results[force] = [np.asarray(read(s, state) - read(s, rest)) for s in (linear, neo)]
    small_linear, small_neo = results[0.005]
    # measured 3.8 % of the largest change, at the chip under the contact: the cells' displacements
    # agree to 0.5 % of their peak, their rotations (a derivative, which the chip near the
    # contact reads most) to 2.5 %
    assert np.max(np.abs(small_neo - small_linear)) < 0.05 * np.max(np.abs(small_linear))
    large_linear, large_neo = results[0.2]
    assert abs(large_neo[0, 2]) > 1.1 * abs(large_linear[0, 2])


@pytest.mark.slow
def test_a_press_the_neo_hookean_layer_cannot_carry_reaches_simulate_as_a_status():
    """Expected before running: the finite-strain layer (K = 100 mu) carries the example's
    0.2 N on a 2 mm sphere (a / R = 0.46) but its four load steps' Newton solves do not
    converge at 10 N (measured: already at 1 N an out-of-balance force is left; at 10 N the
    "depth" is metres, a layer squashed flat under a 2 mm sphere). That load
    point's row is flagged not converged (its field is NaN, never a number that looks like
    an equilibrium), the table names it with its force, and the outputs' mechanics_converged
    is 0 (a design solve's "mechanics_not_converged"). A sweep the layer carries (0.1 N,
    0.2 N) converges at each point, but saturation_force's search presses harder (the
    chips 1 mm under a 2 mm skin of 100 kPa do not saturate below the layer's reach):
    measured NaN, so mechanics_converged is 0 there too, not a silently missing output."""
    spec = neo_hookean_spec()
    spec["mechanics"]["bulk_modulus"] = "10 MPa"  # K = 100 mu
    spec["load"].update(normal=["0.2 N", "10 N"], shear_x=["0 N", "0 N"], points=2)
    scene = scene_from_spec(spec)
    result = simulate(scene, loads_from_spec(spec))
    np.testing.assert_array_equal(np.asarray(result.converged), [True, False])
    readings = np.asarray(result.readings)
    assert np.all(np.isfinite(readings[0])) and np.all(np.isnan(readings[1]))
    table = simulation_table(result)
    assert "did not converge at load points 2 (Fz 10 N)" in table
    assert "1 (Fz" not in table
    # one program for both sweeps (the same shapes): the converged flags and two outputs
    run = eqx.filter_jit(
        lambda s, loads: (lambda r: (r.converged, s.outputs(r)["saturation_force"], s.outputs(r)[MECHANICS_CONVERGED]))(
            simulate(s, loads)
        )
    )
    _, _, converged = run(scene, loads_from_spec(spec))
    assert float(converged) == 0.0
    spec["load"].update(normal=["0.1 N", "0.2 N"])
    carried, saturation, converged = run(scene, loads_from_spec(spec))
    assert np.all(np.asarray(carried)) and np.isnan(float(saturation)) and float(converged) == 0.0
