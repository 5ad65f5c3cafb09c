"""The ``magdesign`` command (also ``python -m magdesign``).

    magdesign solve [SPEC.toml] [--json] [--fidelity LEVEL | --accuracy TOL] [--plot FILE] [--write FILE] [--timing]
    magdesign simulate SPEC.toml [--json]
    magdesign accuracy [--quick] [--json] [--plot FILE]
    magdesign show SPEC.toml --plot FILE
    magdesign tolerance SPEC.toml [--samples N] [--json] [--plot FILE] [--robust K] [--seed S] [--quiet]
    magdesign sweep SPEC.toml --over KEY=LO:HI:N [--over ...] | --points CSV [--json] [--csv FILE]
        [--plot FILE] [--fidelity LEVEL] [--quiet] [--devices N]
        [--coordinator HOST:PORT --num-processes N --process-id I | --distributed]

A skin's design spec with ``design.grids`` (candidate ``sensor.grid`` values) is solved by
``solve`` once per grid, fewest chips first, up to the first success (:func:`_solve_grids`).

Exit codes: 0 done (solve: solved), 1 internal error (a bug: one line; ``--debug`` shows
the traceback) or a stdout that cannot be written (a full disk), 2 bad spec or arguments
(one line naming the key), 3 solve not successful (the status and the violated target are
printed) or a simulation whose mechanics did not converge at some load point, 130
interrupted (Ctrl-C), 141 stdout closed by its reader (``| head -1``). Each error is one
line on stderr.

Progress goes to stderr, one line per stage ("magdesign solve: confirming at the exact
levels ..."), and "wrote FILE" for each file written; a bar, on a terminal only, moves per
point of a sweep. ``--quiet`` silences both; errors and warnings still print.

Compiled programs are kept in a persistent cache (~/.cache/magdesign/jax/<this CPU>; see
:func:`cache_directory`; MAGDESIGN_NO_CACHE=1 turns it off), and the traced programs of a
solve, simulate or sweep beside it (:func:`export_directory`, :mod:`magdesign._export`;
MAGDESIGN_NO_EXPORT=1 turns them off), so that a second run neither traces nor compiles.

The commands' arguments are :mod:`magdesign._cli_parser`'s; how the command writes to stdout
and stderr, and fails to, is :mod:`magdesign._cli_streams`'s.
"""

import atexit
import gc
import importlib
import math
import os
import sys
import time
import warnings
from pathlib import Path

import jax
import numpy as np

from magdesign import _export, _progress
from magdesign._cache import cache_directory, export_directory, use_compilation_cache
from magdesign._cli_parser import build_parser
from magdesign._cli_streams import (
    Stdout,
    StdoutFailed,
    check_output_path,
    drop_stdout,
    fail,
    json_text,
    note_unraisable,
    show_warnings_once,
)
from magdesign._progress import stage, wrote
from magdesign._tracing import random_key
from magdesign.design import solve as solve_problem
from magdesign.design import sweep as sweep_problem
from magdesign.design.report import format_quantity
from magdesign.design.solve import usable_cores
from magdesign.scene import (
    loads_from_spec,
    simulate,
    simulation_json,
    simulation_table,
    with_parameters,
)
from magdesign.scene.core import warn_if_clipping
from magdesign.spec.chips import fewest_chips
from magdesign.spec.design import (
    default_spec,
    design_grids,
    exact_levels,
    fidelity_levels,
    load_spec,
    problem_from_spec,
    stated_value,
)
from magdesign.spec.levels import (
    estimate,
    estimates_json,
    estimates_text,
    levels_of,
    parse_accuracy,
    solve_to_accuracy,
)
from magdesign.spec.scene import scene_from_spec
from magdesign.spec.sizes import check_fits
from magdesign.spec.sweep import input_units, sweep_points
from magdesign.spec.tolerance import tolerance_problem_from_spec
from magdesign.units import SpecError


# Modules that load matplotlib are imported by the commands that use them, so that a
# solve, simulate or sweep starts without it; ``cli.accuracy`` is the accuracy module.
def __getattr__(name):
    if name == "accuracy":
        return importlib.import_module("magdesign.accuracy")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# At exit the objects left (over 100,000: modules, JAX's caches) are frozen, so that Python's
