"""The magdesign command under faults of its process and its output, and its progress lines:
each fault ends in one line on stderr and its exit code, before any work where the fault is
in the arguments; a long run says what it does on stderr, and --quiet silences that."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import magdesign.cli as cli
from magdesign import _progress
from magdesign._files import replaced
from magdesign.cli import main

EXAMPLES = Path(__file__).parents[1] / "examples"
COMMAND = [sys.executable, "-m", "magdesign"]


def one_line(err):
    """The only line of ``err`` (stderr), after checking that there is one and no traceback."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_stage_lines_go_to_stderr_only_when_turned_on(capsys):
    _progress.stage("not on yet")
    _progress.enable("magdesign sweep")
    try:
        _progress.stage("solving 15 points")
        _progress.wrote("points.csv")
    finally:
        _progress.enable(None)
    _progress.stage("off again")
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == ["magdesign sweep: solving 15 points ...", "magdesign sweep: wrote points.csv"]


@pytest.mark.slow
def test_show_says_what_it_writes_and_quiet_silences_it(tmp_path, capsys):
    picture = tmp_path / "sensor.png"
    assert main(["show", str(EXAMPLES / "dome_hall.toml"), "--plot", str(picture)]) == 0
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.splitlines() == [
        f"magdesign show: writing {picture}: the sensor at rest and at the largest load ...",
        f"magdesign show: wrote {picture}",
    ]
    picture.unlink()
    assert main(["show", str(EXAMPLES / "dome_hall.toml"), "--plot", str(picture), "--quiet"]) == 0
    assert capsys.readouterr().err == "" and picture.exists()


