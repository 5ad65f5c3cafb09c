"""Sweeps: grids and lists of full design solves, against closed forms, single solves and
finite differences; the `magdesign sweep` command, its bad input, devices and processes."""

import csv
import importlib
import json
import socket
import subprocess
import sys
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from magdesign.cli import main
from magdesign.design import SQP, Problem, Target, Variable, solve, sweep
from magdesign.spec.design import default_spec, load_spec, problem_from_spec

batch = importlib.import_module("magdesign.design._sqp.batch")  # where the points go a point at a time

mm, mT = 1e-3, 1e-3

# A small scene whose optimum has a closed form: the gap at which the on-axis field of a
# cylinder (radius R, height H, remanence Br) at the sensor is the wanted B.
CHEAP = """
[magnet]
shape = "cylinder"
radius = "1.5 mm"
height = "1 mm"
remanence = "1.2 T"
fidelity = "axis"

[mechanics]
model = "layer"
thickness = "20 mm"           # every gap of the sweeps (up to 20 mm) is the magnet in or on the layer
contact_area = "400 mm^2"     # the stiffness E S / h of a 5 mm layer under 100 mm^2
fidelity = "hooke"
material = "linear"
youngs_modulus = "200 kPa"
poisson_ratio = 0.45

[sensor]
model = "hall3d"
preset = "AK8963"

[geometry]
gap = "5 mm"

[load]
normal = ["0 N", "1 N"]
points = 3

[design.variables]
"geometry.gap" = { lower = "1 mm", upper = "20 mm", start = "5 mm" }

[design.targets]
field_rest = "5 mT"

[design.limits]
saturation_ratio = { upper = 100 }   # fields beyond the AK8963's 4.8 mT range: the chip is not the point here
"""


def on_axis_field(gap, remanence, radius=1.5 * mm, height=1.0 * mm):
    """Bz on a cylinder's axis at ``gap`` from its face (the textbook closed form)."""
    far = gap + height
    return remanence / 2 * (far / np.hypot(far, radius) - gap / np.hypot(gap, radius))


def gap_for(field, remanence):
    return brentq(lambda g: on_axis_field(g, remanence) - field, 0.1 * mm, 50 * mm, xtol=1e-16, rtol=1e-15)


@pytest.fixture(scope="module")
def cheap_spec(tmp_path_factory):
    path = tmp_path_factory.mktemp("sweep") / "cheap.toml"
    path.write_text(CHEAP)
    return path


def product_problem():
    """x * a = y: the optimum x = y / a, dx/dy = 1 / a, dx/da = -y / a^2."""
    return Problem(
        lambda v: {"y": v["x"] * v["a"]},
        [Variable("x", 0.01, 100.0, 1.0)],
        targets=[Target("y", 2.0)],
        fixed={"a": 4.0},
    )


@pytest.mark.slow
def test_grid_shape_and_closed_form_with_derivatives():
    targets, factors = np.array([1.0, 2.0, 3.0]), np.array([0.5, 2.0, 4.0, 8.0])
    result = sweep(product_problem(), {"y": targets, "a": factors})
    assert result.shape == (3, 4) and result.successful.all()
    y, a = np.meshgrid(targets, factors, indexing="ij")
    np.testing.assert_array_equal(result.over["y"], y)
    np.testing.assert_array_equal(result.over["a"], a)
    np.testing.assert_allclose(result.parameters["x"], y / a, rtol=1e-12)
    np.testing.assert_allclose(result.derivatives["y"]["x"], 1 / a, rtol=1e-10)
    np.testing.assert_allclose(result.derivatives["a"]["x"], -y / a**2, rtol=1e-10)


def test_a_failed_point_leaves_the_derivatives_of_the_others():
    """x sqrt(a) = y: at a = -1 the model is NaN (status "nonfinite", no derivatives);
    the points beside it in the same batch keep theirs, dx/dy = 1 / sqrt(a) and
    dx/da = -y / (2 a^1.5), as if solved alone."""
    problem = Problem(
        lambda v: {"y": v["x"] * jnp.sqrt(v["a"])},
        [Variable("x", 0.01, 100.0, 1.0)],
        targets=[Target("y", 2.0)],
        fixed={"a": 4.0},
    )
    a = np.array([0.25, 4.0, -1.0, 9.0])
    result = sweep(problem, {"a": a})
    assert list(result.status) == ["successful", "successful", "nonfinite", "successful"]
    good = a > 0
    np.testing.assert_allclose(result.parameters["x"][good], 2.0 / np.sqrt(a[good]), rtol=1e-12)
    np.testing.assert_allclose(result.derivatives["y"]["x"][good], 1 / np.sqrt(a[good]), rtol=1e-10)
    np.testing.assert_allclose(result.derivatives["a"]["x"][good], -2.0 / (2 * a[good] ** 1.5), rtol=1e-10)
    assert np.isnan(result.derivatives["y"]["x"][2]) and np.isnan(result.derivatives["a"]["x"][2])


