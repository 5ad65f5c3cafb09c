"""Hemispherical dome pressed at its apex by a rigid flat plate (PHYSICS.md 2.3, seed 001).

Fidelity levels of the secant compliance (apex displacement / force, m/N):

- ``"reissner"``: Reissner's thin-shell point-load stiffness
  K = 4 E t^2 / (R sqrt(3 (1 - nu^2))), R = outer_radius - t / 2 the mid-surface radius,
  E and nu the material's small-strain moduli. Linear, cost ~ microseconds; its thin-shell
  assumption costs accuracy for thick walls (0.371 mm/N for seed 001's dome, published FEM
  and experiment 0.32 mm/N).
- ``"axisymmetric"``: finite-strain axisymmetric finite elements of the thick wall
  (9-node quadrilaterals, Q9/P3 volumetric projection) with smoothed penalty contact of a
  frictionless plate; Newton's method on the total potential, first with the plate
  travel held, then with the force held; implicit (exact) derivatives
  (:mod:`magdesign.mechanics._axisymmetric`). Seed 001's dome at 5 N: 1.700 mm
  (0.340 mm/N) bonded, 2.244 mm sliding; meshes (1, 8), (2, 16), (4, 32), (8, 64) give
  1.714, 1.700, 1.704, 1.704 mm, so the default (2, 16) is within 0.25 % of the finest.
  Published (Abaqus hybrid tetrahedra, friction 0.8, and experiment): 1.6 mm. Cost:
  about 25 Newton iterations on ~330 unknowns, ~0.2 s warm on one core; compiling
  ~10 s (value) and ~15 s more for derivatives.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import DOME_MIN_FORCE_FRACTION, DOME_START_TOL, ZERO_LOAD_FRACTION
from magdesign._validation import check_nonnegative, check_positive
from magdesign.mechanics import _axisymmetric
from magdesign.mechanics.materials import AbstractMaterial

FIDELITIES = ("reissner", "axisymmetric")
BASES = ("bonded", "sliding")
# The axisymmetric solve first holds the plate at this fraction of Reissner's estimate of
# the travel at the first wanted force (Reissner overestimates thick domes by ~10 %), then
# holds the force; starting from the undeformed dome, one such step costs fewer Newton
# iterations than several small ones (measured on seed 001's dome).
START_TRAVEL_FRACTION = 0.9


def _check(outer_radius, thickness, material, max_force, fidelity, base, mesh):
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    if base not in BASES:
        raise ValueError(f"base must be one of {BASES}, got {base!r}")
    if not isinstance(material, AbstractMaterial):
        raise ValueError(f"material must be an AbstractMaterial, got {type(material).__name__}")
    if len(mesh) != 2 or any(int(n) != n or n < 1 for n in mesh):
        raise ValueError(f"mesh must be two positive integers (wall, meridian), got {mesh!r}")
    check_positive(outer_radius=outer_radius, thickness=thickness)
    check_nonnegative(max_force=max_force)
    if not _is_traced(outer_radius, thickness) and not thickness < outer_radius:
        raise ValueError(
            f"thickness must be smaller than outer_radius, got {thickness!r} >= {outer_radius!r}"
        )


def _is_traced(*values):
    return any(isinstance(v, jax.core.Tracer) for v in values)


def _reissner_compliance(outer_radius, thickness, material):
    E, nu = material.youngs_modulus, material.poisson_ratio
    R = outer_radius - thickness / 2
    return R * jnp.sqrt(3 * (1 - nu**2)) / (4 * E * thickness**2)


def _axisymmetric_travels(outer_radius, thickness, material, forces, base, mesh):
    """Plate travels (m) and converged flags at each of ``forces`` (n,) (N), increasing."""
    m = _axisymmetric.Mesh(int(mesh[0]), int(mesh[1]), base)
    params = (outer_radius, thickness, material)
    fixed = lax.stop_gradient(params)
    start = START_TRAVEL_FRACTION * _reissner_compliance(*fixed) * lax.stop_gradient(forces[0])
    start = jnp.minimum(start, fixed[0] / 2)
    states, converged = _axisymmetric.equilibria(m, params, forces, start, DOME_START_TOL)
    return states[:, -1], converged


def _effective_force(max_force, thickness, material, fidelity):
    # 0 / 0 at zero load: evaluate at a floor (see _numerics; the axisymmetric level has
    # its own, higher floor, DOME_MIN_FORCE_FRACTION mu t^2)
    fraction = ZERO_LOAD_FRACTION if fidelity == "reissner" else DOME_MIN_FORCE_FRACTION
    floor = fraction * material.shear_modulus * thickness**2
    return jnp.maximum(jnp.asarray(max_force, dtype=float), floor)


def dome_compliance(
    *,
    outer_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractMaterial,
    max_force: Float[ArrayLike, ""],
    fidelity: str = "axisymmetric",
    base: str = "bonded",
    mesh: tuple[int, int] = (2, 16),
) -> Float[Array, ""]:
    """Secant compliance (m/N) of a hemispherical dome: apex displacement at ``max_force``
    divided by ``max_force``.

    Args:
        outer_radius: outer radius R_o of the hemisphere (m), > 0.
        thickness: wall thickness t (m), 0 < t < R_o.
        material: the wall's material.
        max_force: plate force (N), >= 0. Reissner: at 0 the zero-load limit is returned.
            Axisymmetric: forces below DOME_MIN_FORCE_FRACTION mu t^2 (0.024 N for seed
            001's dome) are evaluated at that floor (see magdesign._numerics).
        fidelity: "reissner" (closed form, linear) or "axisymmetric" (nonlinear FE).
        base: "bonded" (rim clamped, seed 001) or "sliding" (rim free to slide radially).
        mesh: (elements through the wall, elements along the meridian), axisymmetric only.

    Raises ValueError naming the argument for a bad configuration or value.
    """
    _check(outer_radius, thickness, material, max_force, fidelity, base, mesh)
    if fidelity == "reissner":
        return _reissner_compliance(outer_radius, thickness, material)
    force = _effective_force(max_force, thickness, material, fidelity)
    travels, _ = _axisymmetric_travels(outer_radius, thickness, material, force[None], base, mesh)
    return travels[0] / force


def dome_curve(
    *,
    outer_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractMaterial,
    max_force: Float[ArrayLike, ""],
    fidelity: str = "axisymmetric",
    base: str = "bonded",
    mesh: tuple[int, int] = (2, 16),
    n_points: int = 10,
) -> tuple[Float[Array, " n_points"], Float[Array, " n_points"]]:
    """(apex displacements (m), forces (N)) at forces max_force k / n_points, k = 1..n.

    Arguments as :func:`dome_compliance`. The Reissner level is a straight line.
    """
    _check(outer_radius, thickness, material, max_force, fidelity, base, mesh)
    if int(n_points) != n_points or n_points < 1:
        raise ValueError(f"n_points must be a positive integer, got {n_points!r}")
    force = _effective_force(max_force, thickness, material, fidelity)
    forces = force * np.arange(1, n_points + 1) / n_points
    if fidelity == "reissner":
        return _reissner_compliance(outer_radius, thickness, material) * forces, forces
    travels, _ = _axisymmetric_travels(outer_radius, thickness, material, forces, base, mesh)
    return travels, forces
