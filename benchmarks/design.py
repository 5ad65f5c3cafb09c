"""Speed of the design solver on the default design, and its QP subproblem. Run by hand:

    .venv/bin/python benchmarks/design.py [--skip-axisymmetric] [--accuracy-only]

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
from magdesign.cli import use_compilation_cache
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
    accuracy_rows()
    if "--accuracy-only" in sys.argv:
        return
    print()
    design_rows("--skip-axisymmetric" in sys.argv)
    print()
    fresh_process_rows()
    print()
    first_call_rows()
    print()
    qp_rows()


if __name__ == "__main__":
    main()
