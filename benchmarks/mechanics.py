"""Dome models: accuracy against a refined mesh, and what each call costs (run by hand:
``taskset -c 0 python benchmarks/mechanics.py``; pinning to one core steadies the timings).

Prints
1. mesh convergence of the axisymmetric level: the dome-Hall sensor's dome (R_o 8 mm, t 2 mm, 5 N)
   and a thin dome (R_o 8 mm, t 0.4 mm, t/R 0.05, travel t/10) against the refined mesh
   REFERENCE_MESH, with the best warm time of one jitted call per mesh;
2. the cost of calls: Reissner and the axisymmetric 5 N path (jitted, warm), its gradient
   with respect to outer radius, thickness, c10 and c01, and a second plain-Python call
   with a new thickness (which reuses the compiled program);
3. the default design (examples/dome_hall.toml) at each dome level: first call (compile
   included) and warm solve;
4. one factor and solve of the Newton tangent: the block tridiagonal factor
   (magdesign.mechanics._blocks) against a dense Cholesky of the same matrix, per mesh;
5. a skin layer's displacement and rotation on its cells (layer_displacement_grid), one
   load on a 20 x 20 x 2 mm layer, and its Jacobian along the load (x, y, Fn, Fx, Fy).
Timings are the best of REPEATS (first calls and the reference mesh: one each).
"""

import time

import jax
import jax.numpy as jnp
import jax.scipy.linalg as jsl
import numpy as np
from jax import lax

import magdesign  # noqa: F401  (float64)
from magdesign.design import solve
from magdesign.mechanics import MooneyRivlin, _axisymmetric, _blocks, dome_compliance, dome_curve
from magdesign.mechanics.dome import DEFAULT_MESH
from magdesign.mechanics.skin_layer import ElasticLayer, SurfaceLoad, layer_displacement_grid, spectral_grid
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.units import mm

REPEATS = 5
RESIN = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)
MESHES = ((1, 12), (2, 12), (2, 16), (3, 24), (4, 32))
REFERENCE_MESH = (6, 48)


def _first_and_best(fn, *args, repeats=REPEATS):
    """(first call (s), best of ``repeats`` further calls (s), result)."""
    start = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    first = time.perf_counter() - start
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        out = jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - start)
    return first, best, out


def dome_hall_compliance(mesh):
    """Jitted dome-Hall compliance at 5 N (m/N) as a function of the wall thickness (m)."""
    return jax.jit(
        lambda t: dome_compliance(outer_radius=8 * mm, thickness=t, material=RESIN, max_force=5.0, mesh=mesh)
    )


def thin_force(mesh):
    """Jitted plate force (N) of the 8 / 0.4 mm dome at travel t/10, from its wall (m)."""
    return jax.jit(
        lambda t: dome_curve(outer_radius=8 * mm, thickness=t, material=RESIN, travels=(t / 10)[None], mesh=mesh).force[
            0
        ]
    )


def mesh_convergence():
    print(
        "1. mesh convergence of the axisymmetric dome (error against the refined mesh "
        f"{REFERENCE_MESH[0]}x{REFERENCE_MESH[1]}; default mesh {DEFAULT_MESH[0]}x{DEFAULT_MESH[1]})"
    )
    cases = (
        ("dome-Hall, 8/2 mm, 5 N compliance", dome_hall_compliance, 2 * mm, 1e3, "mm/N"),
        ("thin, 8/0.4 mm, force at t/10", thin_force, 0.4 * mm, 1e3, "mN"),
    )
    print(f"   {'case':<36}{'mesh':>7}{'value':>14}{'error':>11}{'warm (s)':>11}")
    for name, build, thickness, scale, unit in cases:
        t = jnp.asarray(thickness)
        _, reference_seconds, reference = _first_and_best(build(REFERENCE_MESH), t, repeats=1)
        reference = float(reference)
        for mesh in MESHES + (REFERENCE_MESH,):
            _, warm, value = (
                (None, reference_seconds, reference) if mesh == REFERENCE_MESH else _first_and_best(build(mesh), t)
            )
            error = float(value) / reference - 1.0
            print(
                f"   {name:<36}{mesh[0]}x{mesh[1]:<5}{float(value) * scale:>9.5f} {unit:<4}{error:>+11.2e}{warm:>11.3g}"
            )