# collections while it tears the modules down skip them (a fifth of a second of a command).
atexit.register(gc.freeze)

EXIT_INTERNAL = 1
EXIT_BAD_SPEC = 2
EXIT_NOT_SOLVED = 3
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a command stopped by Ctrl-C
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a writer whose reader left
# Said where a solve starts: a fresh process traces and compiles the solver first.
FIRST_CALL = "the first call compiles the model, up to minutes at the exact levels; later runs load it from the cache"


def scene_at_start(spec):
    """(scene, {variable: start} (SI)): a design spec's scene as written, which is where its
    variables start, with a variable the scene does not state at its start; a scene spec's
    scene and {}."""
    if "design" not in spec:
        return scene_from_spec(spec), {}
    problem, scene = problem_from_spec(spec)
    start = {v.name: float(v.start) for v in problem.variables}
    return with_parameters(scene, start), start


def run_show(args):
    from magdesign.scene.picture import plot_scene  # matplotlib: loaded by the commands that draw

    spec = load_spec(args.spec)
    stage(f"writing {args.plot}: the sensor at rest and at the largest load")
    plot_scene(scene_at_start(spec)[0], loads_from_spec(spec), args.plot, title=args.spec)
    wrote(args.plot)
    return 0


def _designed(spec, path):
    """One line saying what a spec designs: its name ([design] name, else the file's stem),
    magnet, mechanics and chip ("dome_hall: cylinder magnet, mooney_rivlin dome, AK8963
    hall3d chip")."""
    name = spec.get("design", {}).get("name") or (Path(path).stem if path else "the default design")
    magnet, mechanics, sensor = (spec.get(table) or {} for table in ("magnet", "mechanics", "sensor"))
    grid, positions = sensor.get("grid"), sensor.get("positions")
    count = (
        " x ".join(map(str, grid)) + " "
        if isinstance(grid, list)
        else f"{len(positions)} "
        if isinstance(positions, list) and len(positions) > 1
        else ""
    )
    chip = " ".join(str(part) for part in (sensor.get("preset"), sensor.get("model")) if part)
    body = " ".join(str(part) for part in (mechanics.get("material"), mechanics.get("model")) if part)
    parts = [f"{magnet.get('shape', '?')} magnet", body, f"{count}{chip} chip{'s' if count else ''}" if chip else ""]
    return f"{name}: " + ", ".join(part for part in parts if part)


def run_solve(args):
    began = time.perf_counter()
    spec = load_spec(args.spec) if args.spec else default_spec()
    accuracy = None if args.accuracy is None else parse_accuracy(args.accuracy)
    auto = args.fidelity in (None, "auto")
    if accuracy is not None and not auto:
        raise SpecError("--accuracy: it picks every model's level itself; give --accuracy or --fidelity, not both")
    if design_grids(spec) is not None:  # candidate chip grids: the design at each, fewest chips first
        return _solve_grids(args, spec, began)
    problem, scene = problem_from_spec(spec, fidelity=None if auto else args.fidelity)
    if "tolerances" in spec.get("design", {}):  # read by the tolerance command: one rule for both
        with warnings.catch_warnings():  # the spec's warnings are said once, above
            warnings.simplefilter("ignore")
            tolerance_problem_from_spec(spec, fidelity=None if auto else args.fidelity, built=(problem, scene))
    start = accurate = None
    if accuracy is not None:
        stage(f"solving to an accuracy of {accuracy:.3g}, every model from its cheapest level ({FIRST_CALL})")
        accurate = solve_to_accuracy(spec, accuracy=accuracy)
        answers = [(levels, accurate.problem, answer) for levels, answer in accurate.answers]
    else:
        answers, start = _solve_at_levels(args, spec, problem, auto)
    levels, problem, result = answers[-1]
    estimates = _estimates(result, accurate)
    if args.timing:
        stage(f"--timing: solving again at {levels}, warm")
    warm = solve_problem(problem, start=start) if args.timing else None
    if args.json:
        document = {**result.to_json(), "fidelity": levels, "objective": _objective(problem, result)}
        if len(answers) > 1:
            cheap = answers[0]
            document["first_level"] = {**cheap[2].to_json(), "fidelity": cheap[0]}
        document.update(estimates_json(result.source, estimates))
        if accurate is not None:
            document["accuracy"] = {"asked": accuracy, "reached": accurate.reached, "why": accurate.why}
        if warm is not None:
            document["warm_seconds"] = warm.seconds
        document["total_seconds"] = time.perf_counter() - began
        print(json_text(document))
    else:
        print(_designed(spec, args.spec))
        for index, (name, _, answer) in enumerate(answers):
            role = "the answer" if index == len(answers) - 1 else "first answer, confirmed below"
            print(f"{name} ({role}):" if name else f"{role}:")  # a scene without levels names none
            print(answer.table())
            print(
                f"   that solve took {answer.seconds:.3g} s (first call: tracing, and compiling or loading from the cache, included)\n"
            )
        if len(answers) > 1:
            print(_difference(answers[0][2], result, answers[0][0], levels))
        if estimates is not None:
            print(estimates_text(result.source, estimates, result.outputs, result.units))
        if accurate is not None:
            print(accurate.verdict)
        if warm is not None:
            print(f"warm solve at {levels}: {warm.seconds * 1e3:.3g} ms")
        print(f"total time: {time.perf_counter() - began:.3g} s")
    if accurate is not None and not accurate.reached:
        print(f"magdesign solve: {accurate.verdict}", file=sys.stderr)
    if args.write:
        _write_answer(args, result)
    if args.plot:
        from magdesign.design.plot import plot_design

        stage(f"writing {args.plot}: each target and limit along each variable, at {levels}")
        plot_design(problem, result, args.plot)
        wrote(args.plot)
    reached = accurate is None or accurate.reached
    return 0 if result.status == "successful" and reached else EXIT_NOT_SOLVED


