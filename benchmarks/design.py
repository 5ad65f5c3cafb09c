"""Speed of the design solver on the default design (issue 5). Run by hand:

    .venv/bin/python benchmarks/design.py [--skip-axisymmetric]

Prints: warm time of one solve at the Reissner and axisymmetric dome levels, a vmapped
batch of 10,000 target compliances at the Reissner level, and the same batch solved the
way a user would without magdesign (scipy.optimize.least_squares, magpylib for the field,
the Reissner closed form for the dome), timed on a smaller batch and extrapolated.
"""

import sys
import time

import magpylib
import numpy as np
from scipy.optimize import least_squares

from magdesign.design import default_problem, solve, sweep
from magdesign.units import mm, mT

BATCH = 10_000
SCIPY_BATCH = 200


def warm_solve(fidelity, repeats):
    problem = default_problem(fidelity)
    began = time.perf_counter()
    first = solve(problem)
    compile_s = time.perf_counter() - began
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        result = solve(problem)
        times.append(time.perf_counter() - began)
    return first, result, compile_s, np.median(times)


def scipy_design(compliance, model):
    """Rest gap and thickness for one target compliance, the hand-written way."""
    material = model.material
    e, nu = float(material.youngs_modulus), float(material.poisson_ratio)
    reissner = lambda t: (model.outer_radius - t / 2) * np.sqrt(3 * (1 - nu**2)) / (4 * e * t**2)  # noqa: E731
    thickness = least_squares(lambda t: reissner(t[0]) / compliance - 1, [2 * mm], bounds=(1.5 * mm, 4 * mm)).x[0]
    magnet = magpylib.magnet.Cylinder(
        polarization=(0, 0, model.remanence), dimension=(2 * model.radius, model.height), position=(0, 0, 0)
    )
    field = lambda z: magnet.getB((0, 0, model.height / 2 + z))[2]  # noqa: E731
    closest = least_squares(lambda z: field(z[0]) / (4.8 * mT) - 1, [6 * mm], bounds=(0.5 * mm, 20 * mm)).x[0]
    return closest + compliance * model.max_force, thickness


def main():
    rows = []
    first, result, compile_s, warm = warm_solve("reissner", 200)
    rows.append(("solve, Reissner dome", f"{warm * 1e3:.3f} ms warm", f"first call {compile_s:.1f} s", result.status))
    if "--skip-axisymmetric" not in sys.argv:
        _, result_axi, compile_axi, warm_axi = warm_solve("axisymmetric", 5)
        rows.append(
            ("solve, axisymmetric dome", f"{warm_axi * 1e3:.3f} ms warm", f"first call {compile_axi:.1f} s",
             f"{result_axi.status}, t = {result_axi.parameters['thickness'] / mm:.5f} mm")
        )
    problem = default_problem("reissner")
    values = np.linspace(0.2, 0.45, BATCH) * mm
    sweep(problem, "compliance", values)  # compile
    batch = sweep(problem, "compliance", values)
    rows.append(
        ("vmap batch of 10,000 compliances", f"{batch.seconds:.3f} s", f"{batch.successful.mean() * 100:.1f} % solved",
         f"{batch.seconds / BATCH * 1e6:.1f} us per design")
    )
    model = problem.model
    began = time.perf_counter()
    scipy_rows = [scipy_design(c, model) for c in values[:: BATCH // SCIPY_BATCH]]
    scipy_s = (time.perf_counter() - began) * BATCH / SCIPY_BATCH
    rows.append(
        ("scipy least_squares + magpylib", f"{scipy_s:.1f} s (extrapolated)", f"timed on {SCIPY_BATCH} designs",
         f"ratio scipy / magdesign batch = {scipy_s / batch.seconds:.0f}")
    )
    gaps = np.array([g for g, _ in scipy_rows])
    agree = np.max(np.abs(gaps / batch.parameters["gap"][:: BATCH // SCIPY_BATCH] - 1))
    rows.append(("max relative gap difference", f"{agree:.1e}", "scipy/magpylib vs magdesign", ""))
    widths = [max(len(str(r[i])) for r in rows) for i in range(4)]
    for row in rows:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)))
    print(f"default design: rest gap {first.parameters['gap'] / mm:.4f} mm, closest {first.outputs['closest_gap'] / mm:.4f} mm,"
          f" thickness {first.parameters['thickness'] / mm:.5f} mm (Reissner)")


if __name__ == "__main__":
    main()
