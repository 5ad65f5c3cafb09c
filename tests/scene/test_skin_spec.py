"""The magnetic skin from a spec: the example builds the skin it states, every bad input is
a one-line SpecError naming its key, and a design of a small skin solves from its spec."""

import tomllib
import warnings

import equinox as eqx
import jax
import jax.numpy as jnp
import magpylib
import numpy as np
import pytest
from scene_helpers import EXAMPLES, example

from magdesign.cli import main
from magdesign.design import solve
from magdesign.scene import (
    Loads,
    SimulationResult,
    loads_from_spec,
    parameters,
    scene_from_spec,
    simulate,
    simulation_json,
    simulation_table,
    with_parameters,
)
from magdesign.scene.effects import EFFECT_NAMES
from magdesign.scene.skin_scene import SkinScene
from magdesign.spec.checks import PlausibilityWarning
from magdesign.spec.design import problem_from_spec
from magdesign.spec.levels import outputs_at
from magdesign.units import SpecError


def skin(edit=None):
    spec = example("skin")
    if edit is not None:
        edit(spec)
    return spec


def test_the_example_builds_the_skin_it_states():
    scene = scene_from_spec(skin())
    assert isinstance(scene, SkinScene)
    cross = [[0.0, 0.0], [0.01, 0.0], [-0.01, 0.0], [0.0, 0.01], [0.0, -0.01]]
    np.testing.assert_allclose(scene.chips, cross, atol=1e-15)
    # the linear field at its default resolution: 2 nodes per mm of depth across 30 mm, 6 through
    assert scene.field == "linear" and scene.resolution == (60, 60, 6)
    assert scene.map_grid == (2, 2) and scene.direction == (0.0, 0.0, 1.0)
    assert {name: float(value) for name, value in parameters(scene).items()} == pytest.approx(
        {
            "magnet.polarization": 0.02,
            "mechanics.thickness": 2e-3,
            "mechanics.shear_modulus": 100e3,
            "sensor.depth": 1e-3,
            "indenter.radius": 2e-3,
        }
        | {f"sensor.chips[{i}][{k}]": xy for i, chip in enumerate(cross) for k, xy in enumerate(chip)}
    )
    np.testing.assert_allclose(scene.size, [0.03, 0.03])
    # without the noise effect the outputs' noise is one LSB: the MLX90393 datasheet's 0.150 uT
    # (x, y) and 0.242 uT (z) per count at GAIN_SEL = 7, RES_XYZ = 0
    np.testing.assert_allclose(scene.noise, [0.150e-6, 0.150e-6, 0.242e-6], rtol=1e-12)
    assert [effect.name for effect in scene.effects] == ["background", "saturation"]
    loads = loads_from_spec(skin())
    np.testing.assert_allclose(loads.contact[-1], [2e-3, 1e-3])
    np.testing.assert_allclose(loads.normal[-1], 0.2)


def test_a_grid_places_the_chips_and_the_noise_effect_sets_the_outputs_noise():
    def edit(spec):
        spec["sensor"].pop("chips")
        spec["sensor"].update(grid=[2, 2], pitch="8 mm")
        spec["magnet"]["direction"] = [1, 0, 0]  # in-plane, normalised
        spec["scene"].update(effects=["noise"], noise="2 uT")

    scene = scene_from_spec(skin(edit))
    assert sorted(map(tuple, np.asarray(scene.chip_positions()).round(12))) == [
        (-0.004, -0.004),
        (-0.004, 0.004),
        (0.004, -0.004),
        (0.004, 0.004),
    ]
    assert scene.direction == (1.0, 0.0, 0.0)
    np.testing.assert_allclose(scene.noise, [2e-6] * 3)


def test_the_indenters_radius_is_a_design_parameter():
    scene = with_parameters(scene_from_spec(skin()), {"indenter.radius": 3e-3})
    assert float(scene.sphere_radius) == 3e-3
    # Hertz: a = (3 F R / (4 E*))^(1/3), E* = 2 mu / (1 - nu)
    e_star = 2 * 100e3 / (1 - 0.49)
    assert float(scene.contact_radius(jnp.asarray(0.2))) == pytest.approx((3 * 0.2 * 3e-3 / (4 * e_star)) ** (1 / 3))


