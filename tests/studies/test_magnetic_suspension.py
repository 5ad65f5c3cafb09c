"""studies/magnetic_suspension.py in quick mode: its numbers at the method-of-moments level
(the example's 16 cells) and the reduced level against the thesis's (Sajat 2008), and its
verdicts against the published values and tolerances stated here."""

import math

import numpy as np
import pytest
from study_runner import assert_opens_with

NAME = "magnetic_suspension"
DEG = math.pi / 180
UN, MT = 1e-6, 1e-3
UN_PER_DEG = UN / DEG
# Sajat's master's thesis (Wakayama University, 2008): Table 3.1 (unit read as uN/deg), abstract / Sec. 3.1.1, 3.2.2, 3.2.4, 4.3
K_PM_FULL, K_PM_HALF = 0.068 * UN_PER_DEG, 0.215 * UN_PER_DEG
LINEAR_RANGE = 40 * DEG
SENS_PM = 0.3 * MT / DEG
SENS_NIFE = 2.0 * MT / DEG  # Ni-Fe soleplate (condition 1), Hall pair at +-1 mm
K_NIFE_FULL = 0.215 * UN_PER_DEG
INITIAL_FORCE, AIM_FORCE = 12.57 * UN, 1 * UN
GMR_VOLTS_PER_AM = 0.131e-3
# every published number issue 12 lists for this sensor, and the initial model's design rule
# (issue 15), as the first table prints it
PUBLISHED = [
    "+-40 deg",
    "0.068 uN/deg",
    "0.215 uN/deg",
    "0.639 / 0.215 uN/deg",
    "0.3 mT/deg",
    "2 mT/deg",
    "12.57 uN",
    "1 uN",
    "0.131 mV per A/m",
]
# Regression values of the moments level with the example's 16 cells (this study and the
# library's own outputs agree on them; full mode's 32-cell reference differs by a few per
# cent, its convergence table): k, pull, Hall pair, GMR B_x. Tolerance 1e-3 relative: the
# linear solve and the kernels, not the discretisation.
MOMENTS_16 = {
    "spring_coefficient": 4.814e-3,
    "attraction": 2.699e-3,
    "hall_pair_sensitivity": 7.141e-2,
    "gmr_field_sensitivity": 7.398e-2,
}
REGRESSION = 1e-3
# Known gaps, labelled as such (the report's "known gap"): the moments level's k is ~1.2e3
# times Table 3.1 read as uN/deg, its Hall pair ~4 times the thesis's. A band of a factor 2.5
# either way around each: a change of model that moves them out of it must update the report.
K_GAP = (1236 / 2.5, 1236 * 2.5)
HALL_GAP = (4.15 / 2.5, 4.15 * 2.5)
NIFE_SATURATION, FE_SATURATION = 0.8, 2.2  # T: the study's assumption, the thesis's Fe


def test_report_opens_with_every_published_number(results, out):
    assert_opens_with(out, PUBLISHED)


def test_compares_against_the_thesis_numbers(results):
    published = results["published"]
    assert published["k_pm_full"] == pytest.approx(K_PM_FULL)
    assert published["k_pm_half"] == pytest.approx(K_PM_HALF)
    assert published["linear_range"] == pytest.approx(LINEAR_RANGE)
    assert published["sensitivity_pm"] == pytest.approx(SENS_PM)
    assert published["initial_force"] == pytest.approx(INITIAL_FORCE)
    assert published["aim_force"] == pytest.approx(AIM_FORCE)


def test_gmr_preset_reads_the_published_sensitivity(results):
    assert results["gmr_volts_per_am"] == pytest.approx(GMR_VOLTS_PER_AM, rel=1e-6)
    assert results["within_tolerance"]["gmr"] is True


@pytest.mark.parametrize("level", ["moments", "reduced"])
def test_suspension_restores_over_the_published_operating_range(results, level):
    """The thesis's +-40 deg: the pull restores (F theta > 0) all the way, F is odd in theta,
    and k (a central difference at 0) is the small-angle slope."""
    tilt, force = np.array(results["tilt"]), np.array(results[level]["restoring_force"])
    k = results[level]["spring_coefficient"]
    assert k > 0
    inside = (np.abs(tilt) <= LINEAR_RANGE) & (tilt != 0)
    assert np.all(force[inside] * tilt[inside] > 0)
    np.testing.assert_allclose(force, -force[::-1], rtol=0, atol=1e-9 * np.abs(force).max())
    # F at 1 deg is interpolated on the quick grid (2 deg steps): its curvature there is ~8e-4
    assert results[level]["force_at_1deg"] == pytest.approx(k * DEG, rel=2e-3)


def test_moments_level_reproduces_its_regression_values(results):
    moments = results["moments"]
    assert results["cells"] == 16
    for key, value in MOMENTS_16.items():
        assert moments[key] == pytest.approx(value, rel=REGRESSION), key