@pytest.mark.slow
def test_list_of_points_and_small_chunks_agree_with_one_batch():
    points = {"y": np.linspace(0.5, 3.0, 7), "a": np.linspace(1.0, 7.0, 7)}
    listed = sweep(product_problem(), points, grid=False)
    assert listed.shape == (7,)
    np.testing.assert_allclose(listed.parameters["x"], points["y"] / points["a"], rtol=1e-12)
    chunked = sweep(product_problem(), points, grid=False, chunk=3)  # 3 + 3 + 1 padded to 3
    np.testing.assert_array_equal(chunked.parameters["x"], listed.parameters["x"])
    assert list(chunked.status) == list(listed.status)


@pytest.mark.slow
def test_a_sweep_of_a_few_points_moves_its_bar_per_point_with_the_answers_of_one_batch(cheap_spec, monkeypatch):
    """15 points go in chunks of one (the bar moves 15 times, not once at the end), and each
    point's answer is the one it gets in a batch of 16 lanes (the same 15 points repeated
    16 times go in chunks of 16 copies of one point; the sweep of 15 went in one chunk of 16
    before): the same status and steps, and numbers within a few units in the last place.
    The programs of 1 and of 16 lanes are compiled apart, and XLA:CPU may vectorise their
    loops differently (where a multiply and an add fuse, the order of a sum), so that the
    last bits may differ (up to 3 ulp with jaxlib 0.12's fusion emitters)."""
    moves = []

    class Bar:
        def __init__(self, *args, **kwargs):
            pass

        def update(self, points):
            moves.append(points)

        def close(self):
            pass

    monkeypatch.setattr(batch, "tqdm", Bar)
    problem, _ = problem_from_spec(load_spec(cheap_spec))
    fields = np.linspace(3 * mT, 6 * mT, 15)
    few = sweep(problem, {"field_rest": fields}, progress=True)
    assert moves == [1] * 15
    many = sweep(problem, {"field_rest": np.repeat(fields, 16)}, progress=True)
    assert moves[15:] == [16] * 15
    assert few.successful.all()
    np.testing.assert_array_equal(many.status[::16], few.status)
    np.testing.assert_array_equal(many.steps[::16], few.steps)
    rtol = 16 * np.finfo(np.float64).eps
    for name in few.parameters:
        np.testing.assert_allclose(many.parameters[name][::16], few.parameters[name], rtol=rtol, atol=0)
    for name in few.outputs:
        np.testing.assert_allclose(many.outputs[name][::16], few.outputs[name], rtol=rtol, atol=0)
    for key, column in few.derivatives.items():
        for name in column:
            np.testing.assert_allclose(many.derivatives[key][name][::16], column[name], rtol=rtol, atol=0)


def cubic_problem():
    """x solves x^3 + a x = b by Newton's method in a loop of the model's own, and b is
    free: the optimum for a target X on x is b = X^3 + a X, with db/dX = 3 X^2 + a and
    db/da = X."""

    def model(v):
        a, b = v["a"], v["b"]

        def newton(carry):
            x, k = carry
            return x - (x**3 + a * x - b) / (3 * x**2 + a), k + 1

        def unsettled(carry):  # two steps at least: JAX differentiates the iterates
            x, k = carry
            return (k < 2) | (jnp.abs(x**3 + a * x - b) > 1e-14 * (1 + jnp.abs(b))) & (k < 50)

        x, _ = jax.lax.while_loop(unsettled, newton, (b / (1 + a), 0))
        return {"x": x}

    return Problem(model, [Variable("b", 0.0, 100.0, 1.0)], targets=[Target("x", 1.0)], fixed={"a": 2.0})


@pytest.mark.skipif(jax.default_backend() != "cpu", reason="models with loops go a point at a time on a CPU only")
@pytest.mark.slow
def test_a_sweep_a_point_at_a_time_moves_its_bar_per_point_and_stops_soon_when_interrupted(monkeypatch):
    """40 points a point at a time (runs of SQP.chain on threads): the bar moves by one
    point 40 times; Ctrl-C (a KeyboardInterrupt, here raised by the bar at its 3rd move)
    stops the sweep after the points the threads are solving (each made to take 0.1 s
    here), not after every point."""
    sqp = SQP(point_seconds=0.0)
    one_by_one = batch._one_by_one

    class Slow:
        def __init__(self, program):
            self.program, self.memory_analysis = program, program.memory_analysis

        def __call__(self, *args):
            time.sleep(0.1)
            solves.append(1)
            return self.program(*args)

    monkeypatch.setattr(batch, "_one_by_one", lambda host, program, *rest: one_by_one(host, Slow(program), *rest))
    moves, interrupt_at, solves = [], [], []

    class Bar:
        def __init__(self, *args, **kwargs):
            pass

        def update(self, points):
            moves.append(points)
            if len(moves) in interrupt_at:
                raise KeyboardInterrupt

        def close(self):
            pass

    monkeypatch.setattr(batch, "tqdm", Bar)
    targets = {"x": np.linspace(0.5, 2.0, 40)}
    assert sweep(cubic_problem(), targets, progress=True, solver=sqp).successful.all()
    assert moves == [1] * 40
    moves.clear()
    solves.clear()
    interrupt_at.append(3)
    with pytest.raises(KeyboardInterrupt):
        sweep(cubic_problem(), targets, progress=True, solver=sqp)
    # the threads stop after their current points: the last run of SQP.chain points, which
    # the threads reach a second or more after the interrupt, never starts
    assert len(solves) <= 40 - sqp.chain


@pytest.mark.skipif(jax.default_backend() != "cpu", reason="models with loops go a point at a time on a CPU only")
@pytest.mark.parametrize("slow", [True, False])
@pytest.mark.slow
def test_a_model_with_loops_is_swept_a_point_at_a_time_where_a_point_is_slow(monkeypatch, slow):
    """Vmapped lanes of a loop wait for the slowest lane, so a model with loops of its own
    whose point takes longer than SQP.point_seconds (here made 0 or infinite) is swept a
    point per call of the program that solve runs, in runs of points each started from
    the optimum that the point before predicts to first order: each point is then its
    single solve from that start (the first from the variables' own start), or, without
    continuation, from its own start.
    Either way the optimum and its derivatives are the closed form's."""
    assert batch._iterative(cubic_problem()) and not batch._iterative(product_problem())
    sqp = SQP(point_seconds=0.0 if slow else np.inf)
    calls = []
    one_by_one = batch._one_by_one
    monkeypatch.setattr(batch, "_one_by_one", lambda *args: calls.append(1) or one_by_one(*args))
    targets, factors = np.linspace(0.5, 2.0, 4), np.array([1.0, 3.0])
    result = sweep(cubic_problem(), {"x": targets, "a": factors}, solver=sqp)
    assert len(calls) == int(slow)
    assert result.shape == (4, 2) and result.successful.all()
    x, a = np.meshgrid(targets, factors, indexing="ij")
    np.testing.assert_allclose(result.parameters["b"], x**3 + a * x, rtol=1e-10)
    np.testing.assert_allclose(result.derivatives["x"]["b"], 3 * x**2 + a, rtol=1e-9)
    np.testing.assert_allclose(result.derivatives["a"]["b"], x, rtol=1e-9)
    if not slow:
        return
    b, db_dx, db_da = (
        np.ravel(v) for v in (result.parameters["b"], result.derivatives["x"]["b"], result.derivatives["a"]["b"])
    )
    x, a, steps = x.ravel(), a.ravel(), result.steps.ravel()
    each_cold = sweep(cubic_problem(), {"x": targets, "a": factors}, continuation=False, solver=sqp)
    cold_steps = []
    for k in range(len(x)):  # the 8 points are one run (SQP.chain)
        problem = eqx.tree_at(
            lambda p: (p.targets[0].value, p.fixed_values[0]), cubic_problem(), (jnp.asarray(x[k]), jnp.asarray(a[k]))
        )
        start = (
            None if k == 0 else {"b": b[k - 1] + db_dx[k - 1] * (x[k] - x[k - 1]) + db_da[k - 1] * (a[k] - a[k - 1])}
        )
        single = solve(problem, start=start)  # its start equal to the sweep's up to rounding
        np.testing.assert_allclose(single.parameters["b"], b[k], rtol=1e-14)
        np.testing.assert_allclose(
            [single.derivatives["x"]["b"], single.derivatives["a"]["b"]], [db_dx[k], db_da[k]], rtol=1e-13
        )
        assert single.steps == steps[k]
        cold = solve(problem)
        cold_steps.append(cold.steps)
        # without continuation each point is its single solve from its own start, exactly
        assert cold.parameters["b"] == np.ravel(each_cold.parameters["b"])[k]
        assert cold.derivatives["x"]["b"] == np.ravel(each_cold.derivatives["x"]["b"])[k]
    assert steps[1:].sum() < sum(cold_steps[1:])


@pytest.mark.skipif(jax.default_backend() != "cpu", reason="models with loops go a point at a time on a CPU only")
def test_a_point_that_fails_from_its_predicted_start_is_solved_again_from_its_own():
    """x^2 = y by Newton inside the model, NaN for x in (2.2, 2.8): from x = 1 (y = 1,
    dx/dy = 1/2) the prediction for y = 4 is x = 2.5, where the model is NaN; the point is
    solved again from its own start, x = 1, and reaches x = 2."""

    def model(v):
        x = v["x"]
        root = jax.lax.while_loop(
            lambda r: jnp.abs(r * r - x * x) > 1e-15 * x * x, lambda r: r - (r * r - x * x) / (2 * r), x + 1.0
        )
        return {"y": jnp.where((x > 2.2) & (x < 2.8), jnp.nan, root**2)}

    problem = Problem(model, [Variable("x", 0.1, 3.0, start=1.0)], targets=[Target("y", 1.0)])
    assert solve(problem, start={"x": 2.5}).status == "nonfinite"
    result = sweep(problem, {"y": [1.0, 4.0]}, solver=SQP(point_seconds=0.0))
    assert list(result.status) == ["successful", "successful"]
    np.testing.assert_allclose(result.parameters["x"], [1.0, 2.0], rtol=1e-12)


def test_bad_keys_name_the_key():
    problem = product_problem()
    with pytest.raises(ValueError, match="'x'|x: a variable"):
        sweep(problem, {"x": [1.0]})
    with pytest.raises(ValueError, match="nope"):
        sweep(problem, {"nope": [1.0]})
    with pytest.raises(ValueError, match="lengths"):
        sweep(problem, {"y": [1.0, 2.0], "a": [1.0]}, grid=False)


@pytest.mark.slow
def test_scene_parameter_sweep_against_the_closed_form(cheap_spec):
    problem, _ = problem_from_spec(load_spec(cheap_spec))
    remanences = np.linspace(1.0, 1.4, 5)
    result = sweep(problem, {"magnet.remanence": remanences, "field_rest": [3 * mT, 6 * mT]})
    assert result.shape == (5, 2) and result.successful.all()
    for i, br in enumerate(remanences):
        for j, field in enumerate((3 * mT, 6 * mT)):
            gap = gap_for(field, br)
            assert result.parameters["geometry.gap"][i, j] == pytest.approx(gap, rel=1e-9)
            # implicit derivative: d gap / d Br = -(dB/dBr) / (dB/dgap), by the closed form
            step = 1e-9
            dB_dgap = (on_axis_field(gap + step, br) - on_axis_field(gap - step, br)) / (2 * step)
            expected = -(field / br) / dB_dgap
            assert result.derivatives["magnet.remanence"]["geometry.gap"][i, j] == pytest.approx(expected, rel=1e-6)


@pytest.mark.slow
def test_default_design_over_the_dome_radius_matches_single_solves_and_finite_differences():
    spec = default_spec()
    problem, _ = problem_from_spec(spec)
    radii = np.linspace(7.5, 9.5, 9) * mm  # each apex above the 7.4458 mm gap: the dome carries the magnet
    result = sweep(problem, {"mechanics.outer_radius": radii})
    assert result.successful.all()
    # one point against a single solve of the spec written with that radius
    changed = {**spec, "mechanics": {**spec["mechanics"], "outer_radius": radii[2]}}
    single = solve(problem_from_spec(changed)[0])
    for name, value in single.parameters.items():
        assert result.parameters[name][2] == pytest.approx(value, rel=1e-8)
    # the implicit derivative against central differences along the sweep
    thickness = result.parameters["mechanics.thickness"]
    slope = (thickness[2:] - thickness[:-2]) / (radii[2:] - radii[:-2])
    np.testing.assert_allclose(
        result.derivatives["mechanics.outer_radius"]["mechanics.thickness"][1:-1], slope, rtol=2e-3
    )


def test_command_writes_every_point_and_counts_the_failures(cheap_spec, tmp_path, capsys):
    table = tmp_path / "points.csv"
    # 30 mT is out of reach of the weakest magnet at the smallest gap (1 mm: 6.1 mT): a point fails
    assert on_axis_field(1 * mm, 0.05) < 30 * mT < on_axis_field(1 * mm, 0.4333)
    code = main(
        [
            "sweep",
            str(cheap_spec),
            "--over",
            "magnet.remanence=0.05T:1.2T:4",
            "--over",
            "field_rest=5mT:30mT:2",
            "--csv",
            str(table),
            "--plot",
            str(tmp_path / "map.png"),
            "--quiet",
        ]
    )
    out = capsys.readouterr().out
    with open(table) as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 8
    failed = [row for row in rows if row["status"] != "successful"]
    assert failed and code == 3
    assert f"8 points, {8 - len(failed)} successful, {len(failed)} not" in out
    # the swept column keeps the value asked for, a failed point's too; what was reached
    # has its own column
    assert sorted({float(row["field_rest"]) for row in rows}) == pytest.approx([5 * mT, 30 * mT], rel=1e-12)
    for row in failed:
        assert float(row["field_rest"]) == pytest.approx(30 * mT, rel=1e-12)
        assert float(row["field_rest.achieved"]) < 29 * mT
    for row in rows:
        if row["status"] == "successful":
            gap = gap_for(float(row["field_rest"]), float(row["magnet.remanence"]))
            assert float(row["geometry.gap"]) == pytest.approx(gap, rel=1e-9)
    assert (tmp_path / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_command_json_and_points_file(cheap_spec, tmp_path, capsys):
    points = tmp_path / "points.csv"
    points.write_text("magnet.remanence,field_rest\n1.0 T,4 mT\n1.3,0.004\n")
    assert main(["sweep", str(cheap_spec), "--points", str(points), "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["shape"] == [2] and document["grid"] is False
    assert [p["magnet.remanence"] for p in document["points"]] == [1.0, 1.3]
    for point in document["points"]:
        assert point["geometry.gap"] == pytest.approx(gap_for(4 * mT, point["magnet.remanence"]), rel=1e-9)
        assert "d(geometry.gap)/d(magnet.remanence)" in point


@pytest.mark.parametrize(
    "over, message",
    [
        ("nope=1:2:3", "unknown key 'nope'"),
        ("magnet.remanence=1mm:2mm:3", "--over magnet.remanence"),
        ("magnet.remanence=1T:1.2T:0", "N must be at least 1"),
        ("magnet.remanence=1.2T:1T:3", "LO must be below HI"),
        ("geometry.gap=1mm:2mm:3", "unknown key 'geometry.gap'"),  # a variable: not swept
        ("magnet.remanence=1T:2T", "expected KEY=LO:HI:N"),
    ],
)
def test_command_bad_input_is_one_line_exit_2(cheap_spec, capsys, over, message):
    assert main(["sweep", str(cheap_spec), "--over", over]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err


def _command(spec, *extra):
    return [
        sys.executable,
        "-m",
        "magdesign",
        "sweep",
        str(spec),
        "--over",
        "magnet.remanence=1T:1.4T:5",
        "--json",
        *extra,
    ]


@pytest.mark.slow
def test_two_host_devices_and_two_processes_give_the_one_device_answer(cheap_spec):
    one = json.loads(subprocess.run(_command(cheap_spec), capture_output=True, text=True, check=True).stdout)
    two = json.loads(
        subprocess.run(_command(cheap_spec, "--devices", "2"), capture_output=True, text=True, check=True).stdout
    )
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    processes = [
        subprocess.Popen(
            _command(cheap_spec, "--coordinator", f"127.0.0.1:{port}", "--num-processes", "2", "--process-id", str(i)),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in range(2)
    ]
    outputs = [p.communicate(timeout=300) for p in processes]
    assert [p.returncode for p in processes] == [0, 0], outputs[0][1][-500:] + outputs[1][1][-500:]
    merged = json.loads(outputs[0][0])
    assert outputs[1][0] == ""  # process 0 writes the merged result
    gaps = [p["geometry.gap"] for p in one["points"]]
    assert gaps == pytest.approx([gap_for(5 * mT, br) for br in np.linspace(1.0, 1.4, 5)], rel=1e-9)
    assert [p["geometry.gap"] for p in two["points"]] == gaps
    assert [p["geometry.gap"] for p in merged["points"]] == gaps