@pytest.mark.parametrize(
    "edit, key, expected",
    [
        (lambda s: s["sensor"].update(chips=[["0 mm", "0 mm"], ["20 mm", "0 mm"]]), "sensor.chips", "off the 30 x 30"),
        (lambda s: s["sensor"].update(chips=[["0 mm", "0 mm"]]), "sensor.chips", "at least 2 chips"),
        (lambda s: s["sensor"].update(chips=[["0 mm", "0 mm", "0 mm"]]), "sensor.chips", "[x, y] quantities in m"),
        (lambda s: s["sensor"].update(grid=[2, 2], pitch="8 mm"), "sensor.chips", "both were given"),
        (lambda s: s["sensor"].pop("chips"), "sensor.chips", "neither was given"),
        (lambda s: s["sensor"].update(depth="0 mm"), "sensor.depth", "above 0 mm"),
        (lambda s: s["sensor"].pop("depth"), "sensor.depth", "missing"),
        (lambda s: s["sensor"].update(map_grid=[2, 0]), "sensor.map_grid", "positive integers"),
        (lambda s: s["sensor"].update(positions=[["0 mm", "0 mm", "0 mm"]]), "sensor.positions", "unknown key"),
        (lambda s: s["magnet"].update(field="cells", cells=[4, 4]), "magnet.cells", "3 positive integers"),
        (lambda s: s["magnet"].update(cells=[4, 4, 2]), "magnet.cells", "linear field"),
        (lambda s: s["magnet"].update(field="charges"), "magnet.field", "'linear', 'cells'"),
        (lambda s: s["magnet"].update(resolution=[40, 40]), "magnet.resolution", "3 positive integers"),
        (lambda s: s["magnet"].update(field="cells", resolution=[40, 40, 6]), "magnet.resolution", "linear field"),
        (lambda s: s["magnet"].update(direction=[0, 0, 0]), "magnet.direction", "nonzero"),
        (lambda s: s["magnet"].update(polarization="20 mm"), "magnet.polarization", "in T"),
        (lambda s: s["magnet"].update(remanence="1 T"), "magnet.remanence", "unknown key"),
        (lambda s: s["mechanics"].update(model="layer"), "mechanics.model", "'bonded_layer'"),
        (lambda s: s["mechanics"].update(poisson_ratio=0.51), "mechanics.poisson_ratio", "0.51 is not physical"),
        (lambda s: s["mechanics"].update(size=["30 mm"]), "mechanics.size", "list of 2"),
        (lambda s: s.pop("indenter"), "[indenter]", "missing table"),
        (lambda s: s["indenter"].update(radius="-2 mm"), "indenter.radius", "not physical"),
        (lambda s: s["load"].update(contact_y=["0 mm", "16 mm"]), "load.contact_y", "at most 15 mm"),
        (lambda s: s["load"].update(normal=["0 N", "-0.2 N"]), "load.normal", "an indenter only presses"),
        (lambda s: s["load"].update(normal=["0 N", "0 N"]), "load.normal", "expected a press above 0 N"),
        (lambda s: s["sensor"]["chips"].__setitem__(1, ["0 mm", "0 mm"]), "sensor.chips", "chips 0 and 1 both sit"),
        (
            lambda s: (s["sensor"].pop("chips"), s["sensor"].update(grid=[2, 3], pitch="0 mm")),
            "sensor.pitch",
            "every chip at one place",
        ),
        (lambda s: s["indenter"].update(shape="cone"), "indenter.shape", "sphere"),
        (lambda s: s.update(geometry={"gap": "1 mm"}), "[geometry]", "no [geometry] table"),
    ],
)
def test_bad_input_names_the_key_on_one_line(edit, key, expected):
    with pytest.raises(SpecError) as error:
        scene_from_spec(skin(edit))
    message = str(error.value)
    assert message.startswith(key) and expected in message and "\n" not in message, message


