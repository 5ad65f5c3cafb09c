"""Throughput of magdesign.fields.cylinder against magpylib's Cylinder.getB, in one run.

Run by hand: .venv/bin/python benchmarks/fields.py   (taskset -c 1 ... for one core)

Prints, for the dome-Hall sensor's magnet (3 x 1 mm) and random points in a box of +-10 radii:
- the first call (trace + compile + run of a fresh jitted function, 1000 points), axial
  and with a diametral part; target <= 1 s;
- points per second (float64, jitted, warm; best of 7-9 interleaved repeats) of magdesign
  and of magpylib on the same points, their ratio (target >= 10 at 1e5 and 1e6 points), and the
  largest relative difference between the two (a sanity check: the accuracy against
  40-digit references is in tests/fields/test_cylinder.py);
- the cost of the Jacobian with respect to the points, jax.vmap(jax.jacfwd(field)),
  over the cost of the field (target <= 3).
"""

import time

import jax
import jax.numpy as jnp
import magpylib
import numpy as np

from magdesign.fields import cylinder

RADIUS, HEIGHT = 1.5e-3, 1e-3
POLARIZATIONS = {"axial": np.array([0.0, 0.0, 1.17]), "diametral": np.array([0.6, -0.3, 1.0])}
SIZES = (10**3, 10**4, 10**5, 10**6)
JACOBIAN_SIZES = (10**5, 10**6)


def _best_times(fns, repeats):
    """The best time of each function, their runs interleaved (a burst of load on this
    noisy shared machine then slows both sides alike, not one)."""
    best = [float("inf")] * len(fns)
    for _ in range(repeats):
        for i, fn in enumerate(fns):
            start = time.perf_counter()
            fn()
            best[i] = min(best[i], time.perf_counter() - start)
    return best


def _field(polarization):
    """The field as a function of the points (m), polarization a scalar when axial."""
    j = float(polarization[2]) if not np.any(polarization[:2]) else jnp.asarray(polarization)
    return lambda points: cylinder(points, radius=RADIUS, height=HEIGHT, polarization=j)


def main():
    rng = np.random.default_rng(0)
    print(f"jax {jax.__version__} on {jax.devices()[0].device_kind}, magpylib {magpylib.__version__}")
    print("first call (trace + compile + run, 1000 points; target <= 1 s):")
    for name, polarization in POLARIZATIONS.items():
        field = jax.jit(_field(polarization))
        start = time.perf_counter()
        field(rng.uniform(-RADIUS, RADIUS, size=(SIZES[0], 3))).block_until_ready()
        print(f"  {name:>9}: {time.perf_counter() - start:.2f} s")

    print("\nfield, points per second (target: ratio >= 10 at 1e5 and 1e6 points):")
    print(f"{'':>9} {'points':>9} {'magdesign':>11} {'magpylib':>10} {'ratio':>6} {'max rel diff':>13}")
    for name, polarization in POLARIZATIONS.items():
        field = jax.jit(_field(polarization))
        magnet = magpylib.magnet.Cylinder(polarization=polarization, dimension=(2 * RADIUS, HEIGHT))
        for n in SIZES:
            points = rng.uniform(-10 * RADIUS, 10 * RADIUS, size=(n, 3))
            device_points = jax.device_put(points)
            field(device_points).block_until_ready()
            repeats = 9 if n <= 10**5 else 7
            ours, theirs = _best_times(
                [lambda: field(device_points).block_until_ready(), lambda: magnet.getB(points)], repeats
            )
            ours_b, theirs_b = np.asarray(field(device_points)), magnet.getB(points)
            diff = np.max(np.linalg.norm(ours_b - theirs_b, axis=-1) / np.linalg.norm(theirs_b, axis=-1))
            print(f"{name:>9} {n:>9} {n / ours:>11.3g} {n / theirs:>10.3g} {theirs / ours:>6.2f} {diff:>13.1e}")

    print("\nJacobian with respect to the points, vmap(jacfwd(field)), cost / field cost (target <= 3):")
    for name, polarization in POLARIZATIONS.items():
        field = jax.jit(_field(polarization))
        jacobian = jax.jit(jax.vmap(jax.jacfwd(_field(polarization))))
        for n in JACOBIAN_SIZES:
            points = jax.device_put(rng.uniform(-10 * RADIUS, 10 * RADIUS, size=(n, 3)))
            field(points).block_until_ready()
            jacobian(points).block_until_ready()
            repeats = 9 if n <= 10**5 else 7
            value, derivative = _best_times(
                [lambda: field(points).block_until_ready(), lambda: jacobian(points).block_until_ready()], repeats
            )
            print(
                f"{name:>9} {n:>9}: field {value * 1e3:7.1f} ms, jacobian {derivative * 1e3:7.1f} ms, ratio {derivative / value:.2f}"
            )


if __name__ == "__main__":
    main()
