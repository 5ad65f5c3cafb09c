"""The magdesign command: JSON contract, exit codes, one-line errors."""

import importlib.util
import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from magdesign._cache import cpu_tag
from magdesign.cli import main

EXAMPLES = Path(__file__).parents[1] / "examples"


@pytest.mark.slow
def test_solve_default_prints_the_json_contract(capsys, tmp_path):
    """The default (--fidelity auto): solved with the Reissner dome, confirmed with the
    axisymmetric one; both answers, with their levels, units and the objective's value.
    --write writes the answer at its (axisymmetric) levels: its simulation gives the
    targets and limits reported."""
    written = tmp_path / "solved.toml"
    assert main(["solve", "--json", "--write", str(written)]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    assert f"wrote {written}" in captured.err
    assert result["status"] == "successful"
    assert set(result) >= {"status", "parameters", "targets", "steps", "seconds"}
    assert result["parameters"]["geometry.gap"] == pytest.approx(7.4458e-3, abs=1e-7)
    assert result["targets"]["compliance"]["target"] == pytest.approx(0.32e-3)
    assert isinstance(result["steps"], int) and result["seconds"] > 0
    assert result["fidelity"] == "dome axisymmetric, field axis"
    first = result["first_level"]
    assert first["fidelity"] == "dome reissner, field axis" and first["status"] == "successful"
    # the wall differs between the dome models (Reissner: 2.142 mm), the gap not
    assert first["parameters"]["mechanics.thickness"] == pytest.approx(2.1422e-3, abs=1e-7)
    assert abs(result["parameters"]["mechanics.thickness"] - first["parameters"]["mechanics.thickness"]) > 2e-5
    assert result["units"]["geometry.gap"] == "mm" and result["units"]["sensitivity"] == "mT/N"
    assert result["objective"] == {"output": "sensitivity", "sense": "max", "value": result["outputs"]["sensitivity"]}
    assert result["total_seconds"] >= result["seconds"] + first["seconds"]
    assert written.read_text().startswith("# solved by magdesign ")
    assert tomllib.loads(written.read_text())["mechanics"]["fidelity"] == "axisymmetric"
    assert main(["simulate", str(written), "--json"]) == 0
    simulated = json.loads(capsys.readouterr().out)["outputs"]
    for name, entry in {**result["targets"], **result["limits"]}.items():
        assert simulated[name] == pytest.approx(entry["achieved"], rel=1e-9, abs=0), name


@pytest.mark.slow
def test_solve_table_and_plot(capsys, tmp_path):
    """The report says what was designed (name, magnet, mechanics, chip) above the table,
    names the objective, and gives the total time; --write writes the answer, which
    simulate and show then read at the solved gap."""
    plot, written = tmp_path / "design.png", tmp_path / "solved.toml"
    assert (
        main(
            [
                "solve",
                str(EXAMPLES / "dome_hall.toml"),
                "--fidelity",
                "reissner",
                "--plot",
                str(plot),
                "--write",
                str(written),
            ]
        )
        == 0
    )
    captured = capsys.readouterr()
    out = captured.out
    lines = out.splitlines()
    assert lines[0] == "dome_hall: cylinder magnet, mooney_rivlin dome, AK8963 hall3d chip"
    assert "geometry.gap" in out and "successful" in out
    assert any(line.split()[:2] == ["maximize", "sensitivity"] for line in lines)
    assert any(line.startswith("total time: ") for line in lines)
    assert {f"magdesign solve: wrote {written}", f"magdesign solve: wrote {plot}"} <= set(captured.err.splitlines())
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    spec = tomllib.loads(written.read_text())
    gap = float(spec["geometry"]["gap"].removesuffix(" mm"))
    assert 7.4 < gap < 7.5 and spec["mechanics"]["fidelity"] == "reissner"  # the answer, 7.4458 mm
    assert "start" not in spec["design"]["variables"]["geometry.gap"]
    assert main(["simulate", str(written)]) == 0
    assert "design spec" not in capsys.readouterr().out  # every variable stated by the scene
    picture = tmp_path / "solved.png"
    assert main(["show", str(written), "--plot", str(picture)]) == 0
    assert picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_infeasible_design_exits_3_and_names_the_target(capsys, tmp_path):
    spec = (EXAMPLES / "dome_hall.toml").read_text()
    spec = spec.replace(
        '"mechanics.thickness" = { lower = "1.5 mm", upper = "4 mm" }',
        '"mechanics.thickness" = { lower = "5 mm", upper = "6 mm" }',
    )
    spec = spec.replace('thickness = "2 mm"', 'thickness = "5.5 mm"')  # the variable starts at the scene's value
    path = tmp_path / "infeasible.toml"
    path.write_text(spec)
    assert main(["solve", str(path), "--json", "--fidelity", "reissner"]) == 3
    result = json.loads(capsys.readouterr().out)
    assert result["status"] != "successful"
    assert "compliance" in result["violated"]
    assert all(value == value for value in result["parameters"].values())  # no NaN


@pytest.mark.parametrize(
    "old, new, key",
    [
        ('radius = "1.5 mm"', 'radius = "1.5"', "magnet.radius"),
        ('compliance = "0.32 mm/N"', 'compliance = "0.32 mT"', "design.targets.compliance"),
        ('effects = ["saturation", "quantisation"]', 'effects = ["saturation", "gremlins"]', "scene.effects"),
    ],
)
@pytest.mark.slow
def test_bad_spec_exits_2_with_one_line_naming_the_key(tmp_path, old, new, key):
    text = (EXAMPLES / "dome_hall.toml").read_text()
    assert old in text
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(old, new))
    run = subprocess.run([sys.executable, "-m", "magdesign", "solve", str(path)], capture_output=True, text=True)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and key in lines[0] and "Traceback" not in run.stderr