def test_the_skins_tables_are_refused_elsewhere_and_a_fidelity_by_the_skin():
    film = example("film_hall")
    film["indenter"] = {"radius": "2 mm"}
    with pytest.raises(SpecError, match=r"^indenter: .*not a film"):
        scene_from_spec(film)
    film = example("film_hall")
    film["sensor"]["map_grid"] = [2, 2]
    with pytest.raises(SpecError, match=r"^sensor.map_grid: unknown key"):
        scene_from_spec(film)
    with pytest.raises(SpecError, match=r"^fidelity: the skin has one"):
        scene_from_spec(skin(), fidelity="hooke")


def test_a_contact_patch_wider_than_the_model_holds_warns_naming_the_load():
    def edit(spec):
        spec["load"]["normal"] = ["0 N", "5 N"]

    with pytest.warns(PlausibilityWarning, match=r"^load.normal: at 5 N .* times the 2 mm skin"):
        scene_from_spec(skin(edit))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_from_spec(skin())  # the example's 0.9 mm patch under 0.2 N: no patch warning
    assert not [w for w in caught if "Hertz contact radius is" in str(w.message)]


def _hertz_radius(force, sphere=2e-3, shear_modulus=100e3, nu=0.49):
    """Hertz's contact radius (m) of a rigid sphere on the half-space (Johnson 1985, ch. 4)."""
    return (3.0 * force * sphere * (1.0 - nu) / (8.0 * shear_modulus)) ** (1.0 / 3.0)


def test_a_press_past_the_linear_layers_strain_warns_once_naming_force_and_modulus():
    """The strain under a sphere's contact is its depth over its radius, a^2 / R / a = a / R
    (Hertz); a neo-Hookean stress departs from Hooke's by 11.5 % at 10 % uniaxial compression:
    mu (l - l^-2) against 3 mu (l - 1) at l = 0.9."""
    stretch = 0.9
    assert abs((stretch - stretch**-2) / (3.0 * (stretch - 1.0)) - 1.115) < 1e-3
    # the example without its shear: 0.2 N on a 2 mm sphere, a / R = 0.915 mm / 2 mm = 0.46
    strain = _hertz_radius(0.2) / 2e-3
    assert abs(strain - 0.457) < 1e-3

    def pressed(force, shear=0.0):
        def edit(spec):
            spec["load"]["normal"] = ["0 N", f"{force} N"]
            spec["load"]["shear_x"] = ["0 N", f"{shear} N"]

        return skin(edit)

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene_from_spec(pressed(0.2))
    strained = [str(w.message) for w in caught if "strain under the contact" in str(w.message)]
    assert len(strained) == 1 and strained[0].startswith(
        "load.normal: at 0.2 N (shear (0, 0) N) the largest strain under "
    )
    assert f"a / R = {strain:.2g}" in strained[0] and "mechanics.shear_modulus" in strained[0]
    assert "indenter.radius" in strained[0] and "11.5 %" in strained[0]
    # the largest strain inside: Hertz's stresses on the axis (Johnson 1985, eq. 3.45, nu =
    # 0.5), p0 = 8 G a / (pi R), as a uniaxial strain (sigma_r - sigma_z) / (3 G)
    depth = np.linspace(0.01, 3.0, 30000)  # z / a
    axial = -1.0 / (1.0 + depth**2)
    radial = -1.5 * (1.0 - depth * np.arctan(1.0 / depth)) + 0.5 / (1.0 + depth**2)
    peak = float(np.max(radial - axial)) * 8.0 / (3.0 * np.pi)  # per a / R
    assert abs(peak - 0.452) < 1e-3
    assert f"the contact is {peak * strain:.2g} (" in strained[0]
    # a / R = 0.20 and 0.24, a largest strain inside of 0.090 and 0.108, either side of the
    # limit: F = (a / R)^3 8 G R^2 / (3 (1 - nu))
    below, above = (ratio**3 * 8.0 * 100e3 * 2e-3**2 / (3.0 * 0.51) for ratio in (0.20, 0.24))
    assert abs(_hertz_radius(below) / 2e-3 - 0.20) < 1e-12
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene_from_spec(pressed(below))
    with pytest.warns(PlausibilityWarning, match=r"^load.normal: .* strain under the contact is 0.11 "):
        scene_from_spec(pressed(above))

    # a flat punch of 1 mm radius sheared by 0.05 N over 1 mN: its face travels
    # (2 - nu) F_t / (8 G a) = 0.0944 mm along x (Johnson 1985, ch. 7), and 0.0013 mm down
    # (F_n (1 - nu) / (4 G a)): a strain of 0.0944
    def punched(shear):
        spec = pressed(0.001, shear)
        spec["indenter"] = {"shape": "flat", "radius": "1 mm"}
        return spec

    travel = np.hypot(1.51 * 0.05, 2 * 0.51 * 0.001) / (8 * 100e3 * 1e-3**2)
    assert abs(travel - 0.0944) < 1e-4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scene_from_spec(punched(0.05))
    with pytest.warns(PlausibilityWarning, match=r"^load.shear_x: .* is 0.11 \(the flat punch's travel"):
        scene_from_spec(punched(0.06))  # 0.113