def _solve_grids(args, spec, began):
    """solve with ``design.grids``: the design solved at each candidate ``sensor.grid``, fewest
    chips first, until one succeeds (:func:`magdesign.spec.fewest_chips`); each trial's status
    in a table, then the first successful grid's answer as a solve reports one (its --write,
    --plot). Exit 3 where no grid succeeds."""
    for option, given in (
        ("--accuracy", args.accuracy is not None),
        ("--fidelity", args.fidelity not in (None, "auto")),
        ("--timing", args.timing),
    ):
        if given:
            raise SpecError(
                f"{option}: not with design.grids (each candidate grid is solved once, at the spec's levels)"
            )
    grids = design_grids(spec)
    levels = _levels_at(spec)
    stage(f"{_solving_at(levels)} at each candidate grid, fewest chips first ({FIRST_CALL})")
    found = fewest_chips(spec, grids, key="design.grids", before=lambda grid: stage(f"sensor.grid = {list(grid)}"))
    solved = [trial.result for trial in found.trials if trial.result is not None]
    if not solved:  # nothing to report a status of: the spec cannot be solved at any candidate
        reasons = "; ".join(f"{list(trial.grid)}: {trial.reason}" for trial in found.trials)
        raise SpecError(f"design.grids: every candidate grid is refused ({reasons})")
    best = found.best
    result = None if best is None else best.result
    estimates = None if result is None else _estimates(result, None)
    objective = None
    if result is not None and result.objective is not None:
        name, sense = result.objective
        objective = {"output": name, "sense": sense, "value": result.outputs[name]}
    if args.json:
        document = (
            {
                "parameters": {},
                "targets": {},
                "steps": sum(r.steps for r in solved),
                "seconds": sum(r.seconds for r in solved),
            }
            if result is None
            else {**result.to_json(), **estimates_json(result.source, estimates)}
        )
        document.update(found.to_json(), fidelity=levels, objective=objective)
        # the contract's status is a solver's: where no grid succeeds, the last candidate's
        document["search"], document["status"] = found.status, (solved[-1] if result is None else result).status
        document["total_seconds"] = time.perf_counter() - began
        print(json_text(document))
    else:
        unsized = {**spec, "sensor": {k: v for k, v in spec["sensor"].items() if k != "grid"}}  # no grid found
        print(_designed(unsized if result is None else result.source, args.spec))
        print(f"candidate grids, fewest chips first{' (' + levels + ')' if levels else ''}:\n{found.table()}\n")
        if result is None:
            print(f"no candidate grid succeeded (status: {found.status})")
        else:
            print(f"the answer, sensor.grid = {list(best.grid)} ({best.chips} chips):\n{result.table()}\n")
            if estimates is not None:
                print(estimates_text(result.source, estimates, result.outputs, result.units))
        print(f"total time: {time.perf_counter() - began:.3g} s")
    if result is None:
        if args.write or args.plot:
            print("magdesign solve: no candidate grid succeeded: nothing written", file=sys.stderr)
        return EXIT_NOT_SOLVED
    if args.write:
        _write_answer(args, result)
    if args.plot:
        from magdesign.design.plot import plot_design

        stage(f"writing {args.plot}: each target and limit along each variable, at sensor.grid = {list(best.grid)}")
        plot_design(problem_from_spec(result.source)[0], result, args.plot)
        wrote(args.plot)
    return 0


