"""The ``magdesign`` command's arguments: its subcommands, their options and help
(:func:`build_parser`, used by :func:`magdesign.cli.main`)."""

import argparse
import importlib.metadata


def build_parser():
    debug = argparse.ArgumentParser(add_help=False)
    # Taken before or after the command; SUPPRESS keeps a command's default from hiding the first.
    debug.add_argument(
        "--debug", action="store_true", default=argparse.SUPPRESS, help="show the traceback of an internal error"
    )
    parser = argparse.ArgumentParser(
        prog="magdesign",
        parents=[debug],
        description="Design magnetic tactile sensors by differentiable optimisation.",
        epilog="Exit codes: 0 done, 1 internal error (or stdout not writable), 2 bad spec or arguments, "
        "3 not solved (or mechanics not converged), 130 interrupted, 141 stdout closed by its reader. "
        "Progress lines go to stderr (--quiet: none). Specs are TOML: every key, its unit, default and range is in "
        "the spec reference (`python -m magdesign.spec.reference` prints it; also in the docs).",
    )
    parser.add_argument("--version", action="version", version=f"magdesign {importlib.metadata.version('magdesign')}")
    sub = parser.add_subparsers(dest="command", required=True)
    quiet = argparse.ArgumentParser(add_help=False)
    quiet.add_argument(
        "--quiet", action="store_true", help="no progress lines or bars on stderr (errors and warnings still print)"
    )
    add_parser = lambda name, **kwargs: sub.add_parser(name, parents=[debug, quiet], **kwargs)  # noqa: E731

    solve = add_parser("solve", help="solve a design spec (default: the soft dome with a Hall sensor)")
    solve.add_argument("spec", nargs="?", help="design spec (TOML); the built-in default design if omitted")
    solve.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    solve.add_argument(
        "--fidelity",
        default="auto",
        help="auto (default): solve at the spec's levels, then confirm from that answer with the "
        "exact dome (axisymmetric) and field (exact) models, and report both; or one mechanics "
        "level for every solve (e.g. reissner, axisymmetric)",
    )
    solve.add_argument(
        "--accuracy",
        metavar="TOL",
        help="a relative accuracy (1%% or 0.01): each model from its cheapest level up until every "
        "target's and limit's estimated error is within it (else exit 3); not with --fidelity",
    )
    solve.add_argument("--plot", metavar="FILE", help="write a PNG of the targets and limits around the design")
    solve.add_argument(
        "--write",
        metavar="FILE",
        help="write the answer as a spec (TOML): the spec with the solved "
        "values in its scene tables, at the answer's levels, for simulate and show",
    )
    solve.add_argument(
        "--timing", action="store_true", help="solve the answer's problem again and report that warm time too"
    )

    simulate_cmd = add_parser("simulate", help="run a scene's forward chain over its load sweep")
    simulate_cmd.add_argument(
        "spec",
        help="scene or design spec (TOML); a design spec simulates its scene as "
        "written (a [design.variables] entry the scene does not state at its start), then "
        "lists the design outputs",
    )
    simulate_cmd.add_argument("--json", action="store_true", help="print one JSON object instead of the table")

    accuracy_cmd = add_parser("accuracy", help="measure every model's error against its time, on this machine")
    accuracy_cmd.add_argument(
        "--quick",
        action="store_true",
        help="a cheaper tier, under a minute on 2 cores: 3 repeats; the dome at Reissner against "
        "the default mesh 2x16 (in place of 4x32), the spheres at 4 cells across; no suspension "
        "pole, no default design",
    )
    accuracy_cmd.add_argument("--json", action="store_true", help="print a JSON list of rows instead of the table")
    accuracy_cmd.add_argument("--plot", metavar="FILE", help="write a PNG of error against time (log-log)")

    sweep_cmd = add_parser("sweep", help="solve a design spec at every point of a grid (or list) of its inputs")
    sweep_cmd.add_argument("spec", help="design spec (TOML)")
    sweep_cmd.add_argument(
        "--over",
        metavar="KEY=LO:HI:N",
        action="append",
        default=[],
        help="sweep KEY over N values from LO to HI (units as in specs, e.g. "
        "mechanics.outer_radius=6mm:10mm:5); repeat for a grid. KEY: a target (compliance), a limit "
        "bound (field_max.upper) or a scene parameter that is not a variable",
    )
    sweep_cmd.add_argument(
        "--points",
        metavar="CSV",
        help="a CSV file of points instead of a grid: a header row of "
        "keys, then one row per point (quantities with units, or SI numbers)",
    )
    sweep_cmd.add_argument("--json", action="store_true", help="print one JSON object with every point")
    sweep_cmd.add_argument("--csv", metavar="FILE", help="write every point (SI) to a CSV file")
    sweep_cmd.add_argument(
        "--plot",
        metavar="FILE",
        help="write a PNG: curves with their derivatives (one key), maps with contours (two keys)",
    )
    sweep_cmd.add_argument(
        "--fidelity", help="one mechanics level for every point (e.g. reissner, axisymmetric); default: the spec's"
    )
    sweep_cmd.add_argument(
        "--devices",
        type=int,
        metavar="N",
        help="split this machine's CPU into N XLA devices and the points over them (a model "
        "with slow loops of its own goes a point at a time on a thread per core instead, each "
        "started from the one before's predicted optimum)",
    )
    sweep_cmd.add_argument("--coordinator", metavar="HOST:PORT", help="jax.distributed: process 0's address")
    sweep_cmd.add_argument("--num-processes", type=int, metavar="N", help="jax.distributed: how many processes")
    sweep_cmd.add_argument("--process-id", type=int, metavar="I", help="jax.distributed: this process's index")
    sweep_cmd.add_argument(
        "--distributed",
        action="store_true",
        help="jax.distributed from the cluster's environment (SLURM, Open MPI, JAX_COORDINATOR_ADDRESS)",
    )

    show = add_parser("show", help="draw the sensor in its axial plane with its field, at rest and at the largest load")
    show.add_argument("spec", help="scene or design spec (TOML); a design spec shows its scene as written")
    show.add_argument("--plot", metavar="FILE", required=True, help="the PNG to write")

    tolerance = add_parser(
        "tolerance",
        help="solve a design spec, then a Monte Carlo over its [design.tolerances]: "
        "each output's spread, the yield, the inputs that matter most",
    )
    tolerance.add_argument("spec", help="design spec (TOML) with a [design.tolerances] table")
    tolerance.add_argument(
        "--samples", type=int, default=100_000, metavar="N", help="Monte Carlo samples (default 100000)"
    )
    tolerance.add_argument("--json", action="store_true", help="print one JSON object instead of the tables")
    tolerance.add_argument(
        "--plot", metavar="FILE", help="write a PNG of each target and limit output's histogram with its bounds"
    )
    tolerance.add_argument(
        "--robust",
        type=float,
        metavar="K",
        help="also solve with every limit held at K first-order "
        "sigmas of its output, and give that design's Monte Carlo beside the nominal one",
    )
    tolerance.add_argument("--seed", type=int, default=0, metavar="S", help="PRNG seed of the samples (default 0)")
    return parser
