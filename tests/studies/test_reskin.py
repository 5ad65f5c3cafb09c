"""studies/reskin.py in quick mode: the board's chips, the model's bounds beside ReSkin's
figures (Bhirangi, Hellebrekers, Majidi and Gupta 2021), the sweep's units, the tolerances'
first-order spreads, the saturation, the design and the eFlesh-like skin (Pattabiraman,
Huang, Panozzo, Zorin, Pinto and Bhirangi 2025), against references computed here by hand. The quick run
compiles the skin's bounds for several structures (minutes on two cores): its tests are slow,
the board's chips are checked in the fast tier without it."""

import pathlib
import re
import tomllib

import numpy as np
import pytest
from study_runner import assert_opens_with, load_study

NAME = "reskin"
MIL = 0.0254e-3  # m per mil (1/1000 inch, exactly 25.4 um)
# The 5X ReSkin board's "Pick Place for PCB.txt" (reskin_sensor repository, circuits/5X_ReSkin.Zip):
# Mid X, Mid Y (mil) of U1 (the middle chip), U3, U5, U2, U4, each a Melexis MLX90393
PICK_PLACE = {
    "U1": (2559.055, 3153.543),
    "U3": (2834.646, 3153.543),
    "U5": (2283.465, 3155.543),
    "U2": (2559.055, 3429.134),
    "U4": (2559.055, 2877.953),
}
# The paper's figures as the first table prints them
PUBLISHED = ["0.1 N", "about 1 mm", "2-3 mm", "5 MLX90393"]
# The study's assumptions, restated: the skin's modulus and Poisson's ratio, the sphere, the
# paper's 0.1 N, ReSkin's J0 and the tolerance of J0
SHEAR_MODULUS, POISSON, SPHERE, FORCE = 100e3, 0.49, 2e-3, 0.1
POLARIZATION, POLARIZATION_TOLERANCE = 0.02, 0.10
# The design's and the yield's press under which no chip may saturate (N)
SATURATION_PRESS = 5.0
EFLESH_EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "examples" / "eflesh.toml"
# eFlesh's abstract: contact localisation RMSE 0.5 mm, force RMSE 0.27 N normal, 0.12 N shear
EFLESH_PUBLISHED = ["0.5 mm RMSE", "0.27 N RMSE", "0.12 N RMSE"]


def board_offsets():
    """The pick-and-place centres (5, 2) (m) relative to U1, in the study's chip order."""
    middle = np.array(PICK_PLACE["U1"])
    return np.array([np.subtract(PICK_PLACE[name], middle) * MIL for name in ("U1", "U3", "U5", "U2", "U4")])


def test_the_studys_board_chips_are_the_pick_and_place_files():
    np.testing.assert_allclose(load_study(NAME).board_chips(), board_offsets(), atol=1e-9)


def test_the_eflesh_like_skin_is_the_example_on_the_boards_chips():
    """The eFlesh-like spec: examples/eflesh.toml (read here with tomllib) with only its chips
    moved, to the pick-and-place file's."""
    study = load_study(NAME)
    spec = study.eflesh_spec(study.board_chips())
    example = tomllib.loads(EFLESH_EXAMPLE.read_text())
    chips = np.array([[float(x.removesuffix(" m")), float(y.removesuffix(" m"))] for x, y in spec["sensor"]["chips"]])
    np.testing.assert_allclose(chips, board_offsets(), atol=1e-9)
    assert {k: v for k, v in spec["sensor"].items() if k != "chips"} == {
        k: v for k, v in example["sensor"].items() if k != "chips"
    }
    assert {k: v for k, v in spec.items() if k != "sensor"} == {k: v for k, v in example.items() if k != "sensor"}


@pytest.mark.slow
def test_report_opens_with_the_papers_figures(results, out):
    assert_opens_with(out, PUBLISHED)


@pytest.mark.slow
def test_the_chips_are_the_boards(results):
    chips = np.array(results["chips"])
    expected = board_offsets()
    assert chips.shape == (5, 2)
    np.testing.assert_allclose(chips, expected, atol=1e-9)
    # 275.59 mil apart: a cross at 7.000 mm (the example spec's 10 mm is not the board's)
    assert results["pitch"] == pytest.approx(7.0e-3, abs=1e-5)


