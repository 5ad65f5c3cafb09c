"""Warm timings of the dome models (run by hand: python benchmarks/mechanics.py).

Prints, per fidelity, the compile time (first call) and the best warm time of a 5 N
load path of seed 001's dome (one value) and of its gradient with respect to outer
radius, thickness, c10 and c01. The best of several repeats is reported: on a shared
machine XLA's worker threads wait for cores, and single timings scatter by 10x or more
(pinning the process, ``taskset -c 0 python benchmarks/mechanics.py``, steadies them).
"""

import time

import jax

import magdesign  # noqa: F401  (float64)
from magdesign.mechanics import MooneyRivlin, dome_compliance


def _times(fn, *args, repeats=5):
    """(compile + first call (s), best warm call (s), result)."""
    start = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - start
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        out = jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - start)
    return first, best, out


def main():
    def compliance(Ro, t, c10, c01, fidelity):
        return dome_compliance(outer_radius=Ro, thickness=t,
                               material=MooneyRivlin(c10=c10, c01=c01), max_force=5.0,
                               fidelity=fidelity)

    args = (8e-3, 2e-3, 0.1182e6, 0.1769e6)
    print(f"{'model':<28}{'compile (s)':>14}{'warm (s)':>12}{'value':>20}")
    for fidelity in ("reissner", "axisymmetric"):
        value = jax.jit(lambda *a, f=fidelity: compliance(*a, f))
        grad = jax.jit(jax.grad(lambda *a, f=fidelity: compliance(*a, f), argnums=(0, 1, 2, 3)))
        first, warm, c = _times(value, *args)
        print(f"{fidelity + ' 5 N':<28}{first:>14.3g}{warm:>12.3g}{float(c) * 1e3:>15.4f} mm/N")
        first, warm, _ = _times(grad, *args)
        print(f"{fidelity + ' 5 N gradient':<28}{first:>14.3g}{warm:>12.3g}")


if __name__ == "__main__":
    main()
