"""The one table of spec keys against the code that reads specs.

Every key the table lists is read when a set of specs is loaded (the examples, the built-in
default, and specs that between them give every key); every key the code reads is listed
(a read of an unlisted key raises); the reference page lists every key.
"""

import copy
import pathlib
import subprocess
import sys
import tomllib

import pytest

from magdesign.scene import loads_from_spec, parameters, scene_from_spec
from magdesign.scene.effects import EFFECT_NAMES
from magdesign.spec.checks import UnlistedKeyError, listed, recording
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.key import Key
from magdesign.spec.keys import KEYS
from magdesign.spec.reference import markdown
from magdesign.spec.table import Table
from magdesign.spec.tolerance import EFFECT_INPUTS, tolerance_problem_from_spec

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
# The sub-tables of [design.tolerances] that are named inputs rather than scene parameters.
_NAMED_TOLERANCES = ("distribution", "placement", "tilt", "temperature")


def _example(name):
    with open(EXAMPLES / f"{name}.toml", "rb") as file:
        return tomllib.load(file)


def _scene_only(spec):
    return {table: value for table, value in copy.deepcopy(spec).items() if table != "design"}


def _specs_with_every_key():
    """Specs that, with the examples and the default, give every key of the table."""
    # every effect and option, a posed magnet with a further magnet, a soft part, a grid of
    # chips below the sensor plane, a linear dome sliding on its base
    every = _scene_only(default_spec())
    every["scene"] = {
        "effects": list(EFFECT_NAMES),
        "temperature_coefficient": "-0.12 %/K",
        "temperature_change": "20 K",
        "placement": ["100 um", "0 um", "0 um"],
        "tilt": ["5 deg", "0 deg", "0 deg"],
        "lag_time_constant": "0.5 s",
        "area": ["200 um", "95 um"],
        "quadrature": 2,
        "background": ["0 T", "0 T", "50 uT"],
        "saturation_limit": "4.8 mT",
        "noise": "0.15 uT",
        "lsb": "0.15 uT",
    }
    every["magnet"].update(
        fidelity="exact",
        direction=[0, 0, 1],
        offset=["0 mm", "0 mm", "0.1 mm"],
        rotation=["1 deg", "0 deg", "0 deg"],
        extra=[
            {
                "radius": "1 mm",
                "height": "1 mm",
                "polarization": ["0 T", "0 T", "1 T"],
                "position": ["5 mm", "0 mm", "9 mm"],
                "rotation": ["0 deg", "0 deg", "0 deg"],
                "moves": False,
            }
        ],
    )
    every["soft"] = [
        {
            "shape": "cuboid",
            "size": ["2 mm", "2 mm", "0.5 mm"],
            "permeability": 100,
            "saturation": "1 T",
            "cells": 2,
            "position": ["0 mm", "0 mm", "-1 mm"],
            "rotation": ["0 deg", "0 deg", "0 deg"],
            "moves": False,
        }
    ]
    every["sensor"].update(grid=[1, 2], pitch="2 mm", depth="0.5 mm", orientation="radial")
    every["mechanics"] = {
        "model": "dome",
        "outer_radius": "8 mm",
        "thickness": "2 mm",
        "base": "sliding",
        "material": "linear",
        "youngs_modulus": "0.5 MPa",
        "poisson_ratio": 0.49,
    }

    # every design key: a named design, a variable with its start and scale, a target and a
    # limit with every entry, tolerances with their own distributions
    design = default_spec()
    design["design"]["name"] = "every design key"
    design["design"]["variables"]["geometry.gap"].update(start="7.4 mm", scale="1 mm")
    design["design"]["targets"]["compliance"] = {"value": "0.32 mm/N", "scale": "0.01 mm/N", "tolerance": "5 %"}
    design["design"]["limits"]["closest_gap"] = {"lower": "1 mm", "scale": "1 mm"}
    design["design"]["tolerances"] = {
        "distribution": "normal",
        "magnet.remanence": {"value": "2 %", "distribution": "uniform"},
        "mechanics.c10": "5 %",
        "placement": "50 um",
        "tilt": "2 deg",
        "temperature": "10 K",
    }

    film = _example("film_hall")
    film["magnet"]["periods"] = 3
    reduced = _example("pole_plate")
    reduced["pole"] = {
        "ball_radius": "2 mm",
        "diameter": "1.2 mm",
        "length": "3 mm",
        "fidelity": "reduced",
        "demagnetizing_factor": 0.1,
    }
    saturating = _example("pole_plate")
    saturating["pole"]["saturation"] = "1 T"
    loads = _example("gmr_inductor")
    loads["load"].update(shear_y=["0 N", "1 N"], contact_x=["0 mm", "1 mm"], contact_y=["0 mm", "-1 mm"])
    # a skin's design over candidate chip grids
    grids = _example("skin")
    grids["sensor"].pop("chips")
    grids["sensor"].update(grid=[2, 2], pitch="8 mm")
    grids["design"] = {
        "variables": {"magnet.polarization": {"lower": "5 mT", "upper": "80 mT"}},
        "targets": {"force_resolution_normal": "20 mN"},
        "grids": [[1, 2], [2, 2]],
    }
    return {
        "every scene key": every,
        "every design key": design,
        "a skin's candidate grids": grids,
        "finite film": film,
        "reduced pole": reduced,
        "saturating pole": saturating,
        "every load key": loads,
    }


def _all_specs():
    specs = {path.stem: _example(path.stem) for path in sorted(EXAMPLES.glob("*.toml"))}
    return {**specs, "default": default_spec(), **_specs_with_every_key()}


