"""Plain numbers are SI, and say so when they look wrong.

A plain number (no unit string) outside its key's plausible range is read in SI with a
warning that names the key and the unit it was read in, and the unit that was likely meant;
the same for a design variable's bounds. The command shows it as one line on stderr.
"""

import copy
import pathlib
import tomllib
import warnings

import pytest

from magdesign.cli import main
from magdesign.scene import loads_from_spec, scene_from_spec
from magdesign.spec.checks import PlausibilityWarning
from magdesign.spec.design import default_spec, problem_from_spec

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"


def _film():
    with open(EXAMPLES / "film_hall.toml", "rb") as file:
        return tomllib.load(file)


def _warnings(read, spec):
    """The distinct PlausibilityWarnings of ``read(spec)``, as strings (a table read twice,
    as the loads are by the scene and by the chain, warns twice; the command shows it once)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        read(spec)
    return list(dict.fromkeys(str(w.message) for w in caught if issubclass(w.category, PlausibilityWarning)))


def _read(spec):
    return _warnings(lambda s: (scene_from_spec(s), loads_from_spec(s)), spec)


@pytest.mark.parametrize(
    "table, key, value, message",
    [
        # 3 read as metres: 3 mm is a layer's thickness
        ("mechanics", "thickness", 3, 'mechanics.thickness = 3 was read as 3 m; write "3 mm" for millimetres'),
        # 85 read as tesla: 85 mT is the film's polarisation
        ("magnet", "magnetization", 85, 'magnet.magnetization = 85 was read as 85 T; write "85 mT" for millitesla'),
        # 83 read as pascals, softer than any elastomer: 83 kPa is Ecoflex's modulus
        (
            "mechanics",
            "youngs_modulus",
            83,
            'mechanics.youngs_modulus = 83 was read as 83 Pa; write "83 kPa" for kilopascals',
        ),
        # a force of 20 kN on a fingertip sensor: 20000 mN is 20 N
        ("load", "normal", [0, 20000], 'load.normal = 20000 was read as 20000 N; write "20000 mN" for millinewtons'),
    ],
)
def test_an_implausible_plain_number_warns_naming_the_key_and_unit(table, key, value, message):
    spec = _film()
    spec[table][key] = value
    assert _read(spec) == [message]


def test_plain_numbers_in_range_and_dimensionless_ones_warn_nothing():
    spec = _film()
    spec["mechanics"]["thickness"] = 0.0035  # 3.5 mm, SI
    spec["mechanics"]["poisson_ratio"] = 0.49  # dimensionless
    spec["load"]["normal"] = [0, 2]  # 2 N
    assert _read(spec) == []


def test_a_value_with_a_unit_is_never_second_guessed_but_real_parts_still_warn():
    spec = _film()
    spec["mechanics"]["thickness"] = "3 m"  # written as metres: meant
    assert _read(spec) == []
    spec["magnet"]["magnetization"] = "1.8 T"  # above NdFeB
    assert _read(spec) == [
        "magnet.magnetization: 1.8 T is far outside real parts (the strongest permanent "
        "magnets (NdFeB) reach about 1.5 T)"
    ]


def test_a_design_variables_bounds_are_checked_as_the_scene_value():
    spec = copy.deepcopy(default_spec())
    spec["design"]["variables"]["mechanics.thickness"] = {"lower": 0.0015, "upper": 4}
    assert _warnings(problem_from_spec, spec) == [
        'design.variables.mechanics.thickness.upper = 4 was read as 4 m; write "4 mm" for millimetres'
    ]


def test_a_designs_plain_targets_and_limits_are_checked_in_their_outputs_unit():
    """compliance = 0.32 is 0.32 m/N and field_max <= 4.8 is 4.8 T: both warn, naming the
    key, the SI unit they were read in and the unit likely meant; 0.00032 and 0.0048 do not."""
    spec = copy.deepcopy(default_spec())
    spec["design"]["targets"]["compliance"] = 0.32
    spec["design"]["limits"]["field_max"] = {"upper": 4.8}
    assert _warnings(problem_from_spec, spec) == [
        'design.targets.compliance = 0.32 was read as 0.32 m/N; write "0.32 mm/N" for millimetres per newton',
        'design.limits.field_max.upper = 4.8 was read as 4.8 T; write "4.8 mT" for millitesla',
    ]
    spec["design"]["targets"]["compliance"] = 0.00032
    spec["design"]["limits"]["field_max"] = {"upper": 0.0048}
    assert _warnings(problem_from_spec, spec) == []


def _scene_spec(tmp_path, old, new):
    """examples/film_hall.toml's scene (no [design]) with ``old`` replaced by ``new``."""
    text = (EXAMPLES / "film_hall.toml").read_text().split("\n[design")[0]
    assert old in text
    path = tmp_path / "film.toml"
    path.write_text(text.replace(old, new))
    return str(path)


def test_simulate_warns_on_one_line_for_a_plain_thickness_of_3(tmp_path, capsys):
    spec = _scene_spec(tmp_path, 'thickness = "3.5 mm"', "thickness = 3")
    main(["simulate", spec])
    err = capsys.readouterr().err
    assert 'magdesign: warning: mechanics.thickness = 3 was read as 3 m; write "3 mm" for millimetres\n' in err


def test_simulate_of_a_sensible_spec_warns_nothing(capsys):
    """The GMR-inductor example: plain numbers where they are dimensionless (turns, gains),
    units everywhere else, and readings inside the amplifier's rail."""
    assert main(["simulate", str(EXAMPLES / "gmr_inductor.toml")]) == 0
    assert "warning" not in capsys.readouterr().err


def test_a_swept_value_outside_its_domain_is_a_bad_spec(capsys):
    assert main(["sweep", str(EXAMPLES / "dome_hall.toml"), "--over", "mechanics.outer_radius=-8mm:10mm:3"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "mechanics.outer_radius" in err and "not physical" in err
