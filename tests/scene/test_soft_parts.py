"""[[soft]] parts of a magnet scene (MagnetScene.soft, the method of moments): the scene's
field against magpylib's magnet and cuboid cells at the part's pose, the physics of a soft
back plate, and the spec's errors."""

import copy

import equinox as eqx
import jax.numpy as jnp
import magpylib as magpy
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from magdesign.design import solve
from magdesign.fields import soft
from magdesign.scene import scene_from_spec, with_parameters
from magdesign.scene.pose import rotation
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.table import parameter_unit
from magdesign.units import MU0, SpecError

PLATE = {
    "shape": "cuboid",
    "size": ["10 mm", "10 mm", "1 mm"],
    "position": ["0 mm", "0 mm", "-1 mm"],
    "permeability": 1000,
    "cells": 8,
}
field = eqx.filter_jit(lambda scene, points, displacement: scene.source_field(points, displacement))


def spec_with(*parts):
    spec = default_spec()
    spec["magnet"]["fidelity"] = "exact"
    spec["soft"] = [copy.deepcopy(part) for part in parts]
    return spec


@pytest.mark.slow
def test_the_field_of_a_turned_soft_rod_against_magpylib():
    """A Ni-Fe rod turned by three angles beside the magnet: the scene's field (magnet +
    rod) against magpylib's cylinder plus cuboids at the rod's cells, magnetised as the
    scene solves them, at a pressed displacement (the rod fixed, the magnet moved)."""
    rod = {
        "shape": "cylinder",
        "size": ["1 mm", "3 mm"],
        "position": ["2 mm", "0.5 mm", "3 mm"],
        "rotation": ["20 deg", "-35 deg", "10 deg"],
        "permeability": 300,
        "cells": 6,
    }
    scene = scene_from_spec(spec_with(rod))
    part = scene.soft[0]
    displacement = jnp.array([0.0, 0.0, -1e-3])
    points = np.array([[0.0, 0.0, 0.0], [1e-3, -0.5e-3, 0.2e-3], [3e-3, 1e-3, 1e-3]])
    value = np.asarray(field(scene, points, displacement))

    magnet = magpy.magnet.Cylinder(
        polarization=(0, 0, float(scene.remanence)),
        dimension=(2 * float(scene.radius), float(scene.height)),
        position=np.asarray(scene.magnet_centre() + displacement),
    )
    matrix = np.asarray(rotation(part.angles))  # v_body = matrix v_scene
    body = part.body
    cells = np.asarray(part.centre) + np.asarray(body.centres) @ matrix
    external = magnet.getB(cells) @ matrix.T
    magnetization = np.asarray(soft.magnetization(body, external))
    orientation = Rotation.from_matrix(matrix.T)
    cuboids = magpy.Collection(
        *[
            magpy.magnet.Cuboid(
                polarization=MU0 * m, dimension=np.asarray(body.cell), position=c, orientation=orientation
            )
            for c, m in zip(cells, magnetization)
        ]
    )
    np.testing.assert_allclose(value, magnet.getB(points) + cuboids.getB(points), rtol=1e-9, atol=1e-13)
    assert np.linalg.norm(cuboids.getB(points[1])) > 1e-3 * np.linalg.norm(magnet.getB(points[1]))  # the rod matters


@pytest.mark.slow
def test_a_soft_back_plate_draws_the_flux_and_a_far_part_does_nothing():
    """A high-permeability plate just below the sensor raises the magnet's B_z there (the
    magnet's image), by less than the factor 2 of an infinite plate; a part a metre away
    changes it by less than 1e-9."""
    points, rest = jnp.zeros((1, 3)), jnp.zeros(3)
    bare = float(field(scene_from_spec(spec_with()), points, rest)[0, 2])
    plated = float(field(scene_from_spec(spec_with(PLATE)), points, rest)[0, 2])
    assert 1.2 * bare < plated < 2.0 * bare
    far = {**PLATE, "position": ["0 mm", "0 mm", "-1000 mm"]}
    assert abs(float(field(scene_from_spec(spec_with(far)), points, rest)[0, 2]) / bare - 1) < 1e-9


@pytest.mark.slow
def test_a_part_carried_by_the_load_moves_with_the_magnet():
    """A soft disc on the magnet (moves = true): at a displacement the field equals the
    rest field seen from the displaced point."""
    disc = {
        "shape": "cylinder",
        "size": ["3 mm", "0.5 mm"],
        "position": ["0 mm", "0 mm", "8.8 mm"],
        "permeability": 50,
        "moves": True,
        "cells": 6,
    }
    scene = scene_from_spec(spec_with(disc))
    shift = jnp.array([0.3e-3, 0.0, -1e-3])
    points = jnp.array([[0.0, 0.0, 0.0], [1e-3, 0.0, 0.5e-3]])
    np.testing.assert_allclose(
        field(scene, points, shift), field(scene, points - shift, jnp.zeros(3)), rtol=1e-12, atol=1e-15
    )


