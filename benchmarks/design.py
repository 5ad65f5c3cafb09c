"""Speed of the design solver on the default design, and its QP subproblem. Run by hand:

    .venv/bin/python benchmarks/design.py [--skip-axisymmetric] [--accuracy-only | --second-run-only]

Prints:
- the default design (the spec `magdesign solve` runs with no argument, its scene model):
  first call (compile included) and the median warm time of one solve, at the Reissner
  dome level and, unless skipped, the axisymmetric one;
- what `magdesign solve --accuracy` costs on the default design against solves at fixed
  levels: the first call (compiles included) and a second, warm one of
  :func:`magdesign.spec.levels.solve_to_accuracy` at 10 % and 1 %, with the levels it ends at
  (``--accuracy-only``: these rows alone);
- the same first call at the Reissner level in new processes, as `magdesign solve` makes it:
  on an empty persistent cache, and three times with the cache the first run filled;
- the second run of whole commands in new processes, the caches (compiled and exported
  programs, see magdesign._export) filled by a first: `solve --fidelity reissner` (also of a
  spec with other numbers), `solve` with the axisymmetric confirmation (unless skipped),
  `simulate` and a 5-point Reissner `sweep` (also 7 other points): the first run's wall
  time and the medians of five second runs' wall and CPU (user + sys) times
  (``--second-run-only``: these rows alone); then where a second Reissner solve goes
  (imports, spec, solve, estimate, report; within solve and estimate: loading the kept
  executables or waiting for the threads that load them ahead, lowering, loading from the compilation cache and compiling, from JAX's
  monitoring events, and the rest: tracing and running); then the same solve after an upgrade
  of magdesign (the exported and kept programs miss, the compilation cache holds the same
  programs): the run after it and the median of five runs after that;
- where that first call goes, in a new process without the cache: the seconds (wall and
  CPU) of tracing the solver's program, lowering it to StableHLO and compiling it with XLA,
  and the compiled program's size (fusions: XLA compiles each into a kernel of its own);
- a vmapped batch of 10,000 target compliances at the Reissner level, and the same
  10,000 designs solved the usual way without magdesign: scipy's brentq on the same closed
  forms (Reissner's dome compliance for the wall, the dome-Hall paper's Eq. 1 on the axis for the gap
  where the field limit is active), with the largest difference between the two answers;
- the QP subproblem of the solver's first step on the default design and on hs071,
  solved by magdesign's interior-point method, by what the solver runs (active-set rounds
  from its first-step guess, then the interior-point method where they fail) and by jaxopt's BoxOSQP at three
  tolerances: time, iterations, error of the step against an exact active-set solution,
  and whether the active set read from its multipliers is right.
"""

import importlib
import os
import shutil
import subprocess
import sys
import tempfile
import time

import jax
import jax.numpy as jnp
import jaxopt
import numpy as np
from scipy.optimize import brentq

from magdesign.design import solve, sweep
from magdesign.design._sqp.jet import _jet, problem_arrays
from magdesign.design._sqp.step import _no_slack_rows, subproblem, subproblem_box
from magdesign.mechanics import MooneyRivlin
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.levels import levels_text, solve_to_accuracy
from magdesign.units import mm, mT

sys.path.insert(0, "tests/design")
from helpers_problems import HOCK_SCHITTKOWSKI  # noqa: E402

qp_module = importlib.import_module("magdesign.design._qp")

BATCH = 10_000
# The default spec's numbers (magdesign/design/default.toml), for the scipy baseline.
RADIUS, HEIGHT, REMANENCE = 1.5 * mm, 1.0 * mm, 1.17
OUTER, FORCE, SATURATION = 8.0 * mm, 5.0, 4.8 * mT
MATERIAL = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)


def table(rows):
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())


def timed_solves(problem, repeats):
    began = time.perf_counter()
    first = solve(problem)
    first_s = time.perf_counter() - began
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        solve(problem)
        times.append(time.perf_counter() - began)
    return first, first_s, float(np.median(times))


