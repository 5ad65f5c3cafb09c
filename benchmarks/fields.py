"""Throughput of magdesign.fields.cylinder against magpylib's Cylinder.getB.

Run by hand: .venv/bin/python benchmarks/fields.py
Prints points per second (float64, jitted, warm; best of a few repeats) for both on the
same random points, their ratio, the first-call (trace + compile) time, and the largest
relative difference between the two (a sanity check, not an accuracy measurement).
"""

import time

import jax
import magpylib
import numpy as np

from magdesign.fields import cylinder

RADIUS, HEIGHT, POLARIZATION = 1.5e-3, 1e-3, 1.17
SIZES = (10**3, 10**4, 10**5, 10**6)


def _best_time(fn, repeats):
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main():
    rng = np.random.default_rng(0)
    field = jax.jit(lambda p: cylinder(p, radius=RADIUS, height=HEIGHT, polarization=POLARIZATION))
    magnet = magpylib.magnet.Cylinder(polarization=(0, 0, POLARIZATION), dimension=(2 * RADIUS, HEIGHT))

    start = time.perf_counter()
    field(np.zeros((SIZES[0], 3))).block_until_ready()
    print(f"first call (trace + compile + run, {SIZES[0]} points): {time.perf_counter() - start:.2f} s\n")

    print(f"{'points':>9} {'magdesign pts/s':>16} {'magpylib pts/s':>15} {'ratio':>6} {'max rel diff':>13}")
    for n in SIZES:
        points = rng.uniform(-10 * RADIUS, 10 * RADIUS, size=(n, 3))
        device_points = jax.device_put(points)
        field(device_points).block_until_ready()
        repeats = 5 if n <= 10**5 else 3
        ours = _best_time(lambda: field(device_points).block_until_ready(), repeats)
        theirs = _best_time(lambda: magnet.getB(points), repeats)
        ours_b, theirs_b = np.asarray(field(device_points)), magnet.getB(points)
        diff = np.max(np.linalg.norm(ours_b - theirs_b, axis=-1) / np.linalg.norm(theirs_b, axis=-1))
        print(f"{n:>9} {n / ours:>16.3g} {n / theirs:>15.3g} {theirs / ours:>6.2f} {diff:>13.1e}")


if __name__ == "__main__":
    main()
