"""Hostile input at load time: each ends in one line and exit 2 before any work (swept
values checked as spec values, sizes that cannot fit, impossible geometry, loads the model
does not carry, tolerances whose draws leave the physical domain), and a report that names
the rows it breaks."""

import json
from pathlib import Path

import pytest

import magdesign.cli as cli
import magdesign.spec.tolerance as tolerance
from magdesign.cli import main
from magdesign.design.report import _missed
from magdesign.scene import scene_from_spec
from magdesign.spec import sizes
from magdesign.spec.design import load_spec, problem_from_spec
from magdesign.spec.tolerance import tolerance_problem_from_spec
from magdesign.units import SpecError

EXAMPLES = Path(__file__).parents[1] / "examples"
DOME = (EXAMPLES / "dome_hall.toml").read_text()
TOLERANCES = (EXAMPLES / "dome_hall_tolerances.toml").read_text()


def _spec(tmp_path, text, *replacements, name="hostile.toml"):
    for old, new in replacements:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def _refused(capsys, argv, *fragments):
    """``argv`` exits 2 with one line on stderr holding every fragment, and no traceback."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    last = err.splitlines()[-1]
    assert "Traceback" not in err
    for fragment in fragments:
        assert fragment in last, (fragment, err)
    return err


# --- sweeps: every swept value passes the checks of a spec value ---


@pytest.mark.parametrize(
    "over, fragments",
    [
        ("mechanics.outer_radius=-8mm:10mm:3", ("mechanics.outer_radius", "not physical")),
        ("magnet.remanence=0T:1.2T:3", ("magnet.remanence", "not physical")),
        # 2 mm is positive, but a 2 mm wall does not fit in a 2 mm dome (the spec's guard)
        ("mechanics.outer_radius=2mm:9mm:3", ("mechanics.outer_radius = 2 mm", "mechanics.thickness")),
        # 9 mm is positive, but wider than the 8 mm dome that carries the magnet
        ("magnet.radius=1mm:9mm:2", ("magnet.radius = 9 mm", "wider than the dome")),
    ],
)
def test_a_swept_value_is_checked_as_a_spec_value(capsys, over, fragments):
    _refused(capsys, ["sweep", str(EXAMPLES / "dome_hall.toml"), "--over", over, "--fidelity", "reissner"], *fragments)


@pytest.mark.parametrize(
    "content, fragments",
    [
        ("mechanics.outer_radius\n8 mm\n-8 mm\n", ("line 3", "mechanics.outer_radius", "not physical")),
        ("mechanics.outer_radius\n8 mm\n2 mm\n", ("mechanics.outer_radius = 2 mm", "mechanics.thickness")),
        ("compliance,compliance\n0.3 mm/N,0.3 mm/N\n", ("compliance is swept twice",)),
        (b"\x7fELF\x02\x01\x01\x00\x00\x00\xff\xfe\x80\x81", ("points.csv", "not a CSV text file")),
    ],
)
def test_a_points_file_is_checked_as_the_over_option(tmp_path, capsys, content, fragments):
    path = tmp_path / "points.csv"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    argv = ["sweep", str(EXAMPLES / "dome_hall.toml"), "--points", str(path), "--fidelity", "reissner"]
    _refused(capsys, argv, *fragments)


# --- sizes that cannot fit are refused at load; large ones warn ---


@pytest.fixture
def sixteen_gigabytes(monkeypatch):
    """A machine with 16 GB available, whatever this one has."""
    monkeypatch.setattr(sizes, "available_bytes", lambda: 16 * 2**30)


@pytest.mark.parametrize(
    "replacements, fragments",
    [
        ([("points = 11", "points = 100000000")], ("load.points = 100000000", "GB")),
        (
            [
                ('preset = "AK8963"', 'preset = "AK8963"\ngrid = [3000, 3000]\npitch = "1 mm"'),
                ('fidelity = "axis"', 'fidelity = "exact"'),
            ],
            ("9000000 sensors", "field samples", "GB"),
        ),
        (
            [
                ('effects = ["saturation", "quantisation"]', 'effects = ["area_averaging"]\nquadrature = 10000'),
                ('fidelity = "axis"', 'fidelity = "exact"'),
            ],
            ("scene.quadrature = 10000", "GB"),
        ),
    ],
)
@pytest.mark.slow
def test_a_size_that_cannot_fit_is_refused_at_load(tmp_path, capsys, sixteen_gigabytes, replacements, fragments):
    path = _spec(tmp_path, DOME, *replacements)
    for command in ("simulate", "solve"):
        _refused(
            capsys, [command, path, "--fidelity", "reissner"] if command == "solve" else [command, path], *fragments
        )


def test_a_sweep_too_large_to_hold_is_refused(capsys, sixteen_gigabytes):
    argv = ["sweep", str(EXAMPLES / "dome_hall.toml"), "--over", "compliance=0.2mm/N:0.4mm/N:10000000000"]
    _refused(capsys, argv + ["--fidelity", "reissner"], "compliance", "GB")


def test_the_estimate_is_elements_times_eight_bytes_times_the_factor(monkeypatch):
    monkeypatch.setattr(sizes, "available_bytes", lambda: 8 * 32 * 1000)
    sizes.check_fits("n = 1000", 1000)  # exactly fits: 1000 values x 8 bytes x 32 copies
    with pytest.raises(SpecError, match=r"n = 1001: its arrays take about"):
        sizes.check_fits("n = 1001", 1001)
    monkeypatch.setattr(sizes, "available_bytes", lambda: None)  # unknown memory: no refusal
    with pytest.warns(sizes.SizeWarning, match="long run"):
        sizes.check_fits("n", 2 * sizes.SLOW_ELEMENTS)


def test_soft_cells_that_cannot_fit_are_refused(tmp_path, capsys, sixteen_gigabytes):
    text = (EXAMPLES / "pole_plate.toml").read_text()
    path = _spec(tmp_path, text, ("cells = 16", "cells = 1000"))
    _refused(capsys, ["simulate", path], "pole.cells = 1000", "interaction matrix")


# --- impossible geometry ---

SOFT_SCENE = """
[magnet]
shape = "cylinder"
radius = "1.5 mm"
height = "1 mm"
remanence = "1.17 T"
[mechanics]
model = "layer"
thickness = "10 mm"
contact_area = "100 mm^2"
material = "linear"
youngs_modulus = "1 MPa"
poisson_ratio = 0.45
[sensor]
model = "hall3d"
preset = "AK8963"
[geometry]
gap = "5 mm"
[load]
normal = ["0 N", "1 N"]
points = 3
[[soft]]
shape = "sphere"
size = "4 mm"
permeability = 1000
position = ["0 mm", "10 mm", "0 mm"]
"""

ROD = """[[soft]]
shape = "cylinder"
size = ["1 mm", "10 mm"]
permeability = 1000
position = ["0 mm", "{y}", "0 mm"]
"""


def test_a_rod_inside_a_ball_overlaps_it(tmp_path, capsys):
    """A 10 mm rod through the centre of a 4 mm ball overlaps it; 20 mm apart it does not."""
    _refused(capsys, ["simulate", _spec(tmp_path, SOFT_SCENE + ROD.format(y="10 mm"))], "soft[1]", "overlaps soft[0]")
    scene_from_spec(load_spec(_spec(tmp_path, SOFT_SCENE + ROD.format(y="30 mm"))))  # built: apart


def test_a_soft_part_inside_the_magnet_is_refused(tmp_path, capsys):
    # the magnet's centre is 5.5 mm above the chip: gap + height / 2
    text = SOFT_SCENE.replace('position = ["0 mm", "10 mm", "0 mm"]', 'position = ["0 mm", "0 mm", "5.5 mm"]')
    _refused(capsys, ["simulate", _spec(tmp_path, text)], "soft[0]", "overlaps the magnet")


@pytest.mark.parametrize(
    "replacements, fragments",
    [
        ([('radius = "1.5 mm"', 'radius = "20 mm"')], ("magnet.radius", "20 mm", "outer_radius = 8 mm")),
        # the magnet spans 7.4 to 8.4 mm above the chip, on the axis
        (
            [('preset = "AK8963"', 'preset = "AK8963"\npositions = [["0 mm", "0 mm", "7.8 mm"]]')],
            ("sensor.positions", "[0, 0, 7.8] mm", "inside the magnet"),
        ),
        (
            [('"geometry.gap" =', '"magnet.radius" = { lower = "1 mm", upper = "9 mm" }\n"geometry.gap" =')],
            ("design.variables.magnet.radius.upper", "9 mm"),
        ),
        ([('normal = ["0 N", "5 N"]', 'normal = ["0 N", "5 N"]\nshear_x = ["0 N", "1e6 N"]')], ("load.shear_x",)),
    ],
)
def test_impossible_geometry_and_loads_are_refused(tmp_path, capsys, replacements, fragments):
    path = _spec(tmp_path, DOME, *replacements)
    _refused(capsys, ["solve", path, "--fidelity", "reissner"], *fragments)


def test_a_plain_radius_in_metres_warns_and_is_refused_on_its_dome(tmp_path, capsys):
    """radius = 1.5 is 1.5 m: the plain-number warning says so, and the magnet is wider
    than its 8 mm dome."""
    err = _refused(
        capsys, ["solve", _spec(tmp_path, DOME, ('radius = "1.5 mm"', "radius = 1.5")), "--fidelity", "reissner"]
    )
    assert "magnet.radius = 1.5 was read as 1.5 m" in err and "wider than the dome" in err


def test_a_rod_wider_than_its_ball_is_refused(tmp_path, capsys):
    text = (EXAMPLES / "pole_plate.toml").read_text()
    _refused(
        capsys, ["simulate", _spec(tmp_path, text, ('diameter = "1.2 mm"', 'diameter = "10 mm"'))], "pole.diameter"
    )


def test_a_plain_number_warns_once(tmp_path, capsys):
    path = _spec(tmp_path, DOME, ('outer_radius = "8 mm"', "outer_radius = 8"))
    assert main(["simulate", path]) == 2  # an 8 m dome does not carry the magnet 7.4 mm up
    assert capsys.readouterr().err.count("mechanics.outer_radius = 8 was read as 8 m") == 1


# --- tolerances: one rule for solve and tolerance; draws stay in the physical domain ---


def test_a_negative_target_tolerance_is_refused_by_solve_and_tolerance(tmp_path, capsys):
    path = _spec(tmp_path, TOLERANCES, ('tolerance = "5 %"', 'tolerance = "-5 %"'))
    for argv in (["solve", path, "--fidelity", "reissner"], ["tolerance", path, "--samples", "10"]):
        _refused(capsys, argv, "design.targets.compliance.tolerance", "-5 %")


@pytest.mark.parametrize(
    "entry, refused",
    [
        ('"magnet.remanence" = "500 %"', True),
        ('"mechanics.c10" = "300 %"', True),
        ('"magnet.remanence" = "40 %"', True),  # 3 sigma reach 1 - 1.2 = -0.2 of the value
        ('"magnet.remanence" = "30 %"', False),  # 3 sigma reach 0.1 of the value
        ('"magnet.remanence" = { value = "100 %", distribution = "uniform" }', True),  # reaches 0 itself
        ('"magnet.remanence" = { value = "90 %", distribution = "uniform" }', False),
    ],
)
def test_a_tolerance_whose_draws_leave_the_domain_is_refused(tmp_path, entry, refused):
    name = entry.split(" = ")[0].strip('"')
    text = TOLERANCES.replace('"magnet.remanence" = "2 %"', "").replace('"mechanics.c10" = "5 %"', "")
    spec = load_spec(_spec(tmp_path, text.replace("[design.tolerances]", f"[design.tolerances]\n{entry}")))
    if refused:
        with pytest.raises(SpecError, match=rf"design\.tolerances\.{name}.*physical domain \(0, inf\)"):
            tolerance_problem_from_spec(spec)
    else:
        tolerance_problem_from_spec(spec)


def test_solve_refuses_a_tolerance_that_the_tolerance_command_refuses(tmp_path, capsys):
    path = _spec(tmp_path, TOLERANCES, ('"magnet.remanence" = "2 %"', '"magnet.remanence" = "500 %"'))
    for argv in (["solve", path, "--fidelity", "reissner"], ["tolerance", path, "--samples", "10"]):
        _refused(capsys, argv, "design.tolerances.magnet.remanence", "physical domain")


def test_solve_builds_a_toleranced_spec_once(tmp_path, monkeypatch, capsys):
    """solve reads [design.tolerances] on the problem it built: the spec stage runs once."""
    built = []

    def counted(spec, **options):
        built.append(options)
        return problem_from_spec(spec, **options)

    def stop(*args):
        raise RuntimeError("stopped before the solve")

    monkeypatch.setattr(cli, "problem_from_spec", counted)
    monkeypatch.setattr(tolerance, "problem_from_spec", counted)
    monkeypatch.setattr(cli, "_solve_at_levels", stop)
    path = _spec(tmp_path, TOLERANCES)
    assert main(["solve", path, "--fidelity", "reissner"]) == 1  # the internal error of `stop`
    assert "stopped before the solve" in capsys.readouterr().err
    assert built == [{"fidelity": "reissner"}]


# --- the report names exactly the rows it breaks ---


def test_a_miss_smaller_than_six_digits_is_shown():
    # 0.32000000471 mm/N against 0.32 mm/N: equal to 8 digits, told apart at the 9th
    assert _missed(0.32000000471e-3, 0.32e-3, "mm/N") == "0.320000005 mm/N"
    assert _missed(0.0794752e-3, 0.32e-3, "mm/N") == "0.0794752 mm/N"


def test_a_violated_limit_says_so(tmp_path, capsys):
    """A field_max bound no gap of the box meets: the table marks the limit VIOLATED, and the
    status names exactly the rows the table marks."""
    path = _spec(tmp_path, DOME, ('field_max = { upper = "4.8 mT" }', 'field_max = { upper = "0.1 mT" }'))
    assert main(["solve", path, "--fidelity", "reissner"]) == 3
    table = capsys.readouterr().out
    assert main(["solve", path, "--fidelity", "reissner", "--json"]) == 3
    result = json.loads(capsys.readouterr().out)
    assert "field_max.upper" in result["violated"]
    # the answer's table: its indented rows before the estimates' section ("levels: ...")
    answer = table.split("\nlevels: ")[0]
    rows = {line.split()[0]: line.split()[-1] for line in answer.splitlines() if line.startswith("  ")}
    assert rows["field_max"] == "VIOLATED"
    for name in result["targets"]:
        assert (rows[name] == "no") == (name in result["violated"]), name
    for name in result["limits"]:
        broken = any(f"{name}.{side}" in result["violated"] for side in ("upper", "lower"))
        assert (rows[name] == "VIOLATED") == broken, name
    assert f"(not met: {', '.join(result['violated'])})" in table


# --- every solid part: sensors outside, bodies apart, the magnet on its layer ---

GMR = (EXAMPLES / "gmr_inductor.toml").read_text()
POLE = (EXAMPLES / "pole_plate.toml").read_text()


@pytest.mark.parametrize(
    "text, replacements, fragments",
    [
        # a rod beside the ball's centre, 4 mm up: it spans -1 to 9 mm and runs through the ball
        (SOFT_SCENE + ROD.format(y="10 mm").replace('"0 mm"]\n', '"4 mm"]\n'), [], ("soft[1]", "overlaps soft[0]")),
        # the chip at the origin inside a 1 mm ball of iron
        (SOFT_SCENE, [('position = ["0 mm", "10 mm", "0 mm"]', 'position = ["0 mm", "0 mm", "0 mm"]')], ("sensor:",)),
        # the first inductor moved into the 1 mm magnet, whose faces are 15 and 16 mm above the substrate
        (GMR, [('[["9 mm", "9 mm", "-1 mm"]', '[["0 mm", "0 mm", "15.5 mm"]')], ("inductors.positions", "the magnet")),
        # the magnet moved 16 mm down by its offset, into the board under the layer
        (
            GMR,
            [('remanence = "1.2 T"', 'remanence = "1.2 T"\noffset = ["0 mm", "0 mm", "-16 mm"]')],
            ("magnet.offset",),
        ),
        # the magnet moved 10 mm up, off its 15 mm layer
        (GMR, [('remanence = "1.2 T"', 'remanence = "1.2 T"\noffset = ["0 mm", "0 mm", "10 mm"]')], ("magnet.offset",)),
        # the GMR 1 mm above the plate, 0.5 mm off the axis: inside the 2 mm ball whose bottom is 0.4 mm up
        (POLE, [('height = "0.1 mm"', 'height = "1 mm"')], ("sensor.height", "the ball")),
    ],
)
def test_sensors_outside_and_bodies_apart(tmp_path, capsys, text, replacements, fragments):
    _refused(capsys, ["simulate", _spec(tmp_path, text, *replacements)], *fragments)