def _solving_at(levels: str) -> str:
    """The progress line's stage: "solving at" the levels, or "solving" for a scene without any."""
    return f"solving at {levels}" if levels else "solving"


def _solve_at_levels(args, spec, problem, auto):
    """([(levels, problem, result)] of the solve at the spec's (or --fidelity's) levels and, with
    --fidelity auto, its confirmation at the exact levels; the confirmation's start or None)."""
    levels = _levels_at(spec, None if auto else args.fidelity)
    stage(f"{_solving_at(levels)} ({FIRST_CALL})")
    first = solve_problem(problem)
    answers = [(levels, problem, first)]
    exact = exact_levels(spec) if auto else None
    if exact is not None and not all(math.isfinite(value) for value in first.parameters.values()):
        print("magdesign solve: the first answer is not finite; no confirmation at the exact levels", file=sys.stderr)
        exact = None
    if exact is None:
        return answers, None
    # Confirm at the exact levels, from the cheap answer: a few steps of the costly model.
    exact_problem, _ = problem_from_spec(exact)
    confirming = fidelity_levels(exact)
    stage(f"confirming at the exact levels, {confirming}, from that answer ({FIRST_CALL})")
    start = {
        v.name: min(max(first.parameters[v.name], float(v.lower)), float(v.upper)) for v in exact_problem.variables
    }
    answers.append((confirming, exact_problem, solve_problem(exact_problem, start=start)))
    return answers, start


def _estimates(result, accurate):
    """``result``'s error estimates: the accuracy run's, else found here; None where not finite."""
    if accurate is not None or not all(math.isfinite(value) for value in result.parameters.values()):
        return accurate and accurate.estimates
    stage(f"estimating each output's error: each model one level finer ({FIRST_CALL})")
    return estimate(result.source, result.parameters, base=result.outputs)


def _no_grids(spec, command):
    """SpecError naming design.grids: the candidate grids are ``solve``'s search, and
    ``command`` would silently solve the spec's own sensor.grid instead."""
    if design_grids(spec) is not None:
        raise SpecError(
            f"design.grids: magdesign {command} takes the spec's own sensor.grid; the candidate grids are for "
            "magdesign solve (drop design.grids, and set sensor.grid to the grid to analyse)"
        )


def _levels_at(spec, fidelity=None):
    """The levels a run of ``spec`` with ``--fidelity`` (a mechanics level, or None) is at: the
    models' fidelities and a skin's field ("skin linear 60x60x6"), or "" for neither."""
    if fidelity is not None:
        spec = {**spec, "mechanics": {**spec.get("mechanics", {}), "fidelity": fidelity}}
    skin = levels_of(spec).get("skin")
    return ", ".join(part for part in (fidelity_levels(spec), skin and f"skin {skin}") if part)


def _write_answer(args, result):
    """--write: the answer as a spec; one line on stderr, not the file, when it has no
    finite values to write."""
    try:
        result.write_spec(args.write)
    except ValueError as error:
        print(f"magdesign solve: --write {args.write}: not written: {error}", file=sys.stderr)
        return
    except OSError as error:
        raise SpecError(f"--write {args.write}: cannot write ({error.strerror})") from None
    wrote(args.write)


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
        lines.append(
            f"  {name:<24} {format_quantity(cheap.parameters[name], unit):<16} -> {format_quantity(value, unit):<16} "
            f"(difference {format_quantity(value - cheap.parameters[name], unit)})"
        )
    return "\n".join(lines)


