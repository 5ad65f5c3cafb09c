"""The ``magdesign`` command (also ``python -m magdesign``).

    magdesign solve [SPEC.toml] [--json] [--fidelity LEVEL] [--plot FILE] [--timing]
    magdesign simulate SPEC.toml [--json]
    magdesign accuracy [--json] [--plot FILE]
    magdesign show SPEC.toml --plot FILE

Exit codes: 0 done (solve: solved), 1 internal error (a bug: one line; ``--debug`` shows
the traceback), 2 bad spec or arguments (one line naming the key), 3 solve not successful
(the status and the violated target are printed) or a simulation whose mechanics did not
converge at some load point.

Compiled programs are kept in a persistent cache (~/.cache/magdesign/jax; see
:func:`cache_directory`; MAGDESIGN_NO_CACHE=1 turns it off).
"""

import argparse
import importlib.metadata
import json
import math
import os
import sys
import warnings
from pathlib import Path

import jax

from magdesign import accuracy
from magdesign.design import solve as solve_problem
from magdesign.design.plot import plot_design
from magdesign.design.report import format_quantity
from magdesign.design.spec import default_spec, exact_levels, fidelity_levels, load_spec, problem_from_spec
from magdesign.scene import (loads_from_spec, scene_from_spec, simulate, simulation_json, simulation_table,
                             with_parameters)
from magdesign.scene.picture import plot_scene
from magdesign.units import SpecError

EXIT_INTERNAL = 1
EXIT_BAD_SPEC = 2
EXIT_NOT_SOLVED = 3
# Programs that took longer than this to compile are kept in the persistent cache (JAX's own
# JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS, when set, wins).
CACHE_MIN_COMPILE_SECONDS = 0.5


def cache_directory():
    """Where the command keeps compiled programs (JAX's persistent compilation cache):
    $MAGDESIGN_CACHE_DIR, else $XDG_CACHE_HOME/magdesign/jax, else ~/.cache/magdesign/jax;
    None when MAGDESIGN_NO_CACHE is set to anything but "" or "0"."""
    if os.environ.get("MAGDESIGN_NO_CACHE", "") not in ("", "0"):
        return None
    if os.environ.get("MAGDESIGN_CACHE_DIR"):
        return Path(os.environ["MAGDESIGN_CACHE_DIR"])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "magdesign" / "jax"


def use_compilation_cache():
    """Turn on JAX's persistent compilation cache (see :func:`cache_directory`), so that a
    second run of the same command reuses the programs the first compiled."""
    directory = cache_directory()
    if directory is None:
        return
    jax.config.update("jax_compilation_cache_dir", str(directory))
    if "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS" not in os.environ:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", CACHE_MIN_COMPILE_SECONDS)


def build_parser():
    debug = argparse.ArgumentParser(add_help=False)
    # Taken before or after the command; SUPPRESS keeps a command's default from hiding the first.
    debug.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help="show the traceback of an internal error")
    parser = argparse.ArgumentParser(
        prog="magdesign",
        parents=[debug],
        description="Design magnetic tactile sensors by differentiable optimisation.",
        epilog="Exit codes: 0 done, 1 internal error, 2 bad spec or arguments, 3 not solved (or "
        "mechanics not converged). Specs are TOML; see examples/ and the README.",
    )
    parser.add_argument("--version", action="version", version=f"magdesign {importlib.metadata.version('magdesign')}")
    sub = parser.add_subparsers(dest="command", required=True)
    add_parser = lambda name, **kwargs: sub.add_parser(name, parents=[debug], **kwargs)  # noqa: E731

    solve = add_parser("solve", help="solve a design spec (default: the seed-001 dome with a Hall sensor)")
    solve.add_argument("spec", nargs="?", help="design spec (TOML); the built-in default design if omitted")
    solve.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    solve.add_argument("--fidelity", default="auto",
                       help="auto (default): solve at the spec's levels, then confirm from that answer with the "
                       "exact dome (axisymmetric) and field (exact) models, and report both; or one mechanics "
                       "level for every solve (e.g. reissner, axisymmetric)")
    solve.add_argument("--plot", metavar="FILE", help="write a PNG of the targets and limits around the design")
    solve.add_argument("--timing", action="store_true", help="solve the answer's problem again and report that warm time too")

    simulate_cmd = add_parser("simulate", help="run a scene's forward chain over its load sweep")
    simulate_cmd.add_argument("spec", help="scene or design spec (TOML); a design spec simulates its start point "
                              "(every [design.variables] entry at its start), then lists the design outputs")
    simulate_cmd.add_argument("--json", action="store_true", help="print one JSON object instead of the table")

    accuracy_cmd = add_parser("accuracy", help="measure every model's error against its time, on this machine")
    accuracy_cmd.add_argument("--json", action="store_true", help="print a JSON list of rows instead of the table")
    accuracy_cmd.add_argument("--plot", metavar="FILE", help="write a PNG of error against time (log-log)")

    show = add_parser("show", help="draw the sensor in its axial plane with its field, at rest and at the largest load")
    show.add_argument("spec", help="scene or design spec (TOML); a design spec shows its start point")
    show.add_argument("--plot", metavar="FILE", required=True, help="the PNG to write")
    return parser


