"""The GMR-inductor sensor: the four GMR readings back to the magnet's 3-D displacement."""

import pathlib
import tomllib

import jax
import numpy as np
import pytest

from magdesign.inverse import InverseStatus, displacement_grid, forward_readings, invert_displacement
from magdesign.scene import scene_from_spec

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
NOISE = 1.4e-3  # V, the example's [scene] noise
RESOLUTION = 20e-6  # m


@pytest.fixture(scope="module")
def solved():
    with open(EXAMPLES / "gmr_inductor.toml", "rb") as file:
        scene = scene_from_spec(tomllib.load(file))
    # 125 displacements over the paper's working range, and reference points on a coarser
    # grid that contains none of them
    side = np.linspace(-2e-3, 2e-3, 5)
    truth = np.asarray(displacement_grid(side, side, np.linspace(0.0, -4e-3, 5)))
    candidates = displacement_grid(*(np.linspace(-3e-3, 3e-3, 4),) * 2, np.linspace(1e-3, -5e-3, 4))
    clean = np.asarray(forward_readings(scene, truth))
    noisy = clean + NOISE * np.asarray(jax.random.normal(jax.random.key(1), clean.shape))
    # far beyond the working range (up to 12 mm sideways, 14 mm down), where GMRs saturate
    wide = truth * np.array([6.0, 6.0, 3.5])
    outside = np.asarray(forward_readings(scene, wide))
    readings = np.stack([clean, noisy, outside])
    inversion = invert_displacement(
        scene, readings, noise=NOISE, resolution=RESOLUTION, candidates=candidates, starts=2
    )
    return truth, wide, inversion


@pytest.mark.slow
def test_noise_free_readings_give_the_displacement_to_1um(solved):
    truth, _, inversion = solved
    assert inversion.displacement.shape == (3, 125, 3)
    assert np.all(inversion.status._value[0] == InverseStatus.successful._value)
    error = np.linalg.norm(inversion.displacement[0] - truth, axis=-1)
    assert error.max() < 1e-6


@pytest.mark.slow  # the solved fixture compiles the example's readings and their inversion
def test_noisy_readings_report_their_error(solved):
    truth, _, inversion = solved
    error = np.asarray(inversion.displacement[1] - truth)
    sigma = np.asarray(inversion.uncertainty[1])
    assert np.all(sigma > 0) and np.all(np.isfinite(sigma))
    # the Jacobian's standard deviation is the actual scatter: error / sigma has unit rms
    rms = np.sqrt(np.mean((error / sigma) ** 2, axis=0))
    assert np.all((rms > 0.7) & (rms < 1.4)), rms
    assert np.all(np.asarray(inversion.chi2[1]) < 25.0)


@pytest.mark.slow  # the solved fixture, as above (the gmr_inductor study inverts in the fast tier)
def test_readings_out_of_range_are_flagged_never_wrong(solved):
    _, wide, inversion = solved
    status = np.asarray(inversion.status._value[2])
    successful = status == InverseStatus.successful._value
    error = np.linalg.norm(inversion.displacement[2] - wide, axis=-1)
    assert np.all(error[successful] < 1e-6)
    assert np.count_nonzero(~successful) > 0
    flagged = ~successful & (error > 1e-6)
    assert np.all(status[flagged] != InverseStatus.not_converged._value)


def test_bad_arguments_name_themselves():
    with pytest.raises(ValueError, match="^solver"):
        invert_displacement(None, np.zeros((4, 1)), noise=1.0, resolution=1.0, solver="newton")
    with pytest.raises(ValueError, match="^candidates"):
        invert_displacement(None, np.zeros((4, 1)), noise=1.0, resolution=1.0, candidates=np.zeros(3))
