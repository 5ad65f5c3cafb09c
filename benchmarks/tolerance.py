"""Speed of the tolerance analysis (magdesign.design.tolerance). Run by hand:

    .venv/bin/python benchmarks/tolerance.py [--samples N]

Prints, for 100,000 samples (or N):
- the Monte Carlo of the default design (magdesign/design/default.toml, solved first) with
  tolerances on its remanence (2 %), its dome's moduli (5 % each) and its temperature (10 K):
  the default scene as it is (the field on the axis, the dome-Hall paper's Eq. 1);
- the same for examples/dome_hall_tolerances.toml, whose placement (50 um) and tilt (2 deg)
  tolerances move the sensor off the axis: its samples read the exact field;
each as the first call (tracing and compiling included) and the median of 3 warm calls,
with samples per second; then the robust solve of the example (limits at 2 sigma), first
call and warm.
"""

import statistics
import sys
import time
import tomllib

from magdesign.design import solve
from magdesign.design.tolerance import monte_carlo, robust_solve
from magdesign.spec.design import default_spec
from magdesign.spec.tolerance import tolerance_problem_from_spec

SAMPLES = int(sys.argv[sys.argv.index("--samples") + 1]) if "--samples" in sys.argv else 100_000


def timed(function, repeats=3):
    """(first call's seconds, median of ``repeats`` warm calls' seconds, last result)."""
    began = time.perf_counter()
    result = function()
    first = time.perf_counter() - began
    warm = []
    for _ in range(repeats):
        began = time.perf_counter()
        result = function()
        warm.append(time.perf_counter() - began)
    return first, statistics.median(warm), result


def table(rows):
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())


def main():
    spec = default_spec()
    spec["design"]["tolerances"] = {
        "magnet.remanence": "2 %",
        "mechanics.c10": "5 %",
        "mechanics.c01": "5 %",
        "temperature": "10 K",
    }
    with open("examples/dome_hall_tolerances.toml", "rb") as file:
        example = tomllib.load(file)
    rows = [("case", "samples", "first call (s)", "warm (s)", "warm samples/s", "yield")]
    for name, case in (
        ("default scene (field on the axis)", spec),
        ("example, placement + tilt (exact field)", example),
    ):
        tp = tolerance_problem_from_spec(case)
        design = solve(tp.problem)
        first, warm, result = timed(lambda: monte_carlo(tp, design.parameters, samples=SAMPLES, progress=False))
        rows.append(
            (
                f"Monte Carlo, {name}",
                SAMPLES,
                f"{first:.3g}",
                f"{warm:.3g}",
                f"{SAMPLES / warm:.3g}",
                f"{100 * result.yield_fraction:.4g} %",
            )
        )
    first, warm, robust = timed(lambda: robust_solve(tp, 2.0, start=design.parameters))
    rows.append(
        (
            f"robust solve of the example, k = 2 ({robust.status}, {robust.rounds} rounds; its programs compiled above)",
            "",
            f"{first:.3g}",
            f"{warm:.3g}",
            "",
            "",
        )
    )
    table(rows)


if __name__ == "__main__":
    main()