def scene_at_start(spec):
    """(scene, {variable: start} (SI)): a design spec's scene with every [design.variables]
    entry at its start; a scene spec's scene as written and {}."""
    if "design" not in spec:
        return scene_from_spec(spec), {}
    problem, scene = problem_from_spec(spec)
    start = {v.name: float(v.start) for v in problem.variables}
    return with_parameters(scene, start), start


def run_show(args):
    spec = load_spec(args.spec)
    plot_scene(scene_at_start(spec)[0], loads_from_spec(spec), args.plot, title=args.spec)
    print(f"wrote {args.plot}")
    return 0


def run_solve(args):
    spec = load_spec(args.spec) if args.spec else default_spec()
    auto = args.fidelity in (None, "auto")
    problem, _ = problem_from_spec(spec, fidelity=None if auto else args.fidelity)
    levels = fidelity_levels(spec if auto else {**spec, "mechanics": {**spec.get("mechanics", {}), "fidelity": args.fidelity}})
    _progress(args, f"solving at {levels}")
    first = solve_problem(problem)
    answers = [(levels, problem, first)]
    exact = exact_levels(spec) if auto else None
    if exact is not None and not all(math.isfinite(value) for value in first.parameters.values()):
        print("magdesign solve: the first answer is not finite; no confirmation at the exact levels", file=sys.stderr)
        exact = None
    if exact is not None:
        # Confirm at the exact levels, from the cheap answer: a few steps of the costly model.
        exact_problem, _ = problem_from_spec(exact)
        confirming = fidelity_levels(exact)
        _progress(args, f"confirming at {confirming}, from that answer")
        start = {v.name: min(max(first.parameters[v.name], float(v.lower)), float(v.upper)) for v in exact_problem.variables}
        confirmed = solve_problem(exact_problem, start=start)
        answers.append((confirming, exact_problem, confirmed))
    levels, problem, result = answers[-1]
    warm = solve_problem(problem, start=start if exact else None) if args.timing else None
    if args.json:
        document = {**result.to_json(), "fidelity": levels, "objective": _objective(problem, result)}
        if exact is not None:
            cheap = answers[0]
            document["first_level"] = {**cheap[2].to_json(), "fidelity": cheap[0]}
        if warm is not None:
            document["warm_seconds"] = warm.seconds
        print(json_text(document))
    else:
        for index, (name, _, answer) in enumerate(answers):
            role = "the answer" if index == len(answers) - 1 else "first answer, confirmed below"
            print(f"{name} ({role}):")
            print(answer.table())
            print(f"   that solve took {answer.seconds:.3g} s (first call: tracing and compiling included)\n")
        if exact is not None:
            print(_difference(answers[0][2], result, answers[0][0], levels))
        if warm is not None:
            print(f"warm solve at {levels}: {warm.seconds * 1e3:.3g} ms")
    if args.plot:
        plot_design(problem, result, args.plot)
    return 0 if result.status == "successful" else EXIT_NOT_SOLVED


def _progress(args, message):
    """A line on stderr before a solve (not with --json, whose reader wants one object)."""
    if not args.json:
        print(f"magdesign solve: {message} ...", file=sys.stderr, flush=True)


def _objective(problem, result):
    if problem.objective is None:
        return None
    name = problem.objective.output
    return {"output": name, "sense": problem.objective.sense, "value": result.outputs[name]}


def _difference(cheap, exact, cheap_levels, exact_levels_name):
    """How far the cheap answer is from the exact one, parameter by parameter."""
    lines = [f"the first answer ({cheap_levels}) against the answer ({exact_levels_name}):"]
    for name, value in exact.parameters.items():
        unit = exact.units.get(name)
        lines.append(f"  {name:<24} {format_quantity(cheap.parameters[name], unit):<16} -> {format_quantity(value, unit):<16} "
                     f"(difference {format_quantity(value - cheap.parameters[name], unit)})")
    return "\n".join(lines)


def run_simulate(args):
    spec = load_spec(args.spec)
    scene, start = scene_at_start(spec)
    loads = loads_from_spec(spec)
    result = simulate(scene, loads, key=jax.random.key(0))
    # the outputs read no reading after the reading effects: the noisy simulation gives them too
    values = {name: float(value) for name, value in scene.outputs(result).items()}
    if args.json:
        print(json_text({**simulation_json(result), "start": start, "outputs": values,
                         "output_units": scene.output_units}))
    else:
        if start:
            shown = ", ".join(f"{name} = {value:.6g}" for name, value in start.items())
            print(f"a design spec: simulating its start point ({shown}, SI)")
        print(simulation_table(result))
        print("outputs (docs/outputs.md): " + ", ".join(
            f"{name} = {value:.6g} {scene.output_units.get(name, '1').removeprefix('1')}".rstrip()
            for name, value in values.items() if math.isfinite(value)))
    return 0 if bool(result.converged.all()) else EXIT_NOT_SOLVED


def run_accuracy(args):
    rows = accuracy.measure(progress=None if args.json else sys.stderr)
    print(json_text([row._asdict() for row in rows]) if args.json else accuracy.table(rows))
    if args.plot:
        accuracy.plot(rows, args.plot)
    return 0


def json_text(value) -> str:
    """``value`` as strict JSON: a non-finite number (which json.dumps would write as the
    bare, invalid NaN or Infinity) becomes null."""

    def finite(item):
        if isinstance(item, float):
            return item if math.isfinite(item) else None
        if isinstance(item, dict):
            return {key: finite(entry) for key, entry in item.items()}
        if isinstance(item, (list, tuple)):
            return [finite(entry) for entry in item]
        return item

    return json.dumps(finite(value), allow_nan=False)


def check_plot_path(path):
    """SpecError unless ``path`` is a PNG file that can be written (checked before any
    solve, so that a long run does not end in an error): a name ending in .png in an
    existing, writable folder, and not a folder itself."""
    target = Path(path)
    folder = target.parent
    if target.is_dir():
        raise SpecError(f"--plot {path}: a folder; give the path of the .png file to write")
    if target.suffix.lower() != ".png":
        raise SpecError(f"--plot {path}: give a file name ending in .png")
    if not folder.is_dir():
        raise SpecError(f"--plot {path}: no folder {folder}")
    if not os.access(folder, os.W_OK) or (target.exists() and not os.access(target, os.W_OK)):
        raise SpecError(f"--plot {path}: cannot write there")


def _fail(args, code, kind, message):
    """One line on stderr; with --json also one JSON object on stdout (its reader wants one)."""
    print(f"magdesign {args.command}: {message}", file=sys.stderr)
    if getattr(args, "json", False):
        print(json_text({"error": kind, "message": message, "exit_code": code}))
    return code


def _show_warning(message, category, filename, lineno, file=None, line=None):
    """A warning as one line on stderr ("magdesign: warning: ..."), without a source line."""
    print(f"magdesign: warning: {message}", file=sys.stderr if file is None else file)


def main(argv=None):
    args = build_parser().parse_args(argv)
    use_compilation_cache()
    warnings.showwarning = _show_warning
    command = {"solve": run_solve, "simulate": run_simulate, "accuracy": run_accuracy, "show": run_show}[args.command]
    try:
        if getattr(args, "plot", None):
            check_plot_path(args.plot)
        return command(args)
    except SpecError as error:
        return _fail(args, EXIT_BAD_SPEC, "bad_spec", str(error))
    except BrokenPipeError:
        # The reader went away (``magdesign simulate ... | head -1``): stop quietly, and keep
        # Python's final flush of stdout from failing again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:
        if getattr(args, "debug", False):
            raise
        first_line = (str(error).splitlines() or [""])[0][:200]
        return _fail(args, EXIT_INTERNAL, "internal_error",
                     f"internal error: {type(error).__name__}: {first_line} (run with --debug for the traceback)")


if __name__ == "__main__":
    sys.exit(main())