def call_costs():
    print("\n2. cost of one call (dome-Hall dome, 5 N, default mesh)")
    args = tuple(jnp.asarray(a) for a in (8 * mm, 2 * mm, RESIN.c10, RESIN.c01))

    def compliance(Ro, t, c10, c01, fidelity):
        return dome_compliance(
            outer_radius=Ro, thickness=t, material=MooneyRivlin(c10=c10, c01=c01), max_force=5.0, fidelity=fidelity
        )

    print(f"   {'call':<44}{'first (s)':>12}{'warm (s)':>12}")
    for fidelity in ("reissner", "axisymmetric"):
        value = jax.jit(lambda *a, f=fidelity: compliance(*a, f))
        grad = jax.jit(jax.grad(lambda *a, f=fidelity: compliance(*a, f), argnums=(0, 1, 2, 3)))
        first, warm, _ = _first_and_best(value, *args)
        print(f"   {fidelity + ' 5 N path, jitted':<44}{first:>12.3g}{warm:>12.3g}")
        first, warm, _ = _first_and_best(grad, *args)
        print(f"   {fidelity + ' 5 N path, gradient (4 parameters)':<44}{first:>12.3g}{warm:>12.3g}")

    def plain(thickness):
        return dome_compliance(outer_radius=8 * mm, thickness=thickness, material=RESIN, max_force=5.0)

    first, _, _ = _first_and_best(plain, 2 * mm)
    start = time.perf_counter()
    jax.block_until_ready(plain(2.1 * mm))
    again = time.perf_counter() - start
    print(f"   {'axisymmetric 5 N, plain call, new thickness':<44}{first:>12.3g}{again:>12.3g}")


def default_design():
    print("\n3. the default design (examples/dome_hall.toml)")
    print(f"   {'dome level':<16}{'first (s)':>12}{'warm (s)':>12}{'steps':>7}  status")
    for fidelity in ("reissner", "axisymmetric"):
        problem, _ = problem_from_spec(default_spec(), fidelity=fidelity)
        start = time.perf_counter()
        solve(problem)
        first = time.perf_counter() - start
        warm = float("inf")
        for _ in range(3):
            start = time.perf_counter()
            result = solve(problem)
            warm = min(warm, time.perf_counter() - start)
        print(f"   {fidelity:<16}{first:>12.3g}{warm:>12.3g}{result.steps:>7}  {result.status}")


def factor_costs(loops=50):
    print("\n4. one factor and solve of the tangent (dome-Hall dome, plate 0.2 mm in, force held)")
    print(f"   {'mesh':<8}{'unknowns':>10}{'dense (ms)':>12}{'blocks (ms)':>13}{'difference':>12}")
    params = (jnp.asarray(8 * mm), jnp.asarray(2 * mm), RESIN)
    for shape in ((1, 12), DEFAULT_MESH, (4, 32)):
        mesh = _axisymmetric.Mesh(*shape, "bonded")
        _, H = _axisymmetric.derivatives(mesh, jnp.zeros(mesh.size).at[-1].set(0.2 * mm), params)
        M = H.restricted(mesh.layout, jnp.asarray(mesh.mask(True))).dense(mesh.layout)
        rhs = jnp.asarray(np.random.default_rng(0).standard_normal(mesh.size))
        solvers = {
            "dense": lambda A, r: jsl.cho_solve((jnp.linalg.cholesky(A), True), r),
            "blocks": lambda A, r, m=mesh: _blocks.solve(m.layout, _blocks.factor(m.layout, A), r),
        }
        seconds, answers = {}, {}
        for name, one in solvers.items():
            # a loop of solves whose matrix and right side change, so none is hoisted
            looped = jax.jit(
                lambda A, r, one=one: lax.fori_loop(
                    0, loops, lambda i, x: one(A + 1e-12 * i * jnp.eye(A.shape[0]), r + 1e-12 * x), r
                )
            )
            _, best, _ = _first_and_best(looped, M, rhs)
            seconds[name] = best / loops
            answers[name] = one(M, rhs)
        difference = float(jnp.max(jnp.abs(answers["blocks"] - answers["dense"])) / jnp.max(jnp.abs(answers["dense"])))
        print(
            f"   {shape[0]}x{shape[1]:<6}{mesh.size:>10}{seconds['dense'] * 1e3:>12.3f}"
            f"{seconds['blocks'] * 1e3:>13.3f}{difference:>12.1e}"
        )


def skin_grid_costs():
    print("\n5. a skin layer on its cells, one Hertz load (20 x 20 x 2 mm, mu 20 kPa, nu 0.49)")
    print(f"   {'cells':<12}{'first (s)':>11}{'warm (s)':>10}{'jacobian first':>16}{'warm (s)':>10}")
    size = jnp.array([20 * mm, 20 * mm])
    for cells in ((16, 16, 8), (32, 32, 16)):
        grid = spectral_grid(size=size, thickness=2 * mm, cells=cells)

        def fields(state, layer_values, cells=cells, grid=grid):
            layer = ElasticLayer(*layer_values)
            load = SurfaceLoad(centre=state[:2], radius=1.7 * mm, normal_force=state[2], shear_force=state[3:])
            return layer_displacement_grid(layer=layer, load=load, size=size, cells=cells, grid=grid)

        state, layer_values = jnp.array([1 * mm, -2 * mm, 0.3, 0.1, 0.05]), jnp.array([2 * mm, 20e3, 0.49])
        first, warm, _ = _first_and_best(jax.jit(fields), state, layer_values)
        jac_first, jac_warm, _ = _first_and_best(jax.jit(jax.jacfwd(fields)), state, layer_values)
        print(f"   {str(cells):<12}{first:>11.3g}{warm:>10.3g}{jac_first:>16.3g}{jac_warm:>10.3g}")


if __name__ == "__main__":
    mesh_convergence()
    call_costs()
    default_design()
    factor_costs()
    skin_grid_costs()