def test_a_contact_or_map_point_near_the_side_warns():
    """The layer's mechanics is the unbounded layer's: within one thickness of the skin's side
    its free side changes the displacement, and the spec says so."""
    with pytest.warns(PlausibilityWarning, match=r"^load.contact: a point lies 1 mm from the skin's side"):
        scene_from_spec(skin(lambda s: s["load"].update(contact_x=["14 mm", "14 mm"])))
    with pytest.warns(PlausibilityWarning, match=r"^sensor.map_grid: a point lies 0.5 mm from"):
        scene_from_spec(skin(lambda s: s["sensor"]["chips"].__setitem__(1, ["14.5 mm", "0 mm"])))


@pytest.mark.slow
def test_a_flat_punch_keeps_its_radius_and_shrinks_to_the_spheres_point_load():
    """A flat punch presses a patch of its own radius at every force; a small punch and a
    small sphere's patch both load the skin as a point force does, so the chips, 3 mm below
    the surface, read the same change to about (a / 3 mm)^2, while a 1 mm punch reads another."""
    punch = scene_from_spec(skin(lambda s: s["indenter"].update(shape="flat", radius="0.05 mm")))
    assert punch.indenter == "flat"
    np.testing.assert_allclose(punch.contact_radius(jnp.array([0.01, 0.2, 3.0])), 5e-5, rtol=1e-15)
    sphere = scene_from_spec(skin(lambda s: s["indenter"].update(radius="1 um")))
    state = jnp.array([1e-3, 0.5e-3, 0.2, 0.03, -0.02])
    rest = np.asarray(sphere.readings_at(state.at[2:].set(0.0)))
    change = {
        name: np.asarray(scene.readings_at(state)) - rest
        for name, scene in (
            ("punch", punch),
            ("sphere", sphere),
            ("wide", eqx.tree_at(lambda s: s.sphere_radius, punch, jnp.asarray(1e-3))),
        )
    }
    assert float(sphere.contact_radius(0.2)) < 1e-4  # Hertz's patch under 0.2 N on a 1 um sphere: 73 um
    scale = np.abs(change["sphere"]).max()
    np.testing.assert_allclose(change["punch"], change["sphere"], atol=2e-3 * scale)
    assert np.abs(change["wide"] - change["sphere"]).max() > 2e-2 * scale


def test_a_bad_skin_spec_exits_2_naming_the_key(tmp_path, capsys):
    path = tmp_path / "skin.toml"
    path.write_text((EXAMPLES / "skin.toml").read_text().replace('depth = "1 mm"', 'depth = "-1 mm"'))
    assert main(["simulate", str(path)]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].count("sensor.depth") == 1


# A small skin's design: the polarisation that brings the normal-force resolution to a target.
SMALL_DESIGN = """
[design.variables]
"magnet.polarization" = { lower = "5 mT", upper = "80 mT" }

[design.targets]
force_resolution_normal = "TARGET"

[design.limits]
saturation_ratio = { upper = 1 }
"""