# One `magdesign solve` at the Reissner level as the command makes it: a new process, the
# command's persistent cache turned on. Prints the first call's seconds.
FRESH_PROCESS = """
import time
from magdesign._cache import use_compilation_cache
from magdesign.design import solve
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.levels import levels_text, solve_to_accuracy
use_compilation_cache()
problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
began = time.perf_counter()
result = solve(problem)
print(time.perf_counter() - began, result.status)
"""


# The stages of the solver's first call at the Reissner level, in a new process without a
# persistent cache: prints (stage, wall s, CPU s) per line, then the compiled program's
# fusions and instructions.
FIRST_CALL_STAGES = """
import re, resource, time
from magdesign.design.solve import DESIGN_ATOL, DESIGN_RTOL
from magdesign._tracing import errors_as_nan, gc_paused
from magdesign.design._sqp.program import _compiled, _host, _structure, settings_of
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.spec.levels import levels_text, solve_to_accuracy
problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
settings = settings_of(DESIGN_RTOL, DESIGN_ATOL, 100)
key, arrays = _structure(problem, settings)
host = _host(problem)
program = _compiled(key, False)
clock = lambda: (time.perf_counter(), sum(resource.getrusage(resource.RUSAGE_SELF)[:2]))
with errors_as_nan(), gc_paused():
    began = clock()
    traced = program.trace(arrays, host.y0, host.theta)
    traced_at = clock()
    lowered = traced.lower()
    lowered_at = clock()
    compiled = lowered.compile()
    compiled_at = clock()
for stage, (a, b) in (("trace", (began, traced_at)), ("lower", (traced_at, lowered_at)),
                      ("compile", (lowered_at, compiled_at))):
    print(stage, b[0] - a[0], b[1] - a[1])
text = compiled.as_text()
print("size", len(re.findall(r"= [^=]* fusion\\(", text)), len(re.findall(r"\\n  +(?:ROOT )?%", text)))
"""


# Where a second `magdesign solve --fidelity reissner` goes, in a new process whose caches a
# first run filled: each stage's wall and CPU seconds, from timers around the command's
# steps and around loading the kept executables (magdesign._export, "executable-load": with
# the executables loaded ahead in threads as the command starts, the wait for them),
# and JAX's own monitoring events (lowering, loading from the compilation cache,
# compiling: wall only); "tracing+run" is the rest of the solve and estimate steps (JAX's
# tracing events count a nested program's trace again in its caller's).
SECOND_RUN_STAGES = """
import contextlib, io, sys, time
began = time.perf_counter(), time.process_time()
import jax
import magdesign.cli as cli
from magdesign import _export
imported = time.perf_counter(), time.process_time()
stages, inner = {}, {}
def timed(name, fn, into=stages):
    def call(*args, **kwargs):
        start = time.perf_counter(), time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            wall, cpu = into.get(name, (0.0, 0.0))
            into[name] = wall + time.perf_counter() - start[0], cpu + time.process_time() - start[1]
    return call
_export._read_executable = timed("executable-load", _export._read_executable, inner)
events = {}
def heard(event, seconds, **kwargs):
    events[event] = events.get(event, 0.0) + seconds
jax.monitoring.register_event_duration_secs_listener(heard)
for name, stage in (("default_spec", "spec"), ("problem_from_spec", "spec"), ("solve_problem", "solve"),
                    ("estimate", "estimate")):
    setattr(cli, name, timed(stage, getattr(cli, name)))
with contextlib.redirect_stdout(io.StringIO()):
    start = time.perf_counter(), time.process_time()
    assert cli.main(sys.argv[1:]) == 0
    done = time.perf_counter(), time.process_time()
print("imports", imported[0] - began[0], imported[1] - began[1])
for name, (wall, cpu) in stages.items():
    print(name, wall, cpu)
rest = sum(wall for wall, _ in stages.values()), sum(cpu for _, cpu in stages.values())
print("report", done[0] - start[0] - rest[0], done[1] - start[1] - rest[1])
retrieved = events.get("/jax/compilation_cache/cache_retrieval_time_sec", 0.0)
lowering = events.get("/jax/core/compile/jaxpr_to_mlir_module_duration", 0.0)
compiling = events.get("/jax/core/compile/backend_compile_duration", 0.0) - retrieved
loaded = inner.get("executable-load", (0.0, 0.0))
print("executable-load", *loaded)
print("lowering", lowering)
print("cache-load", retrieved)
print("compiling", compiling)
print("tracing+run", stages["solve"][0] + stages["estimate"][0] - loaded[0] - lowering - retrieved - compiling)
"""