@pytest.mark.parametrize(
    "argv, option",
    [
        (["solve", "--plot", "/proc/x.png"], "--plot"),
        (["solve", "--plot", "/sys/x.png"], "--plot"),
        (["solve", "--write", "/proc/solved.toml"], "--write"),
        (["solve", "--plot", "{tmp}/" + "a" * 300 + ".png"], "--plot"),
        (["accuracy", "--plot", "/sys/accuracy.png"], "--plot"),
        (
            [
                "sweep",
                str(EXAMPLES / "dome_hall.toml"),
                "--over",
                "compliance=0.2mm/N:0.4mm/N:3",
                "--csv",
                "/proc/x.csv",
            ],
            "--csv",
        ),
        (["tolerance", str(EXAMPLES / "dome_hall_tolerances.toml"), "--seed", "1208925819614629174706176"], "--seed"),
        (["tolerance", str(EXAMPLES / "dome_hall_tolerances.toml"), "--seed", "-1"], "--seed"),
        (["tolerance", str(EXAMPLES / "dome_hall_tolerances.toml"), "--samples", "1000000000000000"], "--samples"),
    ],
)
def test_arguments_that_cannot_work_are_refused_before_any_work(tmp_path, capsys, monkeypatch, argv, option):
    """Outputs that cannot be written (/proc and /sys take no new files, even from root;
    a name past the file system's 255 bytes), a seed beyond jax.random's 64 bits, more
    samples than memory holds: exit 2 and one line naming the option, before any solve."""

    def no_work(*args, **kwargs):
        raise AssertionError("the work started")

    monkeypatch.setattr(cli, "solve_problem", no_work)
    monkeypatch.setattr(cli, "sweep_problem", no_work)
    monkeypatch.setattr(cli.accuracy, "measure", no_work)
    assert main([word.format(tmp=tmp_path) for word in argv]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and option in one_line(captured.err)
    assert list(tmp_path.iterdir()) == []


def test_more_devices_than_cores_is_refused_at_once():
    """It aborted after minutes with XLA's fatal logs (exit 134)."""
    began = time.perf_counter()
    run = subprocess.run(
        [*COMMAND, "sweep", str(EXAMPLES / "dome_hall.toml"), "--over", "compliance=0.2mm/N:0.4mm/N:3"]
        + ["--devices", "1000"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 2 and time.perf_counter() - began < 30
    line = one_line(run.stderr)
    assert "--devices 1000" in line and f"1 to {len(os.sched_getaffinity(0))}" in line


@pytest.mark.slow
def test_a_closed_or_full_stdout_is_one_line_and_its_exit_code(tmp_path):
    """The reader gone (``| head -1``, ``| true``): exit 141, as a shell reports a writer
    killed by SIGPIPE; a full disk (/dev/full): exit 1. An error with --json whose stdout
    is gone keeps its own code (2) and line."""
    spec = str(EXAMPLES / "dome_hall.toml")
    closed = subprocess.Popen([*COMMAND, "simulate", spec, "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    closed.stdout.close()  # before the command writes anything
    err = closed.stderr.read().decode()
    assert closed.wait(timeout=300) == 141
    assert err.strip().splitlines()[-1] == "magdesign simulate: stdout closed by its reader; output cut short"
    assert "Traceback" not in err
    with open("/dev/full", "w") as full:
        run = subprocess.run(
            [*COMMAND, "simulate", spec, "--json", "--quiet"], stdout=full, stderr=subprocess.PIPE, text=True
        )
    assert run.returncode == 1
    assert run.stderr.strip().splitlines()[-1] == "magdesign simulate: cannot write to stdout (No space left on device)"
    assert "Traceback" not in run.stderr
    missing = subprocess.Popen(
        [*COMMAND, "solve", str(tmp_path / "none.toml"), "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    missing.stdout.close()
    assert "none.toml" in one_line(missing.stderr.read().decode()) and missing.wait(timeout=120) == 2


@pytest.mark.slow
def test_a_sweep_on_a_pipe_says_its_stages_and_ctrl_c_stops_it_in_one_line(tmp_path):
    """On a pipe (no terminal) a sweep prints a line per stage and no bar, and --quiet none;
    Ctrl-C during a long sweep: one line "interrupted", exit 130, no CSV file."""
    spec = str(EXAMPLES / "dome_hall.toml")
    table = tmp_path / "points.csv"
    sweep = [*COMMAND, "sweep", spec, "--fidelity", "reissner", "--csv", str(table)]
    run = subprocess.run([*sweep, "--over", "compliance=0.2mm/N:0.4mm/N:15"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    lines = run.stderr.splitlines()
    assert lines[0] == "magdesign sweep: solving 15 points at dome reissner, field axis ..."
    assert any(line.startswith("magdesign sweep: compiling the solver for batches of 1 point") for line in lines)
    assert lines[-1] == f"magdesign sweep: wrote {table}" and "\r" not in run.stderr
    table.unlink()
    quiet = subprocess.run(
        [*sweep, "--over", "compliance=0.2mm/N:0.4mm/N:3", "--quiet"], capture_output=True, text=True
    )
    assert quiet.returncode == 0 and quiet.stderr == "" and table.exists()
    table.unlink()
    # 200,000 points: tens of seconds at the least, in chunks of 4096 between which Ctrl-C acts
    # A background job of a non-interactive shell (a CI script's `cmd &`) starts with SIGINT
    # ignored, which its children inherit and Python keeps (no KeyboardInterrupt at all): the
    # sweep is given SIGINT's default, as a command started from a terminal has it.
    long = subprocess.Popen(
        [*sweep, "--over", "compliance=0.2mm/N:0.4mm/N:200000"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    first = long.stderr.readline().decode()
    assert first.startswith("magdesign sweep: solving 200000 points"), first
    time.sleep(2)
    long.send_signal(signal.SIGINT)
    err = long.stderr.read().decode()
    assert long.wait(timeout=120) == 130
    assert err.strip().splitlines()[-1] == "magdesign sweep: interrupted" and "Traceback" not in err, err
    assert not table.exists()


def test_accuracy_says_each_measurement_and_each_row_and_json_stays_pure(monkeypatch, capsys):
    monkeypatch.setattr(cli.accuracy, "MEASUREMENTS", (("elastomer layer", cli.accuracy.measure_layer, True),))
    assert main(["accuracy", "--quick", "--json"]) == 0
    captured = capsys.readouterr()
    rows = json.loads(captured.out)
    lines = captured.err.splitlines()
    assert lines[0] == "magdesign accuracy: measuring elastomer layer (1 of 1) ..."
    assert [line.split(": error ")[0] for line in lines[1:]] == [
        f"magdesign accuracy: elastomer layer, {row['fidelity']}" for row in rows
    ]
    assert main(["accuracy", "--quick", "--json", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_ctrl_c_during_a_solve_is_one_line_and_exit_130_and_writes_nothing(tmp_path, capsys, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "solve_problem", interrupted)
    written, picture = tmp_path / "solved.toml", tmp_path / "design.png"
    argv = ["solve", str(EXAMPLES / "dome_hall.toml"), "--write", str(written), "--plot", str(picture), "--json"]
    assert main(argv) == 130
    captured = capsys.readouterr()
    assert captured.err.splitlines()[-1] == "magdesign solve: interrupted"
    assert json.loads(captured.out) == {"error": "interrupted", "message": "interrupted", "exit_code": 130}
    assert list(tmp_path.iterdir()) == []


def test_a_ctrl_c_that_a_callback_swallowed_still_stops_the_command(tmp_path, capsys, monkeypatch):
    """A Ctrl-C that lands in a callback Python cannot raise from (JAX's garbage-collection
    callback; here a __del__) is reported nowhere by Python and the run goes on: the
    command notes it, writes no file and ends with exit 130 and one line."""

    class Dropped:
        def __del__(self):
            raise KeyboardInterrupt

    def show(args):
        Dropped()  # its __del__'s KeyboardInterrupt goes to sys.unraisablehook
        with replaced(args.plot) as temporary:
            temporary.write_text("picture")
        return 0

    monkeypatch.setattr(cli, "run_show", show)
    picture = tmp_path / "sensor.png"
    assert main(["show", str(EXAMPLES / "dome_hall.toml"), "--plot", str(picture)]) == 130
    err = capsys.readouterr().err
    assert err.splitlines()[-1] == "magdesign show: interrupted" and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []
