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
from pathlib import Path

import jax

from magdesign import accuracy
from magdesign.design import solve as solve_problem
from magdesign.design.plot import plot_design
from magdesign.design.spec import default_spec, load_spec, problem_from_spec
from magdesign.scene import loads_from_spec, scene_from_spec, simulate, simulation_json, simulation_table
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
    solve.add_argument("--fidelity", help="mechanics fidelity level, overriding the spec (e.g. reissner, axisymmetric)")
    solve.add_argument("--plot", metavar="FILE", help="write a PNG of the targets and limits around the design")
    solve.add_argument("--timing", action="store_true", help="solve a second time and report that warm time too")

    simulate_cmd = add_parser("simulate", help="run a scene's forward chain over its load sweep")
    simulate_cmd.add_argument("spec", help="scene or design spec (TOML); a design spec simulates its start point")
    simulate_cmd.add_argument("--json", action="store_true", help="print one JSON object instead of the table")

    accuracy_cmd = add_parser("accuracy", help="measure every model's error against its time, on this machine")
    accuracy_cmd.add_argument("--json", action="store_true", help="print a JSON list of rows instead of the table")
    accuracy_cmd.add_argument("--plot", metavar="FILE", help="write a PNG of error against time (log-log)")

    show = add_parser("show", help="draw the sensor in its axial plane with its field, at rest and at the largest load")
    show.add_argument("spec", help="scene or design spec (TOML); a design spec shows its start point")
    show.add_argument("--plot", metavar="FILE", required=True, help="the PNG to write")
    return parser


def run_show(args):
    spec = load_spec(args.spec)
    plot_scene(scene_from_spec(spec), loads_from_spec(spec), args.plot, title=args.spec)
    print(f"wrote {args.plot}")
    return 0


def run_solve(args):
    spec = load_spec(args.spec) if args.spec else default_spec()
    problem, _ = problem_from_spec(spec, fidelity=args.fidelity)
    # The first solve traces and compiles; with --timing a second one measures the warm
    # time a design costs (not by default: at the axisymmetric level it doubles the wait).
    first = solve_problem(problem)
    result = solve_problem(problem) if args.timing else first
    if args.json:
        print(json_text({**result.to_json(), "first_call_seconds": first.seconds}))
    else:
        print(result.table())
        if args.timing:
            print(f"first call: {first.seconds:.3g} s (tracing and compiling included); the time above is a warm solve")
        else:
            print("the time above is the first call (tracing and compiling included); --timing adds a warm solve")
    if args.plot:
        plot_design(problem, result, args.plot)
    return 0 if result.status == "successful" else EXIT_NOT_SOLVED


def run_simulate(args):
    spec = load_spec(args.spec)
    scene = scene_from_spec(spec)
    result = simulate(scene, loads_from_spec(spec), key=jax.random.key(0))
    print(json_text(simulation_json(result)) if args.json else simulation_table(result))
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


def main(argv=None):
    args = build_parser().parse_args(argv)
    use_compilation_cache()
    command = {"solve": run_solve, "simulate": run_simulate, "accuracy": run_accuracy, "show": run_show}[args.command]
    try:
        if getattr(args, "plot", None):
            check_plot_path(args.plot)
        return command(args)
    except (SpecError, ValueError) as error:
        print(f"magdesign {args.command}: {error}", file=sys.stderr)
        return EXIT_BAD_SPEC
    except BrokenPipeError:
        # The reader went away (``magdesign simulate ... | head -1``): stop quietly, and keep
        # Python's final flush of stdout from failing again.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except Exception as error:
        if getattr(args, "debug", False):
            raise
        first_line = (str(error).splitlines() or [""])[0][:200]
        print(f"magdesign {args.command}: internal error: {type(error).__name__}: {first_line} "
              "(run with --debug for the traceback)", file=sys.stderr)
        return EXIT_INTERNAL


if __name__ == "__main__":
    sys.exit(main())