# The second run of each command, in new processes: the commands that benchmarks/design.py
# times as whole commands, each once to fill the caches, then SECOND_RUNS times.
SECOND_RUNS = 5
OTHER_NUMBERS = "0.3 mm/N"  # the default design's compliance target in the spec "with other numbers"


def _command(arguments, env):
    """(wall, user + sys CPU) seconds of ``python -m magdesign ARGUMENTS`` in a new process."""
    began, before = time.perf_counter(), os.times()
    subprocess.run([sys.executable, "-m", "magdesign", *arguments], env=env, capture_output=True, check=True)
    after = os.times()
    return (
        time.perf_counter() - began,
        after.children_user + after.children_system - before.children_user - before.children_system,
    )


def second_run_rows(skip_axisymmetric):
    """Each command's first run (caches empty) and the median of SECOND_RUNS second runs
    (wall and CPU), new processes all; then the stages of a second Reissner solve."""
    default = "magdesign/design/default.toml"
    with tempfile.TemporaryDirectory() as cache:
        other = os.path.join(cache, "other_numbers.toml")
        with open(default) as file:
            text = file.read()
        with open(other, "w") as file:
            file.write(text.replace('compliance = "0.32 mm/N"', f'compliance = "{OTHER_NUMBERS}"'))
        commands = [
            ("solve --fidelity reissner", ["solve", "--fidelity", "reissner", "--json"]),
            (
                f"  the same, a spec with compliance {OTHER_NUMBERS}",
                ["solve", other, "--fidelity", "reissner", "--json"],
            ),
            ("simulate", ["simulate", default, "--json"]),
            (
                "sweep --fidelity reissner, 5 points",
                ["sweep", default, "--over", "compliance=0.3mm/N:0.34mm/N:5", "--fidelity", "reissner", "--json"],
            ),
            (
                "  the same, 7 other points",
                ["sweep", default, "--over", "compliance=0.29mm/N:0.35mm/N:7", "--fidelity", "reissner", "--json"],
            ),
        ]
        if not skip_axisymmetric:
            commands.insert(2, ("solve (axisymmetric confirmation)", ["solve", "--json"]))
        env = {
            **os.environ,
            "MAGDESIGN_CACHE_DIR": cache,
            "MAGDESIGN_NO_CACHE": "",
            "MAGDESIGN_NO_EXPORT": "",
            "MAGDESIGN_NO_RECOMPILE": "",
        }
        rows = [("second run, new process", "first run wall (s)", "wall (s), median", "CPU (s), median", "walls (s)")]
        for name, arguments in commands:
            first = _command(arguments, env)[0] if not name.startswith("  ") else float("nan")
            runs = [_command(arguments, env) for _ in range(SECOND_RUNS)]
            walls, cpus = zip(*runs)
            rows.append(
                (
                    name,
                    f"{first:.1f}",
                    f"{np.median(walls):.2f}",
                    f"{np.median(cpus):.2f}",
                    " ".join(f"{w:.1f}" for w in walls),
                )
            )
        table(rows)
        print()
        stages = {}
        for _ in range(SECOND_RUNS):
            out = subprocess.run(
                [sys.executable, "-c", SECOND_RUN_STAGES, "solve", "--fidelity", "reissner", "--json", "--quiet"],
                env=env,
                capture_output=True,
                text=True,
                check=True,
            )
            for line in out.stdout.splitlines():
                name, *numbers = line.split()
                stages.setdefault(name, []).append([float(n) for n in numbers])
        rows = [("second solve --fidelity reissner, stage", "wall (s), median", "CPU (s), median")]
        for name, values in stages.items():
            values = np.median(np.array(values), axis=0)
            rows.append((name, f"{values[0]:.2f}", f"{values[1]:.2f}" if len(values) > 1 else ""))
        table(rows)
        print()
        upgrade_rows(cache, env)