def _simulated(scene, loads, key):
    """(the simulation, its outputs) in one program (kept on disk, magdesign._export), not the
    outputs op by op; no output reads the readings after the reading effects: noise is harmless."""
    result = simulate(scene, loads, key=key)
    return result, scene.outputs(result)


_simulate = _export.filter_jit(_simulated, "simulate")

SWEEP_TABLE_ROWS = 200  # a longer sweep prints its summary only (see --csv / --json)


def _start_devices(args):
    """Set up the devices a sweep runs on, before JAX starts: ``--devices N`` host devices,
    and jax.distributed for several processes (CPU collectives by gloo)."""
    if args.devices is not None:
        cores = usable_cores()
        if not 1 <= args.devices <= cores:
            raise SpecError(f"--devices {args.devices}: expected 1 to {cores}, the CPU cores this process may use")
        jax.config.update("jax_num_cpu_devices", args.devices)
    if _distributed(args):
        if args.num_processes is not None and args.num_processes < 1:
            raise SpecError(f"--num-processes {args.num_processes}: expected at least 1")
        if args.process_id is not None and not 0 <= args.process_id < (args.num_processes or args.process_id + 1):
            raise SpecError(f"--process-id {args.process_id}: expected 0 to --num-processes - 1")
        jax.config.update("jax_cpu_collectives_implementation", "gloo")
        jax.distributed.initialize(
            coordinator_address=args.coordinator, num_processes=args.num_processes, process_id=args.process_id
        )


def _distributed(args) -> bool:
    """Whether the command runs under jax.distributed (--distributed, a coordinator, process
    count or id, or JAX_COORDINATOR_ADDRESS); commands without those options never do."""
    named = [getattr(args, name, None) for name in ("coordinator", "num_processes", "process_id")]
    distributed = getattr(args, "distributed", False) or os.environ.get("JAX_COORDINATOR_ADDRESS")
    return bool(distributed) or any(value is not None for value in named)


def _sets_up_devices(args) -> bool:
    """Whether the command sets up its devices (:func:`_start_devices`: ``--devices``,
    jax.distributed), which JAX takes only before it starts its backend."""
    return getattr(args, "devices", None) is not None or _distributed(args)


def run_sweep(args):
    _start_devices(args)
    spec = load_spec(args.spec)
    _no_grids(spec, "sweep")
    if args.plot and args.points is None and len(args.over) > 2:
        raise SpecError("--plot: a picture shows 1 or 2 swept keys (curves or maps)")
    problem, scene = problem_from_spec(spec, fidelity=args.fidelity)
    values, shown, grid = sweep_points(args.over, args.points, input_units(spec, problem, scene))
    if args.plot and len(values) > 2:
        raise SpecError("--plot: a picture shows 1 or 2 swept keys (curves or maps)")
    count = math.prod(len(v) for v in values.values()) if grid else len(next(iter(values.values())))
    levels = _levels_at(spec, args.fidelity)
    stage(f"solving {count} point{'s' if count != 1 else ''}{' at ' + levels if levels else ''}")
    try:
        result = sweep_problem(
            problem,
            values,
            grid=grid,
            progress=False if args.quiet else None,
            over_units={k: None if u == "1" else u for k, u in shown.items()},
        )
    except ValueError as error:
        raise SpecError(str(error)) from None
    if jax.process_index() != 0:  # every process holds the merged result; the first one writes it
        return 0 if result.successful.all() else EXIT_NOT_SOLVED
    if args.csv:
        result.write_csv(args.csv)
        wrote(args.csv)
    if args.json:
        print(
            json_text(
                {
                    "over": list(result.over),
                    "shape": list(result.shape),
                    "grid": grid,
                    "status_counts": result.status_counts(),
                    "seconds": result.seconds,
                    "units": {k: v for k, v in result.units.items() if v},
                    "points": result.records(),
                }
            )
        )
    else:
        if result.status.size <= SWEEP_TABLE_ROWS:
            print(result.table())
        print(f"magdesign sweep: {result.summary()}" + (f"; every point written to {args.csv}" if args.csv else ""))
    if args.plot:
        from magdesign.design.plot import plot_sweep

        stage(f"writing {args.plot}")
        plot_sweep(result, args.plot)
        wrote(args.plot)
    return 0 if result.successful.all() else EXIT_NOT_SOLVED