def test_known_gaps_to_the_thesis_stay_known(results):
    """Not agreement: the gaps the report labels as known, and the reduced level's claim
    (its docstring) that its forces are upper bounds of the finer level's."""
    moments, reduced = results["moments"], results["reduced"]
    assert K_GAP[0] < moments["spring_coefficient"] / K_PM_FULL < K_GAP[1]
    assert HALL_GAP[0] < abs(moments["hall_pair_sensitivity"]) / SENS_PM < HALL_GAP[1]
    assert reduced["spring_coefficient"] > moments["spring_coefficient"]
    assert reduced["attraction"] > moments["attraction"]
    # the initial model's design rule (1 uN at 1 deg) is missed for every assumed magnet
    assert all(level["force_at_1deg"] > AIM_FORCE for level in results["initial_model"]["levels"])


def test_linear_materials_hold_where_the_report_uses_them(results):
    """The rod stays below Ni-Fe's saturation at rest, the initial model's Fe below 2.2 T."""
    assert results["moments"]["peak_polarization"] < NIFE_SATURATION
    assert all(level["peak_polarization"] < FE_SATURATION for level in results["initial_model"]["levels"])


def test_candidate_checks_are_computed_consistently(results):
    """The numbers behind the report's 'where the gap could come from'."""
    k = results["moments"]["spring_coefficient"]
    for reading in results["unit_readings"]:
        assert reading["moments_ratio"] == pytest.approx(k / reading["published"], rel=1e-12)
    uN_per_deg = next(r for r in results["unit_readings"] if r["reading"] == "uN/deg")
    assert uN_per_deg["published"] == pytest.approx(K_PM_FULL)
    # the pull at rest outweighs the rod (7x), which Table 3.1 in uN/deg would not
    pull = results["moments"]["attraction"]
    assert pull > results["weight"] > K_PM_FULL * pull / k
    # k rises with the pole's diameter and falls with the plate's radius (40 mm: still >10x Table 3.1)
    by_diameter = [level["spring_coefficient"] for level in results["pole_diameters"]["levels"]]
    by_plate = [level["spring_coefficient"] for level in results["plate_radii"]["levels"]]
    assert np.all(np.diff(by_diameter) > 0) and np.all(np.diff(by_plate) < 0)
    assert by_plate[-1] > 10 * K_PM_FULL


def test_verdicts_follow_the_published_values_and_tolerances(results):
    """No row may claim agreement that the published number and its tolerance do not give."""
    factor, verdicts = results["tolerance"]["factor"], results["within_tolerance"]
    assert factor == 2.0 and results["tolerance"]["range"] == pytest.approx(5 * DEG)
    within = lambda value, published: 1 / factor <= value / published <= factor  # noqa: E731
    k, k_half = results["moments"]["spring_coefficient"], results["half_pole"]["spring_coefficient"]
    assert verdicts["k_pm_full"] is within(k, K_PM_FULL)
    assert verdicts["k_pm_half"] is within(k_half, K_PM_HALF)
    assert verdicts["k_half_over_full"] is within(k_half / k, K_PM_HALF / K_PM_FULL)
    assert verdicts["sensitivity_pm"] is within(results["moments"]["hall_pair_sensitivity"], SENS_PM)
    assert verdicts["linear_range"] is (abs(results["moments"]["linear_range"] - LINEAR_RANGE) <= 5 * DEG)
    nife = results["nife_soleplate"]["full"]
    assert verdicts["sensitivity_nife"] is within(abs(nife["hall_pair_sensitivity"]), SENS_NIFE)
    assert verdicts["k_nife"] is within(nife["spring_coefficient"], K_NIFE_FULL)
    assert verdicts["k_nife_over_pm"] is within(nife["spring_coefficient"] / k, K_NIFE_FULL / K_PM_FULL)
    assert verdicts["sensitivity_nife_over_pm"] is within(
        abs(nife["hall_pair_sensitivity"] / results["moments"]["hall_pair_sensitivity"]), SENS_NIFE / SENS_PM
    )
    for key in ("gmr_field", "initial_force", "design_rule"):
        assert verdicts[key] is None, key


def test_the_ni_fe_soleplate_restores_and_stays_linear(results):
    """Condition 1 (a magnet pole over a Ni-Fe soleplate): the plate pulls the pole back
    (k > 0) for both poles, the pair reads the tilt, and the plate stays far below Ni-Fe's
    saturation, where its linear level holds."""
    for pole in ("full", "half"):
        level = results["nife_soleplate"][pole]
        assert level["spring_coefficient"] > 0
        assert abs(level["hall_pair_sensitivity"]) > 0
        assert level["peak_polarization"] < 0.5 * NIFE_SATURATION