def upgrade_rows(cache, env):
    """`solve --fidelity reissner` after an upgrade of magdesign, in new processes: the
    exported and kept programs all miss (new versions(); here their folder is emptied) while
    the compilation cache holds the same programs. The run after the upgrade (which compiles
    the kept programs once more, magdesign._export._Program._keep) and the median of
    SECOND_RUNS runs after it, wall and CPU."""
    arguments = ["solve", "--fidelity", "reissner", "--json"]
    shutil.rmtree(os.path.join(cache, "exported"))
    upgraded = _command(arguments, env)
    walls, cpus = zip(*[_command(arguments, env) for _ in range(SECOND_RUNS)])
    rows = [("solve --fidelity reissner after an upgrade", "wall (s)", "CPU (s)")]
    rows.append(("the run after the upgrade", f"{upgraded[0]:.2f}", f"{upgraded[1]:.2f}"))
    rows.append(("the runs after it, median", f"{np.median(walls):.2f}", f"{np.median(cpus):.2f}"))
    table(rows)


def first_call_rows():
    env = {**os.environ, "JAX_ENABLE_COMPILATION_CACHE": "false"}
    out = subprocess.run([sys.executable, "-c", FIRST_CALL_STAGES], env=env, capture_output=True, text=True, check=True)
    rows = [("first call, new process", "wall (s)", "CPU (s)")]
    for line in out.stdout.splitlines():
        stage, *numbers = line.split()
        if stage == "size":
            fusions, instructions = numbers
        else:
            rows.append((stage, f"{float(numbers[0]):.2f}", f"{float(numbers[1]):.2f}"))
    table(rows)
    print(f"compiled program: {fusions} fusions in {instructions} instructions")


def fresh_process_rows():
    rows = [("default design, new process", "first call (s)", "status")]
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "MAGDESIGN_CACHE_DIR": cache, "MAGDESIGN_NO_CACHE": ""}
        for run in range(4):
            out = subprocess.run(
                [sys.executable, "-c", FRESH_PROCESS], env=env, capture_output=True, text=True, check=True
            )
            seconds, status = out.stdout.split()
            rows.append(("empty cache" if run == 0 else f"cache kept, run {run}", f"{float(seconds):.2f}", status))
    table(rows)


def scipy_designs(compliances):
    """(gap, thickness) of each target compliance, by brentq on the same closed forms."""
    e, nu = float(MATERIAL.youngs_modulus), float(MATERIAL.poisson_ratio)

    def reissner(t):
        return (OUTER - t / 2) * np.sqrt(3 * (1 - nu**2)) / (4 * e * t**2)

    def bz(z):
        return REMANENCE / 2 * ((HEIGHT + z) / np.hypot(RADIUS, HEIGHT + z) - z / np.hypot(RADIUS, z))

    closest = brentq(lambda z: bz(z) - SATURATION, 0.1 * mm, 50 * mm, xtol=1e-16, rtol=1e-15)
    gaps, thicknesses = [], []
    for c in compliances:
        thicknesses.append(brentq(lambda t: reissner(t) - c, 0.1 * mm, 8 * mm, xtol=1e-16, rtol=1e-15))
        gaps.append(closest + c * FORCE)
    return np.array(gaps), np.array(thicknesses)