def run_simulate(args):
    spec = load_spec(args.spec)
    scene, start = scene_at_start(spec)
    loads = loads_from_spec(spec)
    levels = _levels_at(spec)
    stage(f"simulating the load sweep{' at ' + levels if levels else ''} ({FIRST_CALL})")
    result, outputs = _simulate(scene, loads, key=random_key(0))
    warn_if_clipping(scene, result)
    order = list(scene.output_units)  # the scene's order (a program's dict comes back sorted)
    ranked = sorted(outputs, key=lambda name: order.index(name) if name in order else len(order))
    values = {name: float(outputs[name]) for name in ranked}
    # one more evaluation of the outputs per model, at its next level (noiseless, as the outputs are)
    stage("estimating each output's error: each model one level finer")
    estimates = estimate(spec, start, base=values)
    if args.json:
        document = {**simulation_json(result), "start": start, "outputs": values, "output_units": scene.output_units}
        print(json_text({**document, **estimates_json(spec, estimates)}))
    else:
        unstated = {name: value for name, value in start.items() if stated_value(spec, name) is None}
        if unstated:
            shown = ", ".join(f"{name} = {value:.6g}" for name, value in unstated.items())
            print(
                f"a design spec: its scene as written, with the variables it does not state at their start ({shown}, SI)"
            )
        print(simulation_table(result))
        print(
            "outputs (docs/outputs.md): "
            + ", ".join(
                f"{name} = {value:.6g} {scene.output_units.get(name, '1').removeprefix('1')}".rstrip()
                for name, value in values.items()
                if math.isfinite(value)
            )
        )
        units = {name: unit.removeprefix("1") or None for name, unit in scene.output_units.items()}
        print(estimates_text(spec, estimates, values, units))
    return 0 if bool(np.all(np.asarray(result.converged))) else EXIT_NOT_SOLVED


def run_tolerance(args):
    from magdesign.design import tolerance as tolerance_analysis

    if args.samples < 1:
        raise SpecError(f"--samples: expected a positive number of samples, got {args.samples}")
    if args.robust is not None and not (math.isfinite(args.robust) and args.robust > 0):
        raise SpecError(f"--robust: expected a number of sigmas K > 0, got {args.robust:g}")
    if not 0 <= args.seed < 2**63:  # jax.random.key takes a 64-bit signed integer
        raise SpecError(f"--seed {args.seed}: expected a whole number from 0 to 2**63 - 1")
    spec = load_spec(args.spec)
    _no_grids(spec, "tolerance")
    tp = tolerance_problem_from_spec(spec)
    # the samples' outputs are kept (samples x outputs float64), twice while they are joined
    check_fits(f"--samples {args.samples}", args.samples * len(tp.problem.outputs), factor=2, what="its outputs")
    levels = _levels_at(spec)

    def analyse(result, what):
        if not result.successful:
            print(
                f"magdesign tolerance: the {what} solve ended {result.status}: analysing its end point anyway",
                file=sys.stderr,
            )
        stage(f"Monte Carlo of the {what} design, {args.samples} samples")
        return tolerance_analysis.monte_carlo(
            tp, result.parameters, samples=args.samples, seed=args.seed, progress=False if args.quiet else None
        )

    stage(f"{_solving_at(levels)} ({FIRST_CALL})")
    nominal = solve_problem(tp.problem)
    runs = [("nominal", nominal, analyse(nominal, "nominal"))]
    if args.robust is not None:
        stage(f"solving with every limit held at {args.robust:g} sigma (first order)")
        robust = tolerance_analysis.robust_solve(tp, args.robust, start=nominal.parameters)
        runs.append(("robust", robust, analyse(robust, "robust")))
    if args.json:
        document = {
            "status": nominal.status,
            "yield": runs[0][2].yield_fraction,
            "fidelity": levels,
            "tolerances": tolerance_analysis.describe(tp),
            "design": {**nominal.to_json(), "monte_carlo": runs[0][2].to_json()},
            "robust": None,
        }
        if args.robust is not None:
            document["robust"] = {"k": args.robust, **runs[1][1].to_json(), "monte_carlo": runs[1][2].to_json()}
        print(json_text(document))
    else:
        print(f"tolerances:\n{tolerance_analysis.tolerance_lines(tp)}")
        for name, result, carlo in runs:
            held = f", every limit held at {args.robust:g} sigma (first order)" if name == "robust" else ""
            at = f" ({levels}{held})" if levels else f" ({held[2:]})" if held else ""
            print(f"\n{name} design{at}:\n{result.table()}\n")
            print(carlo.table())
        if args.robust is not None:
            print(
                "\nyield: "
                + ", ".join(
                    f"{name} {100 * carlo.yield_fraction:.4g} % ({result.status})" for name, result, carlo in runs
                )
            )
    if args.plot:
        stage(f"writing {args.plot}")
        tolerance_analysis.plot_tolerance(
            runs[0][2], args.plot, robust=runs[1][2] if len(runs) > 1 else None, title=Path(args.spec).name
        )
        wrote(args.plot)
    return 0 if all(result.successful for _, result, _ in runs) else EXIT_NOT_SOLVED


