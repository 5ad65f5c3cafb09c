"""Speed and memory of design sweeps on the default design. Run by hand:

    .venv/bin/python benchmarks/sweep.py [--points N] [--million] [--skip-axisymmetric]

Prints, each measured in a fresh process (the number of host devices is fixed when JAX
starts):
- a grid of N (default 10,000) Reissner-level default designs (dome outer radius x target
  compliance), on 1 and on 2 host devices (``--devices``): first call (compile included),
  warm time, solves per second, the speed-up of 2 devices, and the peak memory;
- with ``--million``: 1,000,000 such points (chunked), their time and peak memory;
- unless skipped: a 200-point sweep of the target compliance at the axisymmetric level.
"""

import argparse
import json
import resource
import subprocess
import sys
import time

import numpy as np

mm = 1e-3


def child(devices, points, fidelity):
    """One measurement in this process: JSON on stdout."""
    import jax

    jax.config.update("jax_num_cpu_devices", devices)
    from magdesign.design import sweep
    from magdesign.design.spec import default_spec, problem_from_spec

    problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
    if fidelity == "axisymmetric":
        over = {"compliance": np.linspace(0.25, 0.4, points) * mm}
    else:
        side = int(round(np.sqrt(points)))
        over = {"mechanics.outer_radius": np.linspace(6.0, 10.0, side) * mm,
                "compliance": np.linspace(0.25, 0.4, points // side) * mm}
    began = time.perf_counter()
    first = sweep(problem, over, progress=False)
    first_s = time.perf_counter() - began
    print(f"first call of {points} points on {jax.devices()}: {first_s:.1f} s", file=sys.stderr, flush=True)
    began = time.perf_counter()
    warm = sweep(problem, over, progress=False)
    warm_s = time.perf_counter() - began
    print(json.dumps({
        "device": str(jax.devices()[0].device_kind), "points": int(warm.status.size), "first_s": first_s, "warm_s": warm_s,
        "successful": int(warm.successful.sum()), "agree": bool(np.array_equal(first.status, warm.status)),
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }))


def measure(devices, points, fidelity="reissner"):
    command = [sys.executable, __file__, "--child", str(devices), "--points", str(points), "--fidelity", fidelity]
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
    args = parser.parse_args()
    if args.child:
        return child(args.child, args.points, args.fidelity)

    rows = [("sweep", "devices", "points", "successful", "first call (s)", "warm (s)", "solves/s", "peak memory (MB)")]
    results = {}
    runs = [(1, args.points, "reissner"), (2, args.points, "reissner")]
    runs += [(2, 1_000_000, "reissner")] if args.million else []
    runs += [] if args.skip_axisymmetric else [(2, 200, "axisymmetric")]
    for devices, points, fidelity in runs:
        print(f"measuring {points} points at {fidelity} on {devices} device(s) ...", file=sys.stderr, flush=True)
        r = results[devices, points, fidelity] = measure(devices, points, fidelity)
        rows.append((f"default design, {fidelity}", devices, r["points"], r["successful"], f"{r['first_s']:.2f}",
                     f"{r['warm_s']:.2f}", f"{r['points'] / r['warm_s']:.0f}", f"{r['peak_mb']:.0f}"))
    table(rows)
    one, two = results[1, args.points, "reissner"], results[2, args.points, "reissner"]
    print(f"\n2 host devices against 1: {one['warm_s'] / two['warm_s']:.2f}x (warm)")


if __name__ == "__main__":
    main()