def design_rows(skip_axisymmetric):
    rows = [("default design", "first call (s)", "warm (ms, median)", "status")]
    levels = ["reissner"] + ([] if skip_axisymmetric else ["axisymmetric"])
    for level in levels:
        problem, _ = problem_from_spec(default_spec(), fidelity=level)
        result, first_s, warm_s = timed_solves(problem, 200 if level == "reissner" else 3)
        rows.append((f"solve, {level} dome", f"{first_s:.2f}", f"{warm_s * 1e3:.3f}", result.status))
    table(rows)

    problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
    values = np.linspace(0.2, 0.45, BATCH) * mm
    began = time.perf_counter()
    sweep(problem, "compliance", values)
    first_s = time.perf_counter() - began
    batch = sweep(problem, "compliance", values)
    began = time.perf_counter()
    gaps, thicknesses = scipy_designs(values)
    scipy_s = time.perf_counter() - began
    print()
    table(
        [
            ("10,000 compliances", "time (s)", "per design (us)", "note"),
            (
                "magdesign sweep (vmap)",
                f"{batch.seconds:.3f}",
                f"{batch.seconds / BATCH * 1e6:.1f}",
                f"first call {first_s:.1f} s; {batch.successful.mean() * 100:.1f} % successful",
            ),
            (
                "scipy brentq, same closed forms",
                f"{scipy_s:.3f}",
                f"{scipy_s / BATCH * 1e6:.1f}",
                f"ratio scipy / magdesign {scipy_s / batch.seconds:.1f}",
            ),
        ]
    )
    gap_error = np.max(np.abs(gaps / batch.parameters["geometry.gap"] - 1))
    thickness_error = np.max(np.abs(thicknesses / batch.parameters["mechanics.thickness"] - 1))
    print(f"largest relative difference, scipy vs magdesign: gap {gap_error:.1e}, thickness {thickness_error:.1e}")


def first_subproblem(problem):
    """The solver's QP at the start of ``problem`` (scaled as the solver scales it)."""
    lower, upper, scale, start, theta = problem_arrays(problem, np)
    y0, y_max = (start - lower) / scale, (upper - lower) / scale
    jet = _jet(problem, jnp.asarray(y0), jnp.asarray(theta))
    weight = 1.0 / float(jnp.linalg.norm(jet.J[0])) if problem.objective is not None else 1.0
    m = jet.v.shape[0] - 1
    return subproblem(
        jet,
        jnp.asarray(y0),
        jnp.asarray(y_max),
        jnp.zeros(m),
        weight,
        len(problem.targets),
        problem.objective is not None,
    )


def exact_qp(Q, q, A, b, G, h, active):
    """The QP's solution with the given inequality rows held as equations (KKT system)."""
    E = jnp.concatenate([A, G[active]])
    rhs = jnp.concatenate([b, h[active]])
    k = E.shape[0]
    matrix = jnp.block([[Q, E.T], [E, jnp.zeros((k, k))]])
    return jnp.linalg.lstsq(matrix, jnp.concatenate([-q, rhs]))[0][: Q.shape[0]]


def median_time(fn, repeats=20):
    jax.block_until_ready(fn())
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - began)
    return float(np.median(times))