def run_accuracy(args):
    from magdesign import accuracy

    rows = accuracy.measure(quick=args.quick)
    print(json_text([row._asdict() for row in rows]) if args.json else accuracy.table(rows))
    if args.plot:
        stage(f"writing {args.plot}")
        accuracy.plot(rows, args.plot)
        wrote(args.plot)
    return 0


def main(argv=None):
    args = build_parser().parse_args(argv)
    use_compilation_cache(getattr(args, "debug", False))
    warnings.showwarning = show_warnings_once()
    command = {
        "solve": run_solve,
        "simulate": run_simulate,
        "accuracy": run_accuracy,
        "show": run_show,
        "sweep": run_sweep,
        "tolerance": run_tolerance,
    }[args.command]
    _progress.enable(None if args.quiet else f"magdesign {args.command}")
    kept, directory = _export.directory(), cache_directory()  # the command's exported programs, for its run
    _export.enable(None if directory is None else export_directory(directory))
    # the programs that the last run of these arguments here loaded, loaded ahead as it starts;
    # not for a sweep that sets up its devices, which must come before JAX starts its backend
    run = None if _sets_up_devices(args) else f"{os.getcwd()}\n{sys.argv[1:] if argv is None else list(argv)}"
    if run is not None:
        try:
            _export.load_ahead(run)
        except Exception:  # loading ahead only saves time: the run loads what it needs itself
            pass
    stdout, sys.stdout = sys.stdout, Stdout(sys.stdout)
    unraisable, sys.unraisablehook = sys.unraisablehook, note_unraisable
    code = None  # the command's own exit code where it returned (its run is complete)
    try:
        if getattr(args, "plot", None):
            check_output_path(args.plot)
        if getattr(args, "csv", None):
            check_output_path(args.csv, "--csv", ".csv")
        if getattr(args, "write", None):
            check_output_path(args.write, "--write", ".toml")
        code = command(args)
        _progress.check_interrupt()
        sys.stdout.flush()  # a full or closed stdout fails here, not in Python's flush at exit
        return code
    except SpecError as error:
        return fail(args, EXIT_BAD_SPEC, "bad_spec", str(error))
    except KeyboardInterrupt:
        # Ctrl-C: one line, the shell's code for SIGINT; files are written only after the work
        return fail(args, EXIT_INTERRUPTED, "interrupted", "interrupted")
    except StdoutFailed as failed:
        drop_stdout()
        if isinstance(failed.error, BrokenPipeError):  # the reader left (``magdesign ... | head -1``)
            print(f"magdesign {args.command}: stdout closed by its reader; output cut short", file=sys.stderr)
            return EXIT_BROKEN_PIPE
        print(f"magdesign {args.command}: cannot write to stdout ({failed.error.strerror})", file=sys.stderr)
        return EXIT_INTERNAL
    except Exception as error:
        if getattr(args, "debug", False):
            raise
        first_line = (str(error).splitlines() or [""])[0][:200]
        return fail(
            args,
            EXIT_INTERNAL,
            "internal_error",
            f"internal error: {type(error).__name__}: {first_line} (run with --debug for the traceback)",
        )
    finally:
        _progress.enable(None)
        if run is not None:
            _export.remember_run(run, succeeded=code is not None)
        _export.enable(kept)
        sys.stdout, sys.unraisablehook = stdout, unraisable


if __name__ == "__main__":
    sys.exit(main())