@pytest.mark.slow
def test_contact_radius_is_hertzs(results):
    young = 2 * SHEAR_MODULUS * (1 + POISSON)
    reduced = young / (1 - POISSON**2)
    radius = (3 * FORCE * SPHERE / (4 * reduced)) ** (1 / 3)
    assert results["contact_radius"] == pytest.approx(radius, rel=1e-12)
    assert radius == pytest.approx(0.7259e-3, rel=1e-3)  # by hand: (3 * 0.1 * 2e-3 / (4 * 392.16e3)) ** (1/3)


@pytest.mark.slow
def test_the_bounds_are_set_beside_the_papers_learned_figures(results):
    """The report's verdict at quick mode's corner map (a regression of the pipeline: the
    values below are this model's, recorded, not ReSkin's): with the assumed noise and J0 the
    3-sigma normal-force bound is 246 mN, above the paper's 0.1 N, and the worst localisation
    2.03 mm, above its 1 mm (the paper's figures are a learned model's, read differently);
    the outputs are in SI."""
    outputs = results["outputs"]
    assert 3 * outputs["force_resolution_normal"] == pytest.approx(0.246, rel=0.05)  # regression
    assert 0 < outputs["localisation_median"] <= outputs["localisation_worst"]
    assert outputs["localisation_worst"] == pytest.approx(2.03e-3, rel=0.05)  # regression
    assert results["units"]["force_resolution_normal"] == "N"
    assert results["units"]["localisation_worst"] == "m"


@pytest.mark.slow
def test_the_sweep_table_prints_its_units(results, out):
    """Each row of the report's sweep table shows the SI results in its headers' units (mm, mN, um)."""
    lines = (out / "report.md").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| pitch (mm) |"))
    header = [cell.strip() for cell in lines[start].strip("|").split("|")]
    rows = results["sweep"]
    assert len(lines[start + 2 : start + 2 + len(rows)]) == len(rows)
    for line, row in zip(lines[start + 2 :], rows):
        cells = dict(zip(header, (cell.strip() for cell in line.strip("|").split("|"))))
        assert float(cells["pitch (mm)"]) == pytest.approx(row["pitch"] * 1e3, rel=1e-3)
        assert float(cells["thickness (mm)"]) == pytest.approx(row["thickness"] * 1e3, rel=1e-3)
        value = float(re.match(r"[-0-9.e+]+", cells["normal force (mN)"]).group())
        assert value == pytest.approx(row["force_resolution_normal"] * 1e3, rel=5e-3)
        value = float(re.match(r"[-0-9.e+]+", cells["localisation worst (um)"]).group())
        assert value == pytest.approx(row["localisation_worst"] * 1e6, rel=5e-3)


@pytest.mark.slow
def test_the_sweeps_board_pitch_agrees_with_the_board(results):
    """The sweep's ideal cross at 7 mm and 2 mm (the chips moved in one compiled scene) against
    the board's own chips (U5 sits 2 mil off the axis) built from the spec: the same skin to a
    few per cent (2 % apart in quick mode, where the coarse map's corners feel U5's offset)."""
    row = next(r for r in results["sweep"] if abs(r["pitch"] - 7e-3) < 1e-9 and abs(r["thickness"] - 2e-3) < 1e-9)
    for name in ("force_resolution_normal", "localisation_worst", "saturation_ratio"):
        assert row[name] == pytest.approx(results["outputs"][name], rel=0.05), name


@pytest.mark.slow
def test_the_tolerance_of_j0_spreads_the_bounds_by_its_own_share(results):
    """The readings are linear in J0, so a bound c / J0 spreads by the relative tolerance of
    J0 to first order: 10 % of the bound (the library's first-order parts are derivatives,
    exact to rounding)."""
    for name in ("force_resolution_normal", "localisation_worst", "background_force_error"):
        part = results["spread"][name]["magnet.polarization"]
        assert part == pytest.approx(POLARIZATION_TOLERANCE * results["outputs"][name], rel=1e-6), name
        assert results["spread"][name]["total"] >= part
    spread = [row for row in results["sweep"] if row["sigma"] is not None]
    assert spread
    for row in spread:
        part = row["sigma"]["force_resolution_normal"]["magnet.polarization"]
        assert part == pytest.approx(POLARIZATION_TOLERANCE * row["force_resolution_normal"], rel=1e-6)