@pytest.mark.slow  # compiles the outputs' Jacobians through the layer's transforms, and their derivatives
def test_a_small_skins_design_solves_from_its_spec():
    """The spec's design solved in Python, as the command does: the command line's solve of
    a skin is test_skin_chips's (design.grids) and its simulate test_cli's (every example),
    so that here the command's error estimates (one more program: the outputs at the finer
    field) are left out."""
    text = (EXAMPLES / "skin.toml").read_text()
    text = text.replace("direction = [0, 0, 1]", "direction = [0, 0, 1]\nresolution = [20, 20, 4]")
    text = text.replace("map_grid = [2, 2]", "map_grid = [1, 1]")
    # the resolution scales as 1 / J0 (the readings' Jacobian is linear in it): from the start's value,
    # the target at twice the start's polarization is half the start's resolution
    resolution = outputs_at(tomllib.loads(text))["force_resolution_normal"]
    problem, _ = problem_from_spec(tomllib.loads(text + SMALL_DESIGN.replace("TARGET", f"{resolution / 2:.12g} N")))
    solved = solve(problem)
    assert str(solved.status) == "successful", solved.status
    assert float(solved.parameters["magnet.polarization"]) == pytest.approx(0.04, rel=1e-4)


def test_the_simulation_table_shows_a_skins_contact_point_in_line_with_its_readings():
    """A skin's mechanics' state is its load (x, y, Fn, F_x, F_y): the table shows the contact
    point (mm), and every row has as many columns as the header."""
    loads = Loads(jnp.array([0.0, 0.2]), contact=jnp.array([2e-3, 1e-3]))
    state = jnp.concatenate([loads.contact, loads.normal[:, None], loads.shear], axis=-1)
    field = jnp.arange(12.0).reshape(2, 2, 3) * 1e-3
    result = SimulationResult(loads, jnp.ones(2, bool), state, field, field, field, {}, ("Bx", "By", "Bz"), "T")
    header, *rows = simulation_table(result).splitlines()
    assert header.split()[8:12] == ["x", "(mm)", "y", "(mm)"]
    assert all(len(row.split()) == 4 + 2 + 6 for row in rows)
    assert rows[1].split()[4:7] == ["2", "1", "6"]  # x, y (mm), then sensor 0's Bx (mT)
    assert simulation_json(result)["units"]["displacement"] == "m, m, N, N, N"


def test_at_rest_the_specs_chips_read_magpylibs_block():
    """The spec's layer (sides, thickness above z = 0, a tilted polarisation) and chips (x, y,
    depth below z = 0) against magpylib's cuboid of the same polarisation, unloaded, plus the
    example's background field (50 uT along z), which the chips read too."""

    def edit(spec):
        spec["magnet"]["direction"] = [1, 0, 1]

    scene = scene_from_spec(skin(edit))
    got = np.asarray(scene.readings_at(jnp.zeros(5)))
    polarization = 0.02 * np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    block = magpylib.magnet.Cuboid(polarization=polarization, dimension=(0.03, 0.03, 0.002), position=(0, 0, 0.001))
    chips = [[0.0, 0.0, -1e-3], [0.01, 0.0, -1e-3], [-0.01, 0.0, -1e-3], [0.0, 0.01, -1e-3], [0.0, -0.01, -1e-3]]
    background = np.array([0.0, 0.0, 50e-6])
    np.testing.assert_allclose(got, block.getB(np.array(chips)) + background, rtol=1e-9, atol=1e-15)


def test_every_effect_traces_through_the_skins_chain():
    def edit(spec):
        spec["scene"] = {"effects": list(EFFECT_NAMES)}

    spec = skin(edit)
    scene, loads = scene_from_spec(spec), loads_from_spec(spec)
    assert [effect.name for effect in scene.effects] == list(EFFECT_NAMES)
    result = jax.eval_shape(lambda: simulate(scene, loads, key=jax.random.key(0)))
    assert result.readings.shape == (3, 5, 3)