@pytest.mark.parametrize(
    "change, match",
    [
        ({"shape": "torus"}, "soft\\[0\\].shape"),
        ({"size": ["1 mm", "1 mm"]}, "soft\\[0\\].size"),
        ({"size": ["1 mm", "-1 mm", "1 mm"]}, "soft\\[0\\].size"),
        ({"permeability": 0}, "soft\\[0\\].permeability"),
        ({"saturation": "0 T"}, "soft\\[0\\].saturation"),
        ({"saturation": "2 mm"}, "soft\\[0\\].saturation"),
        ({"saturation": "1 T", "permeability": 1}, "soft\\[0\\].saturation"),
        ({"position": ["1 T", "0 mm", "0 mm"]}, "soft\\[0\\].position"),
        ({"colour": "grey"}, "colour"),
    ],
)
def test_bad_soft_parts_name_the_key(change, match):
    with pytest.raises(SpecError, match=match):
        scene_from_spec(spec_with({**PLATE, **change}))


def test_soft_parts_need_the_exact_field_and_a_cylinder_magnet():
    spec = spec_with(PLATE)
    spec["magnet"]["fidelity"] = "axis"
    with pytest.raises(SpecError, match="magnet.fidelity"):
        scene_from_spec(spec)
    from scene_helpers import example

    film = example("film_hall")
    film["soft"] = [PLATE]
    with pytest.raises(SpecError, match="soft"):
        scene_from_spec(film)


@pytest.mark.slow
def test_parts_magnetise_one_another():
    """A second plate near the first changes the field by more than its own field alone
    does (the two magnetise one another); a second plate a metre away changes nothing."""
    points, rest = jnp.zeros((1, 3)), jnp.zeros(3)
    near = {**PLATE, "position": ["0 mm", "0 mm", "-2.1 mm"], "cells": 6}  # 0.1 mm below the first
    first = {**PLATE, "cells": 6}
    alone = [float(field(scene_from_spec(spec_with(part)), points, rest)[0, 2]) for part in (first, near)]
    bare = float(field(scene_from_spec(spec_with()), points, rest)[0, 2])
    both = float(field(scene_from_spec(spec_with(first, near)), points, rest)[0, 2])
    independent = alone[0] + alone[1] - bare  # each part magnetised by the magnet alone
    assert abs(both / independent - 1) > 0.02, (both, independent)
    far = {**near, "position": ["0 mm", "0 mm", "-1000 mm"]}
    with_far = float(field(scene_from_spec(spec_with(first, far)), points, rest)[0, 2])
    assert abs(with_far / alone[0] - 1) < 1e-9


@pytest.mark.slow
def test_a_saturating_part_gives_less_than_the_linear_one():
    """A plate whose J_s is below what the magnet would drive it to: the gain over the bare
    magnet shrinks; a J_s far above changes nothing."""
    points, rest = jnp.zeros((1, 3)), jnp.zeros(3)
    bare = float(field(scene_from_spec(spec_with()), points, rest)[0, 2])
    linear = float(field(scene_from_spec(spec_with(PLATE)), points, rest)[0, 2])
    weak = float(field(scene_from_spec(spec_with({**PLATE, "saturation": "0.5 mT"})), points, rest)[0, 2])
    strong = float(field(scene_from_spec(spec_with({**PLATE, "saturation": "10 T"})), points, rest)[0, 2])
    assert bare < weak < bare + 0.8 * (linear - bare)
    assert abs(strong / linear - 1) < 1e-6


@pytest.mark.slow
def test_a_design_places_a_soft_back_plate():
    """The plate's depth as a design variable (soft[0].position[2], read in m): the solve
    reaches a wanted rest field that lies between the far and the near plate's, and the
    scene at the answer gives it."""
    spec = spec_with({**PLATE, "size": ["10 mm", "10 mm", "0.5 mm"], "position": ["0 mm", "0 mm", "-3 mm"], "cells": 4})
    spec["mechanics"]["fidelity"] = "reissner"
    spec["load"] = {"normal": ["0 N", "5 N"], "points": 2}
    spec["scene"] = {"effects": []}
    spec["design"] = {
        "variables": {"soft[0].position[2]": {"lower": "-6 mm", "upper": "-0.5 mm"}},  # starts at the scene's -3 mm
        "targets": {"field_rest": "2.9 mT"},
        "limits": {"saturation_ratio": {"upper": 10}},  # pressed 5 N the AK8963 clips: not the point here
    }
    assert parameter_unit("soft[0].position[2]") == "m" and parameter_unit("soft[0].saturation") == "T"
    problem, scene = problem_from_spec(spec)
    points, rest = jnp.zeros((1, 3)), jnp.zeros(3)
    ends = [
        float(field(with_parameters(scene, {"soft[0].position[2]": z}), points, rest)[0, 2]) for z in (-6e-3, -0.5e-3)
    ]
    assert ends[0] < 2.9e-3 < ends[1]
    result = solve(problem)
    assert str(result.status) == "successful", result.status
    depth = float(result.parameters["soft[0].position[2]"])
    assert -6e-3 < depth < -0.5e-3
    at_answer = float(field(with_parameters(scene, {"soft[0].position[2]": depth}), points, rest)[0, 2])
    assert abs(at_answer / 2.9e-3 - 1) < 1e-8