@pytest.mark.slow
def test_the_design_halves_the_bound_at_twice_j0(results):
    design = results["design"]
    assert design["status"] == "successful"
    # the bound scales as 1 / J0: half of it at twice ReSkin's J0
    assert design["parameters"]["magnet.polarization"] == pytest.approx(2 * POLARIZATION, rel=1e-3)
    assert design["checked"]["force_resolution_normal"] == pytest.approx(design["target"], rel=1e-3)
    assert design["target"] == pytest.approx(results["outputs"]["force_resolution_normal"] / 2, rel=1e-12)
    assert design["checked"]["saturation_ratio"] <= 1


@pytest.mark.slow
def test_the_saturation_is_the_skins_output(results, out):
    """saturation_force is among the study's outputs and printed in its table (N); at ReSkin's
    design no press up to the 1 kN cap saturates a chip (a regression of this model, as
    docs/skins.md finds for examples/skin.toml: a press moves the readings by about 1e-3 of
    the range per 0.2 N), and the report says so rather than extrapolating a force."""
    assert results["units"]["saturation_force"] == "N"
    assert results["outputs"]["saturation_force"] == pytest.approx(1e3, rel=1e-12)  # regression: the cap
    report = (out / "report.md").read_text()
    assert re.search(r"^\| saturation_force \| 1000 \| N \|$", report, re.MULTILINE)
    assert "No press up to 1 kN saturates a chip" in report
    # J0 / saturation_ratio: the readings are linear in J0 (the Earth's 50 uT aside)
    saturation = results["saturation"]
    assert saturation["polarization"] == pytest.approx(POLARIZATION / results["outputs"]["saturation_ratio"], rel=1e-12)
    # the Hertz patch reaches a / h = 0.5 where (3 F R / (4 E*))^(1/3) = 1 mm for the 2 mm layer
    young = 2 * SHEAR_MODULUS * (1 + POISSON)
    reduced = young / (1 - POISSON**2)
    assert saturation["reach"] == pytest.approx(4 * reduced * (1e-3) ** 3 / (3 * SPHERE), rel=1e-9)


@pytest.mark.slow
def test_the_design_keeps_the_chips_in_range_under_the_press(results):
    assert results["design"]["checked"]["saturation_force"] >= SATURATION_PRESS


@pytest.mark.slow
def test_the_eflesh_like_skin_is_set_beside_efleshs_figures(results, out):
    """The eFlesh section's table prints eFlesh's published RMSEs; its press's Hertz radius is
    the example's by hand (G = 100 kPa, nu = 0.3, a 5 mm sphere at 0.5 N); the bounds (a
    regression of this model at the example's assumptions, over the board's chips) lie below
    the published RMSEs."""
    report = (out / "report.md").read_text()
    section = report[report.index("## An eFlesh-like skin") :]
    for value in EFLESH_PUBLISHED:
        assert f"| {value} |" in section, value
    skin = results["eflesh"]
    assert skin["published"] == pytest.approx({"localisation": 0.5e-3, "normal": 0.27, "shear": 0.12})
    reduced = 2 * 100e3 * (1 + 0.3) / (1 - 0.3**2)
    assert skin["contact_radius"] == pytest.approx((3 * 0.5 * 5e-3 / (4 * reduced)) ** (1 / 3), rel=1e-12)
    assert skin["contact_radius"] == pytest.approx(1.872e-3, rel=1e-3)  # by hand: (6.5625e-9) ** (1/3)
    outputs = skin["outputs"]
    assert outputs["localisation_worst"] == pytest.approx(231e-6, rel=0.05)  # regression
    assert outputs["force_resolution_normal"] == pytest.approx(10.7e-3, rel=0.05)  # regression
    assert outputs["force_resolution_shear"] == pytest.approx(9.25e-3, rel=0.05)  # regression
    assert outputs["localisation_worst"] < 0.5e-3
    assert outputs["force_resolution_normal"] < 0.27
    assert outputs["force_resolution_shear"] < 0.12
    assert 0 < outputs["saturation_force"] < 1e3
