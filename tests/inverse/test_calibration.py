"""Calibration: a dome-Hall scene's Br and c10 recovered from synthetic data."""

import dataclasses
import pathlib
import tomllib

import numpy as np
import optimistix as optx

from magdesign.inverse import calibrate
from magdesign.scene import Loads, parameters, scene_from_spec, simulate, with_parameters

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples"
NAMES = ("magnet.remanence", "mechanics.c10")


def test_br_and_c10_perturbed_by_10_percent_are_recovered():
    with open(EXAMPLES / "dome_hall.toml", "rb") as file:
        spec = tomllib.load(file)
    # Br scales the field, c10 the displacement (through E = 6 (c10 + c01)): the on-axis
    # readings over a press depend on both separately
    # the Hall sensor sits on the axis: the on-axis closed form is its exact field
    truth = dataclasses.replace(scene_from_spec(spec, fidelity="reissner"), effects=(), fidelity="axis")
    loads = Loads(np.linspace(0.0, 5.0, 6))
    readings = simulate(truth, loads).readings
    true_values = parameters(truth)
    start = with_parameters(truth, {name: 1.1 * true_values[name] for name in NAMES})
    fit = calibrate(start, NAMES, loads, readings, noise=1e-6)
    assert fit.result == optx.RESULTS.successful
    for name in NAMES:
        assert abs(float(fit.values[name]) / float(true_values[name]) - 1.0) < 1e-6, name
        assert 0.0 < float(fit.uncertainty[name]) < 1e-3 * float(true_values[name])
    assert np.max(np.abs(fit.residuals)) < 1e-12