@pytest.mark.slow  # compiles the layer's displacement and draws the field on a 181 x 181 grid: about a minute
def test_the_show_command_draws_the_skin(tmp_path):
    picture = tmp_path / "skin.png"
    assert main(["show", str(EXAMPLES / "skin.toml"), "--plot", str(picture), "--quiet"]) == 0
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_an_incompressible_layer_is_a_skins_and_not_a_linear_materials():
    """nu = 0.5 is exact for the skin's bonded layer (its equations are written with mu and
    kappa = 3 - 4 nu, kappa = 1 at 0.5), while a linear material's bulk modulus
    E / (3 (1 - 2 nu)) is infinite there: the spec takes it for the one and says why not for the other."""
    scene = scene_from_spec(skin(lambda s: s["mechanics"].update(poisson_ratio=0.5)))
    assert float(scene.poisson_ratio) == 0.5
    film = example("film_hall")
    film["mechanics"]["poisson_ratio"] = 0.5
    with pytest.raises(SpecError, match=r"mechanics\.poisson_ratio: 0\.5 makes a linear material incompressible"):
        scene_from_spec(film)


@pytest.mark.slow
def test_iron_near_a_skin_is_magnetised_by_its_field():
    """A small soft sphere (mu_r 2, 0.5 mm radius) 5 mm below the board: magnetised by the
    layer's field at its centre (magpylib's block), it is the dipole m = 4 pi a^3 chi / (chi
    + 3) B0 / mu0 (a sphere in a uniform field), whose field the chips add to the layer's, to
    the field's variation over the sphere and the staircase sphere's error (0.5 % seen)."""

    def with_iron(spec):
        spec["scene"] = {}
        spec["soft"] = [{"shape": "sphere", "size": "1 mm", "position": ["3 mm", "2 mm", "-5 mm"], "permeability": 2}]

    scene = scene_from_spec(skin(with_iron))
    assert "soft[0].permeability" in parameters(scene)
    alone = scene_from_spec(skin(lambda s: s.update(scene={})))
    added = np.asarray(scene.readings_at(jnp.zeros(5))) - np.asarray(alone.readings_at(jnp.zeros(5)))
    centre, radius, chi, mu0 = np.array([3e-3, 2e-3, -5e-3]), 0.5e-3, 1.0, 4e-7 * np.pi
    block = magpylib.magnet.Cuboid(polarization=(0, 0, 0.02), dimension=(0.03, 0.03, 0.002), position=(0, 0, 0.001))
    moment = 4 * np.pi * radius**3 * chi / (chi + 3) * block.getB(centre) / mu0
    chips = np.concatenate([np.asarray(scene.chip_positions()), np.full((5, 1), -1e-3)], axis=-1)
    dipole = magpylib.misc.Dipole(moment=moment, position=centre).getB(chips)
    np.testing.assert_allclose(added, dipole, atol=2e-2 * np.abs(dipole).max())
    with pytest.raises(SpecError, match=r"^soft\[0\]\.moves: a skin's load moves its layer"):
        scene_from_spec(skin(lambda s: (with_iron(s), s["soft"][0].update(moves=True))))
    with pytest.raises(SpecError, match=r"^soft\[0\]: it overlaps the skin's layer"):
        scene_from_spec(skin(lambda s: (with_iron(s), s["soft"][0].update(position=["3 mm", "2 mm", "1 mm"]))))


@pytest.mark.parametrize("indenter", ["sphere", "flat"])
def test_the_checks_numpy_numbers_are_the_scenes_jax_numbers(indenter):
    """The spec's checks read the contact patch, its strain and the outputs' map in numpy
    (no JAX program at load); the traceable jax.numpy forms give the same numbers."""
    scene = scene_from_spec(skin(lambda s: s["indenter"].update(shape=indenter)))
    normal = np.array([0.0, 5e-4, 0.05, 0.2, 3.0])
    shear = np.array([[0.0, 0.0], [1e-4, 0.0], [0.01, -0.02], [0.05, 0.0], [0.0, 1.0]])
    pairs = [
        (scene.contact_radius(normal, xp=np), scene.contact_radius(jnp.asarray(normal))),
        (scene.contact_strain(normal, shear, xp=np), scene.contact_strain(jnp.asarray(normal), jnp.asarray(shear))),
        (scene.map_points(xp=np), scene.map_points()),
        (scene.chip_positions(xp=np), scene.chip_positions()),
    ]
    for numbers, traceable in pairs:
        assert isinstance(numbers, np.ndarray)
        np.testing.assert_allclose(numbers, np.asarray(traceable), rtol=1e-14, atol=0.0)