def qp_rows():
    default, _ = problem_from_spec(default_spec(), fidelity="reissner")
    hs071 = next(p for p in HOCK_SCHITTKOWSKI if p.name == "hs071").problem()
    rows = [("QP of the first step", "solver", "time (ms)", "iterations", "step error", "active set")]
    for name, problem in (("default design", default), ("hs071", hs071)):
        Q, q, A, b, G, h = first_subproblem(problem)
        ours = jax.jit(qp_module.solve_qp)
        solution = ours(Q, q, A, b, G, h)
        active = np.asarray(solution.z) > 1e-8
        reference = exact_qp(Q, q, A, b, G, h, active)
        seconds = median_time(lambda: ours(Q, q, A, b, G, h))
        error = float(jnp.max(jnp.abs(solution.w - reference)))
        rows.append(
            (
                name,
                "magdesign interior point",
                f"{seconds * 1e3:.2f}",
                int(solution.iterations),
                f"{error:.1e}",
                "reference",
            )
        )
        # What the solver runs: active-set rounds from its first-step guess, the interior
        # point method only where they fail (iterations > 0).
        n, n_targets = len(problem.variables), len(problem.targets)
        n_limits = (G.shape[0] - 2 * n - 2 * n_targets) // 2
        guess, box = _no_slack_rows(n, n_targets, n_limits), subproblem_box(n, n_targets, n_limits)
        guessed = jax.jit(lambda *args: qp_module.solve_qp(*args, guess=guess, box=box))
        solution = guessed(Q, q, A, b, G, h)
        seconds = median_time(lambda: guessed(Q, q, A, b, G, h))
        same = bool(np.all((np.asarray(solution.z) > 1e-8) == active))
        rows.append(
            (
                "",
                "magdesign active set, then IP",
                f"{seconds * 1e3:.2f}",
                int(solution.iterations),
                f"{float(jnp.max(jnp.abs(solution.w - reference))):.1e}",
                "right" if same else "wrong",
            )
        )
        stacked = jnp.concatenate([A, G])
        lower_rows = jnp.concatenate([b, jnp.full(G.shape[0], -jnp.inf)])
        upper_rows = jnp.concatenate([b, h])
        for tol, maxiter in ((1e-3, 4000), (1e-6, 100_000), (1e-10, 100_000)):
            osqp = jaxopt.BoxOSQP(tol=tol, maxiter=maxiter, jit=True)
            run = jax.jit(
                lambda Q=Q, q=q: osqp.run(params_obj=(Q, q), params_eq=stacked, params_ineq=(lower_rows, upper_rows))
            )
            out = run()
            seconds = median_time(run, repeats=5)
            w = out.params.primal[0]
            # BoxOSQP's dual of the rows A x = z: positive where an upper bound is active.
            z_osqp = np.asarray(out.params.dual_eq)[A.shape[0] :]
            same = bool(np.all((z_osqp > 1e-8) == active))
            rows.append(
                (
                    "",
                    f"jaxopt BoxOSQP tol {tol:g}",
                    f"{seconds * 1e3:.2f}",
                    int(out.state.iter_num),
                    f"{float(jnp.max(jnp.abs(w - reference))):.1e}",
                    "right" if same else "wrong",
                )
            )
    table(rows)


def accuracy_rows():
    rows = [("default design", "first call (s)", "warm (s)", "levels at the end", "solves", "reached")]
    for level in ("reissner", "axisymmetric"):
        spec = default_spec()
        spec["mechanics"]["fidelity"] = level
        problem, _ = problem_from_spec(spec)
        _, first_s, warm_s = timed_solves(problem, 1)
        rows.append((f"fixed levels, {level} dome", f"{first_s:.1f}", f"{warm_s:.2f}", levels_text(spec), 1, ""))
    for accuracy in (0.1, 0.01):
        times = []
        for _ in range(2):
            began = time.perf_counter()
            run = solve_to_accuracy(default_spec(), accuracy=accuracy)
            times.append(time.perf_counter() - began)
        rows.append(
            (
                f"--accuracy {accuracy:.0%}",
                f"{times[0]:.1f}",
                f"{times[1]:.2f}",
                levels_text(run.spec),
                len(run.answers),
                run.reached,
            )
        )
    table(rows)


def main():
    if "--second-run-only" in sys.argv:
        second_run_rows("--skip-axisymmetric" in sys.argv)
        return
    accuracy_rows()
    if "--accuracy-only" in sys.argv:
        return
    print()
    design_rows("--skip-axisymmetric" in sys.argv)
    print()
    fresh_process_rows()
    print()
    second_run_rows("--skip-axisymmetric" in sys.argv)
    print()
    first_call_rows()
    print()
    qp_rows()


if __name__ == "__main__":
    main()