def _design_keys_given(spec):
    """The table's names of the [design.*] keys ``spec`` gives (a name the spec chooses is *)."""
    given = set()
    for sub, entries in spec.get("design", {}).items():
        if sub == "name":
            given.add("design.name")
        elif sub in ("variables", "limits"):
            given |= {f"design.{sub}.*.{key}" for entry in entries.values() for key in entry}
        elif sub == "targets":
            given |= {"design.targets.*"} if entries else set()
            given |= {
                f"design.targets.*.{key}" for entry in entries.values() if isinstance(entry, dict) for key in entry
            }
        elif sub == "objective":
            given |= {f"design.objective.{key}" for key in entries}
        elif sub == "report":
            given |= {"design.report.*"} if entries else set()
        elif sub == "grids":
            given.add("design.grids")
        elif sub == "tolerances":
            for name, entry in entries.items():
                given.add(f"design.tolerances.{name}" if name in _NAMED_TOLERANCES else "design.tolerances.*")
                if isinstance(entry, dict):
                    given |= {f"design.tolerances.*.{key}" for key in entry}
    return given


def _load(spec):
    """Read ``spec`` as the command does: its scene and loads, its design, its tolerances."""
    scene_from_spec(spec)
    loads_from_spec(spec)
    if "design" in spec:
        problem_from_spec(spec)
    if "tolerances" in spec.get("design", {}):
        tolerance_problem_from_spec(spec)


def _coverage(specs):
    """(keys of the table no spec had read, or given where a design reads by the table's names)."""
    read, given = set(), set()
    for spec in specs.values():
        with recording() as names:
            _load(spec)
        read |= names
        given |= _design_keys_given(spec)
    scene_keys = {name for name in KEYS if not name.startswith("design.")}
    design_keys = set(KEYS) - scene_keys
    return sorted((scene_keys - read) | (design_keys - given))


@pytest.fixture(scope="module")
def specs():
    return _all_specs()


def test_every_key_of_the_table_is_read(specs):
    assert _coverage(specs) == []


def test_the_check_fails_for_a_key_that_no_reader_reads(specs, monkeypatch):
    monkeypatch.setitem(KEYS, "magnet.colour", Key("magnet.colour", "choice", "a colour", default="red"))
    monkeypatch.setitem(KEYS, "design.limits.*.margin", Key("design.limits.*.margin", "quantity", "a margin"))
    assert _coverage(specs) == ["design.limits.*.margin", "magnet.colour"]


def test_a_read_of_a_key_the_table_does_not_list_raises():
    spec = _example("film_hall")
    spec["magnet"]["colour"] = "red"
    with pytest.raises(UnlistedKeyError, match="magnet.colour"):
        Table(spec, "magnet").choice("colour", ("red",))
    with pytest.raises(UnlistedKeyError, match="magnet.colour"):
        Table(spec, "magnet").has("colour")


@pytest.mark.parametrize(
    "read, message",
    [
        (lambda t: t.quantity("period", "T"), "read in T"),  # the table's unit is m
        (lambda t: t.quantity("period", "m", default=0.006), "default"),  # the table: required
        (lambda t: t.integer("period"), "read as integer"),
        (lambda t: t.choice("shape", ("film", "ring")), "ring"),  # a choice the table lacks
    ],
)
def test_a_read_that_disagrees_with_the_table_raises(read, message):
    with pytest.raises(UnlistedKeyError, match=message):
        read(Table(_example("film_hall"), "magnet"))


def test_every_spec_of_the_set_is_accepted(specs):
    """The specs above are good specs (a coverage built on a refused spec would say nothing)."""
    for spec in specs.values():
        _load(spec)


def test_the_effects_listed_are_the_chains():
    assert tuple(KEYS["scene.effects"].choices) == EFFECT_NAMES


def test_every_scene_parameter_is_a_key_with_a_unit(specs):
    """A design variable, a sweep or a tolerance names a scene parameter by its spec key and
    reads it in the key's unit."""
    for spec in specs.values():
        for name in parameters(scene_from_spec(spec)):
            assert listed(name).kind in ("quantity", "quantities", "plane points"), name  # a skin's chips: [x, y] each
            assert listed(name).unit, name


def test_the_tolerance_inputs_read_in_the_tables_units():
    for name, (_, _, unit, _) in EFFECT_INPUTS.items():
        assert KEYS[f"design.tolerances.{name}"].unit == unit


def test_every_preset_builds_its_part():
    presets = KEYS["sensor.preset"].presets
    assert set(presets) == set(KEYS["sensor.preset"].choices)
    # the AK8963's datasheet figures: 0.15 uT per count; the range the design limits at 4.8 mT
    hall = presets["AK8963"]()
    assert float(hall.lsb[0]) == pytest.approx(0.15e-6) and float(hall.full_scale[0]) == pytest.approx(4.8e-3)


def test_the_reference_has_a_row_for_every_key():
    page = markdown()
    sections = page.split("\n## ")
    for key in KEYS.values():
        title = f"[[{key.table}]]" if key.table in ("soft", "magnet.extra", "magnet.magnets") else f"[{key.table}]"
        section = next((s for s in sections if s.startswith(title + "\n")), None)
        assert section is not None, title
        assert f"| `{key.field}` | {key.kind} |" in section, key.name
    # the presets' values, from the parts themselves: the NVE AA003-02's 1.4 mT linear range
    assert "`AA003-02`" in page and "linear_range 1.4 mT" in page
    assert "plain number" in page and "was read as 3 m" in page


def test_the_reference_prints_as_a_module():
    run = subprocess.run([sys.executable, "-m", "magdesign.spec.reference"], capture_output=True, text=True)
    assert run.returncode == 0 and run.stdout == markdown()
