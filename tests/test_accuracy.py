"""magdesign accuracy: the rows' shape, the table and the plot, on the cheap models (the
full run, dome included, is measured by hand: `magdesign accuracy`; the quick tier runs
from the installed wheel in tests/test_installed.py)."""

import json
import tomllib
from pathlib import Path

import pytest

from magdesign import accuracy


@pytest.fixture(scope="module")
def rows():
    return accuracy.measure_layer() + accuracy.measure_area_averaging()


@pytest.mark.slow
def test_rows_carry_error_and_time_and_the_reference_level_is_exact(rows):
    assert [row.fidelity for row in rows] == ["bonded", "hooke", "n=1", "n=4", "n=16", "n=64"]
    assert all(row.seconds > 0 and row.error >= 0 for row in rows)
    assert rows[0].error == 0.0  # bonded is the layer's most exact level
    errors = [row.error for row in rows[2:]]
    assert errors == sorted(errors, reverse=True)  # more Gauss nodes, smaller error
    assert json.loads(json.dumps([row._asdict() for row in rows]))[1]["model"] == "elastomer layer"


def test_table_and_plot(rows, tmp_path):
    assert "sensor area averaging" in accuracy.table(rows)
    path = tmp_path / "accuracy.png"
    accuracy.plot(rows, path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_pole_case_is_the_examples_scene():
    """The accuracy table's pole is the one examples/pole_plate.toml builds (the package holds
    its own copy, since a wheel has no examples/), apart from the levels it measures."""
    example = tomllib.loads((Path(__file__).resolve().parents[1] / "examples" / "pole_plate.toml").read_text())
    for name, table in accuracy.SUSPENSION_POLE.items():
        assert table == {key: example[name][key] for key in table}, name
    assert set(example["pole"]) - set(accuracy.SUSPENSION_POLE["pole"]) == {"fidelity", "cells"}
    assert example["pole"]["cells"] in accuracy.POLE_CELLS  # the example's level is a row of the table
