"""Speed and memory of design sweeps on the default design. Run by hand:

    .venv/bin/python benchmarks/sweep.py [--points N] [--million] [--skip-axisymmetric]

Prints, each measured in a fresh process (the number of host devices is fixed when JAX
starts):
- a grid of N (default 10,000) Reissner-level default designs (dome outer radius x target
  compliance), on 1 and on 2 host devices (``--devices``), and (on Linux) on 1 device held
  to half the cores: first call (compile included), warm time, solves per second, the
  speed-up of 2 devices, and the peak memory. One XLA CPU device already spreads its
  larger operations over every core, so two devices, each with half of them, can at most
  double the rate of one device on half the cores: the benchmark prints that bound beside
  the speed-up;
- with ``--million``: 1,000,000 such points (chunked), their time and peak memory;
- unless skipped: a 200-point sweep of the target compliance at the axisymmetric level (on one
  device: its model's loops send the points one at a time to a thread per core, whatever
  the devices).
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

mm = 1e-3


def child(devices, points, fidelity, cores):
    """One measurement in this process, on its first ``cores`` CPUs if given: JSON on stdout."""
    if cores:
        os.sched_setaffinity(0, sorted(os.sched_getaffinity(0))[:cores])  # before JAX starts its threads
    import jax

    jax.config.update("jax_num_cpu_devices", devices)
    from magdesign.design import sweep
    from magdesign.spec.design import default_spec, problem_from_spec

    problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
    if fidelity == "axisymmetric":
        over = {"compliance": np.linspace(0.25, 0.4, points) * mm}
    else:
        side = int(round(np.sqrt(points)))
        over = {
            "mechanics.outer_radius": np.linspace(6.0, 10.0, side) * mm,
            "compliance": np.linspace(0.25, 0.4, points // side) * mm,
        }
    began = time.perf_counter()
    first = sweep(problem, over, progress=False)
    first_s = time.perf_counter() - began
    print(f"first call of {points} points on {jax.devices()}: {first_s:.1f} s", file=sys.stderr, flush=True)
    began = time.perf_counter()
    warm = sweep(problem, over, progress=False)
    warm_s = time.perf_counter() - began
    print(
        json.dumps(
            {
                "device": str(jax.devices()[0].device_kind),
                "points": int(warm.status.size),
                "first_s": first_s,
                "warm_s": warm_s,
                "successful": int(warm.successful.sum()),
                "agree": bool(np.array_equal(first.status, warm.status)),
                "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            }
        )
    )


def measure(devices, points, fidelity="reissner", cores=None):
    command = [sys.executable, __file__, "--child", str(devices), "--points", str(points), "--fidelity", fidelity]
    command += ["--cores", str(cores)] if cores else []
    run = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(run.stdout.strip().splitlines()[-1])


def table(rows):
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--points", type=int, default=10_000)
    parser.add_argument("--million", action="store_true")
    parser.add_argument("--skip-axisymmetric", action="store_true")
    parser.add_argument("--child", type=int)
    parser.add_argument("--fidelity", default="reissner")
    parser.add_argument("--cores", type=int)
    args = parser.parse_args()
    if args.child:
        return child(args.child, args.points, args.fidelity, args.cores)

    rows = [
        (
            "sweep",
            "devices",
            "cores",
            "points",
            "successful",
            "first call (s)",
            "warm (s)",
            "solves/s",
            "peak memory (MB)",
        )
    ]
    results = {}
    from magdesign.design.solve import usable_cores  # here: a child sets its cores before JAX loads

    all_cores = usable_cores()
    half = all_cores // 2 if hasattr(os, "sched_setaffinity") and all_cores >= 2 else None
    runs = [(1, args.points, "reissner", None), (2, args.points, "reissner", None)]
    runs += [(1, args.points, "reissner", half)] if half else []
    runs += [(2, 1_000_000, "reissner", None)] if args.million else []
    runs += [] if args.skip_axisymmetric else [(1, 200, "axisymmetric", None)]
    for devices, points, fidelity, cores in runs:
        print(
            f"measuring {points} points at {fidelity} on {devices} device(s), {cores or all_cores} core(s) ...",
            file=sys.stderr,
            flush=True,
        )
        r = results[devices, points, fidelity, cores] = measure(devices, points, fidelity, cores)
        rows.append(
            (
                f"default design, {fidelity}",
                devices,
                cores or all_cores,
                r["points"],
                r["successful"],
                f"{r['first_s']:.2f}",
                f"{r['warm_s']:.2f}",
                f"{r['points'] / r['warm_s']:.0f}",
                f"{r['peak_mb']:.0f}",
            )
        )
    table(rows)
    one, two = results[1, args.points, "reissner", None], results[2, args.points, "reissner", None]
    print(f"\n2 host devices against 1: {one['warm_s'] / two['warm_s']:.2f}x (warm)")
    if half:
        held = results[1, args.points, "reissner", half]
        print(
            f"one device on {all_cores} cores against {half}: {held['warm_s'] / one['warm_s']:.2f}x; "
            f"so 2 devices can gain at most {2 * one['warm_s'] / held['warm_s']:.2f}x over one"
        )


if __name__ == "__main__":
    main()