def test_missing_spec_file_exits_2(capsys):
    assert main(["simulate", "no/such/spec.toml"]) == 2
    assert "no/such/spec.toml" in capsys.readouterr().err


# Examples whose simulation compiles for half a minute and more: the pole plate's soft rod is
# solved by the method of moments (400 cells), the skins' outputs take the Jacobian of every
# reading through the layer's transforms (eflesh: through its magnets'; the fast tier
# simulates it from Python in tests/scene/test_skin_magnets.py).
SLOW_EXAMPLES = ("eflesh.toml", "pole_plate.toml", "skin.toml", "skin_pattern.toml")


@pytest.mark.parametrize(
    "example",
    [
        pytest.param(name, marks=pytest.mark.slow) if name in SLOW_EXAMPLES else name
        for name in sorted(p.name for p in EXAMPLES.glob("*.toml"))
    ],
)
def test_every_example_simulates(example, capsys):
    assert main(["simulate", str(EXAMPLES / example), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)


@pytest.mark.slow
def test_the_command_keeps_compiled_programs_in_its_cache_folder(tmp_path):
    """The solver's own program among them: JAX keeps no program that calls back to Python
    (a runtime error check does, as lineax's checks of a solve), and a cache
    without the solver would leave every run to compile it again. The programs lie in a
    folder named for the CPU (JAX's cache key leaves it out), and loading them says nothing."""
    cache = tmp_path / "cache"
    env = {
        **os.environ,
        "MAGDESIGN_CACHE_DIR": str(cache),
        "MAGDESIGN_NO_CACHE": "",
        "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0",
    }
    solve = [
        sys.executable,
        "-m",
        "magdesign",
        "solve",
        str(EXAMPLES / "dome_hall.toml"),
        "--fidelity",
        "reissner",
        "--json",
    ]
    assert subprocess.run(solve, capture_output=True, env=env).returncode == 0
    # A second run loads the programs; XLA logged an error for each ("... SIGILL") before.
    again = subprocess.run(solve, capture_output=True, env=env, text=True)
    assert again.returncode == 0
    assert all(line.startswith("magdesign") for line in again.stderr.splitlines()), again.stderr
    kept = sorted(entry.name for entry in cache.glob(f"{cpu_tag()}/*"))
    assert any(name.startswith("jit_run-") for name in kept), kept
    # beside them, the exported programs (magdesign._export), where jax.export can write them
    assert sorted(folder.name for folder in cache.iterdir()) in ([cpu_tag()], sorted([cpu_tag(), "exported"]))
    exported = [entry.name for entry in cache.glob(f"exported/{cpu_tag()}/*")]
    assert importlib.util.find_spec("flatbuffers") is None or any(name.startswith("solve-") for name in exported)
    command = [sys.executable, "-m", "magdesign", "simulate", str(EXAMPLES / "dome_hall.toml"), "--json"]
    off = tmp_path / "off"
    env = {**env, "MAGDESIGN_CACHE_DIR": str(off), "MAGDESIGN_NO_CACHE": "1"}
    assert subprocess.run(command, capture_output=True, env=env).returncode == 0
    assert not off.exists()


@pytest.mark.slow
def test_simulate_flags_load_points_where_the_dome_did_not_converge(tmp_path, capsys):
    """A 1 mm dome at axisymmetric fidelity pressed with up to 50 N, more than it carries before
    its wall is pressed flat (it passes its snap near 2.4 N): exit 3, a warning, and the
    JSON says which points converged."""
    text = (EXAMPLES / "dome_hall.toml").read_text()
    for old, new in (
        ('thickness = "2 mm"', 'thickness = "1 mm"'),
        ('fidelity = "reissner"', 'fidelity = "axisymmetric"'),
        ('normal = ["0 N", "5 N"]', 'normal = ["0 N", "50 N"]'),
    ):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "thin.toml"
    path.write_text(text[: text.index("[design")])  # a scene spec: a design spec simulates its start point
    assert main(["simulate", str(path)]) == 3
    assert "did not converge" in capsys.readouterr().out
    assert main(["simulate", str(path), "--json"]) == 3
    converged = json.loads(capsys.readouterr().out)["converged"]
    assert converged[0] and not converged[-1]


@pytest.mark.slow
def test_show_writes_a_picture(capsys, tmp_path):
    plot = tmp_path / "sensor.png"
    assert main(["show", str(EXAMPLES / "spin_valve_matrix.toml"), "--plot", str(plot)]) == 0
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and f"magdesign show: wrote {plot}" in capsys.readouterr().err


def test_show_needs_a_plot_file_and_a_good_spec(capsys, tmp_path):
    with pytest.raises(SystemExit) as exit_code:
        main(["show", str(EXAMPLES / "dome_hall.toml")])
    assert exit_code.value.code == 2  # argparse: --plot is required
    path = tmp_path / "bad.toml"
    path.write_text((EXAMPLES / "dome_hall.toml").read_text().replace('radius = "1.5 mm"', 'radius = "1.5"'))
    assert main(["show", str(path), "--plot", str(tmp_path / "x.png")]) == 2
    assert "magnet.radius" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


@pytest.mark.parametrize(
    "content, fragment",
    [
        (bytes(range(256)) * 4, "not a text file"),  # a binary file
        (("a = " + "[" * 5000 + "]" * 5000).encode(), "nested too deep"),  # RecursionError in the reader
        ('radius = "1 mm^"', "magnet.radius"),  # IndexError in the unit parser
        ('radius = "1 km^200"', "magnet.radius"),  # OverflowError
        ("radius = nan", "magnet.radius"),
        ('radius = "1e999 mm"', "magnet.radius"),
    ],
)
def test_broken_files_exit_2_with_one_line(tmp_path, capsys, content, fragment):
    if isinstance(content, str):  # the default spec's magnet radius replaced
        text = (EXAMPLES / "dome_hall.toml").read_text()
        assert 'radius = "1.5 mm"' in text
        content = text.replace('radius = "1.5 mm"', content, 1).encode()
    path = tmp_path / "broken.toml"
    path.write_bytes(content)
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and fragment in err and len(err) < 400, err


def test_an_internal_error_is_one_line_and_exit_1_and_debug_shows_it(monkeypatch, capsys):
    import magdesign.cli as cli

    def broken(args):
        raise ZeroDivisionError("a bug\nwith a second line")

    monkeypatch.setattr(cli, "run_simulate", broken)
    assert main(["simulate", "any.toml"]) == 1
    err = capsys.readouterr().err.strip()
    assert err.splitlines() == [
        "magdesign simulate: internal error: ZeroDivisionError: a bug (run with --debug for the traceback)"
    ]
    for argv in (["--debug", "simulate", "any.toml"], ["simulate", "any.toml", "--debug"]):
        with pytest.raises(ZeroDivisionError):
            main(argv)


def test_version():
    version = subprocess.run([sys.executable, "-m", "magdesign", "--version"], capture_output=True, text=True)
    assert version.returncode == 0 and version.stdout.startswith("magdesign ")


@pytest.mark.parametrize(
    "option, path",
    [
        ("--plot", "{tmp}"),
        ("--plot", "{tmp}/no/such/folder/x.png"),
        ("--plot", "{tmp}/picture"),
        ("--write", "{tmp}"),
        ("--write", "{tmp}/no/such/folder/x.toml"),
        ("--write", "{tmp}/solved.txt"),
    ],
)
def test_an_output_path_that_cannot_be_written_is_refused_before_the_solve(tmp_path, capsys, option, path):
    """A folder (once silently written as folder.png), a missing folder, a name without
    .png (.toml): exit 2 at once, and nothing written."""
    path = path.format(tmp=tmp_path)
    assert main(["solve", option, path]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and option in captured.err and len(captured.err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_json_output_is_strict_json():
    """A non-finite number is written as null, never as the bare NaN / Infinity that
    json.dumps writes by default (which JSON readers refuse)."""
    from magdesign.cli import json_text

    text = json_text({"a": float("nan"), "b": [1.5, float("inf"), {"c": -float("inf")}], "d": "x"})
    assert json.loads(text, parse_constant=lambda name: pytest.fail(f"bare {name}")) == {
        "a": None,
        "b": [1.5, None, {"c": None}],
        "d": "x",
    }


@pytest.mark.parametrize("normal", ['["0 N", "0 N"]', '["0 N", "-5 N"]'])
def test_a_design_without_a_press_is_a_bad_spec(tmp_path, capsys, normal):
    """A zero or negative load range gave exit 3 and an infinite sensitivity: it is a bad
    spec naming load.normal."""
    text = (EXAMPLES / "dome_hall.toml").read_text()
    assert 'normal = ["0 N", "5 N"]' in text
    path = tmp_path / "no_press.toml"
    path.write_text(text.replace('normal = ["0 N", "5 N"]', f"normal = {normal}"))
    assert main(["solve", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "load.normal" in err


def test_solve_runs_once_unless_timing_is_asked(monkeypatch, capsys):
    """A slow (axisymmetric) solve was run twice to report a warm time; now only with --timing."""
    import magdesign.cli as cli

    calls = []
    real = cli.solve_problem
    monkeypatch.setattr(cli, "solve_problem", lambda problem, **kw: calls.append(1) or real(problem, **kw))
    assert main(["solve", "--fidelity", "reissner"]) == 0 and len(calls) == 1
    out = capsys.readouterr().out
    assert "first call" in out and "dome reissner" in out
    assert main(["solve", "--fidelity", "reissner", "--timing", "--json"]) == 0 and len(calls) == 3
    result = json.loads(capsys.readouterr().out)
    assert result["warm_seconds"] > 0 and result["seconds"] > 0


def test_a_load_that_drives_the_magnet_through_the_sensor_breaks_the_geometry(tmp_path, capsys):
    """The magnet never reaches the sensor plane: a design meets that or says it does not."""
    text = (EXAMPLES / "dome_hall.toml").read_text()
    path = tmp_path / "crush.toml"
    path.write_text(text.replace('normal = ["0 N", "5 N"]', 'normal = ["0 N", "1e7 N"]'))
    assert main(["solve", str(path), "--json", "--fidelity", "reissner"]) == 3
    result = json.loads(capsys.readouterr().out)
    assert result["status"] != "successful"
    assert result["limits"]["closest_gap"]["lower"] == 0.0 and "closest_gap.lower" in result["violated"]


@pytest.mark.parametrize(
    "old, new, key",
    [
        ('radius = "1.5 mm"', 'radius = "-1.5 mm"', "magnet.radius"),
        ('height = "1 mm"', 'height = "0 mm"', "magnet.height"),
        ('thickness = "2 mm"', 'thickness = "9 mm"', "mechanics.thickness"),
        ('compliance = "0.32 mm/N"', 'compliance = "0 mm/N"', "design.targets.compliance"),
        ('effects = ["saturation", "quantisation"]', 'effects = ["saturation", "saturation"]', "scene.effects"),
    ],
)
def test_impossible_input_is_refused_at_load_time(tmp_path, capsys, old, new, key):
    text = (EXAMPLES / "dome_hall.toml").read_text()
    assert old in text
    path = tmp_path / "impossible.toml"
    path.write_text(text.replace(old, new, 1))
    for command in (["solve", str(path), "--fidelity", "reissner"], ["simulate", str(path)]):
        assert main(command) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and key in err


def test_an_implausible_value_warns_in_one_line(tmp_path, capsys):
    text = (EXAMPLES / "dome_hall.toml").read_text()
    path = tmp_path / "strong.toml"
    path.write_text(text.replace('remanence = "1.17 T"', 'remanence = "100 T"'))
    assert main(["simulate", str(path)]) == 0
    err = capsys.readouterr().err
    assert "warning: magnet.remanence" in err and "Traceback" not in err


def test_simulate_of_a_design_spec_simulates_its_scene_as_written(capsys):
    """[geometry] gap = "7.4 mm" is the gap simulated, and where the solve starts."""
    assert main(["simulate", str(EXAMPLES / "dome_hall.toml"), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["start"] == {"geometry.gap": 7.4e-3, "mechanics.thickness": 2e-3}
    assert result["outputs"]["closest_gap"] == pytest.approx(7.4e-3 + min(u[2] for u in result["displacement"]))
    assert result["output_units"]["compliance"] == "m/N"


def test_a_start_that_differs_from_the_scene_is_refused_naming_both_keys(tmp_path, capsys):
    text = (EXAMPLES / "dome_hall.toml").read_text()
    old = '"geometry.gap" = { lower = "4 mm", upper = "20 mm" }'
    assert old in text
    path = tmp_path / "two_gaps.toml"
    path.write_text(text.replace(old, '"geometry.gap" = { lower = "4 mm", upper = "20 mm", start = "7 mm" }'))
    assert main(["simulate", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert (
        len(err.splitlines()) == 1 and "design.variables.geometry.gap.start" in err and "geometry.gap = '7.4 mm'" in err
    )


def test_a_time_series_effect_needs_two_load_points(tmp_path, capsys):
    text = (EXAMPLES / "gmr_inductor.toml").read_text().replace("points = 21", "points = 1")
    path = tmp_path / "one_point.toml"
    path.write_text(text)
    assert main(["simulate", str(path), "--json"]) == 2
    captured = capsys.readouterr()
    assert "load.points" in captured.err and len(captured.err.strip().splitlines()) == 1
    # with --json the error is also one JSON object on stdout
    assert json.loads(captured.out) == {
        "error": "bad_spec",
        "message": captured.err.strip().split(": ", 1)[1],
        "exit_code": 2,
    }


def test_simulate_warns_when_the_chip_clips_and_its_columns_are_readings(tmp_path, capsys):
    """The default scene with the magnet 5 mm above the AK8963: pressed 1.6 mm nearer, its
    on-axis field (about 12 mT) is beyond the chip's 4.8 mT range: one warning line on
    stderr, and the table's columns are the chip's readings, clipped at 4.8 mT."""
    text = (EXAMPLES / "dome_hall.toml").read_text()
    assert 'gap = "7.4 mm"' in text
    path = tmp_path / "near.toml"
    path.write_text(text[: text.index("[design")].replace('gap = "7.4 mm"', 'gap = "5 mm"'))
    assert main(["simulate", str(path)]) == 0
    captured = capsys.readouterr()
    warning = [line for line in captured.err.splitlines() if "clips" in line]
    assert len(warning) == 1 and warning[0].startswith("magdesign: warning: the chip clips")
    header = captured.out.splitlines()[0]
    assert "s0.Bz reading (mT)" in header and "field" not in header
    pressed = captured.out.splitlines()[11].split()  # the 11th load point, 5 N; its last column is s0.Bz
    assert float(pressed[-1]) == pytest.approx(4.8, rel=1e-12)
    # 10 mm above the chip (8.4 mm or more at 5 N: below 2.2 mT on the axis) no reading clips
    path.write_text(
        text[: text.index("[design")]
        .replace('gap = "7.4 mm"', 'gap = "10 mm"')
        .replace('outer_radius = "8 mm"', 'outer_radius = "10.5 mm"')
    )
    assert main(["simulate", str(path)]) == 0
    assert "clips" not in capsys.readouterr().err
