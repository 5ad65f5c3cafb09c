"""Hemispherical dome pressed at its apex by a rigid flat plate (the dome of the dome-Hall
sensor, "Design and Fabrication of a Soft Magnetic Tactile Sensor").

Fidelity levels:

- ``"reissner"``: Reissner's thin-shell point-load stiffness (E. Reissner, "Stresses and
  small displacements of shallow spherical shells", J. Math. Phys. 25 (1946-1947)):
  K = 4 E t^2 / (R sqrt(3 (1 - nu^2))), R = outer_radius - t / 2 the mid-surface radius,
  E and nu the material's small-strain moduli. Linear, cost ~ microseconds. It leaves out
  what makes a thick wall softer (transverse shear, the wall's compression under the plate;
  the most at light loads) and what makes it stiffer at travels of the order of t (the
  plate's contact spreading over the apex). The dome-Hall sensor's dome (8 mm / 2 mm) at
  5 N has travelled 0.8 t, and the stiffening wins: Reissner gives 0.371 mm/N against the
  published FEM and experiment's 0.32 mm/N (the axisymmetric level's secant compliance is
  1.6 times Reissner's at a travel of 0.2 mm and 0.94 times at 1.6 mm, where the contact
  reaches a radius of 3.2 mm).
- ``"axisymmetric"``: finite-strain axisymmetric finite elements of the thick wall
  (9-node quadrilaterals, Q9/P3 volumetric projection, graded towards the apex) with
  penalty contact of a frictionless plate (:mod:`magdesign.mechanics._axisymmetric`). The
  force-travel path is followed with the plate travel held, from the undeformed dome, so
  it passes the points where a thin dome softens and its force falls; a force is found at
  its first crossing on that path and solved there with the force held. Derivatives are
  exact (implicit). The dome-Hall sensor's dome at 5 N: see ``benchmarks/mechanics.py`` for the
  travel, its mesh convergence and its cost.

For thin walls the axisymmetric compliance tends to Reissner's (tested), but slowly: its
excess at a travel of t / 100 is about 8 t / R (transverse shear and the wall's local
compression under the plate; more at lighter loads), and it falls as the travel grows and
the plate's contact spreads (at a travel of t: +10 % for t / R = 0.1, -15 % for 0.25,
R the outer radius).
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax
from jaxtyping import Array, ArrayLike, Float

from magdesign._validation import _concrete, check_nonnegative, check_positive
from magdesign.mechanics import _axisymmetric, _ladder
from magdesign.mechanics.materials import AbstractHyperelastic, AbstractMaterial

# Smallest plate travel of the axisymmetric dome, as a fraction of the wall thickness:
# a force whose Reissner travel is below it is evaluated at the force whose Reissner
# travel equals it. Smaller travels press the plate into the dome by amounts comparable
# with the contact smoothing (CONTACT_SMOOTHING t), which then sets the answer; the secant
# compliance of a frictionless contact has no finite zero-load limit anyway (the wall's
# Hertz-like indentation, d ~ F^(2/3)).
DOME_MIN_TRAVEL_FRACTION = 1e-3


FIDELITIES = ("reissner", "axisymmetric")
BASES = ("bonded", "sliding")
# The axisymmetric level's meshes (elements through the wall, elements along the meridian)
# whose values carry an error estimate, coarsest first; the default is the lowest.
MESH_LADDER = _ladder.LADDER
DEFAULT_MESH = MESH_LADDER[0]
# The first travel step of a followed path, as a fraction of Reissner's estimate of the
# travel at the largest wanted force (the path doubles it while Newton converges easily).
FIRST_STEP_FRACTION = 0.5


class DomeResult(eqx.Enumeration):
    """Outcome of an axisymmetric dome solve."""

    successful = "converged"
    not_converged = (
        "the axisymmetric dome did not converge: Newton left an out-of-balance force above "
        "its tolerance (DOME_RESIDUAL_TOL mu t^2)"
    )
    force_not_reached = (
        "the dome does not carry this force: its followed force-travel path reached a plate "
        "travel of outer_radius - thickness (the wall pressed flat) first"
    )
    snapped = (
        "the dome's force-travel path could not be followed past a snap: with the plate travel "
        "held the equilibrium ceased to exist (as where a thin dome's apex inverts) and the jump "
        "to the equilibrium beyond did not converge"
    )
    max_steps_reached = "the dome's force-travel path needed more steps than PATH_MAX_STEPS"
    tolerance_not_met = (
        "the dome's estimated mesh error stayed above rtol |value| up to the finest level of the "
        "mesh ladder (LADDER): the value and its estimate are that level's"
    )


class DomeCurve(eqx.Module):
    """A force-travel path of the dome under plate-travel control, (n,) arrays.

    Attributes:
        travel: plate travel from first touch (m).
        force: plate force (N), the reaction of the dome; differentiable.
        contact_radius: radius (m) out to which the wall touches the plate (0 for
            "reissner", a point load); not differentiable.
        error: estimated absolute error (N) of each force from the mesh, >= 0, not
            differentiated (see :func:`dome_curve`); +inf where nothing is known: for
            "reissner" (its error is the model's, not a mesh's, see the module docstring), a
            mesh off the ladder, or a point whose companion level did not succeed.
        result: :class:`DomeResult` of each point.
        mesh: the axisymmetric mesh used (elements through the wall, along the meridian);
            None for "reissner".
    """

    travel: Float[Array, " n"]
    force: Float[Array, " n"]
    contact_radius: Float[Array, " n"]
    error: Float[Array, " n"]
    result: DomeResult
    mesh: tuple[int, int] | None = eqx.field(static=True)


class ComplianceEstimate(eqx.Module):
    """A dome compliance with its estimated mesh error (:func:`dome_compliance` with
    ``estimate=True``); arrays of the shape of ``max_force``.

    Attributes:
        value: secant compliance (m/N); differentiable.
        error: estimated absolute error of ``value`` (m/N), >= 0, not differentiated
            (stop_gradient); +inf where nothing is known (as :attr:`DomeCurve.error`).
        result: :class:`DomeResult` of each compliance.
        mesh: the axisymmetric mesh used; None for "reissner".
    """

    value: Float[Array, "*k"]
    error: Float[Array, "*k"]
    result: DomeResult
    mesh: tuple[int, int] | None = eqx.field(static=True)


def _check(outer_radius, thickness, material, fidelity, base, mesh, rtol):
    if mesh is not None and rtol is not None:
        raise ValueError("give at most one of mesh and rtol: rtol chooses the mesh from the ladder")
    if rtol is not None:
        if not (np.ndim(rtol) == 0 and _concrete(rtol) is not None and 0 < float(rtol) < 1):
            raise ValueError(f"rtol must be a number between 0 and 1, got {rtol!r}")
        if fidelity != "axisymmetric":
            raise ValueError("rtol chooses an axisymmetric mesh: use it with fidelity='axisymmetric'")
    mesh = DEFAULT_MESH if mesh is None else mesh
    if fidelity not in FIDELITIES:
        raise ValueError(f"fidelity must be one of {FIDELITIES}, got {fidelity!r}")
    if base not in BASES:
        raise ValueError(f"base must be one of {BASES}, got {base!r}")
    if not isinstance(material, AbstractMaterial):
        raise ValueError(f"material must be an AbstractMaterial, got {type(material).__name__}")
    if fidelity == "axisymmetric" and not isinstance(material, AbstractHyperelastic):
        raise ValueError(
            f"material: the axisymmetric level needs a finite-strain law (NeoHookean or "
            f"MooneyRivlin); {type(material).__name__} is a small-strain law, wrong under the "
            f"rotations of a pressed dome (use it with fidelity='reissner')"
        )
    if len(mesh) != 2 or any(int(n) != n or n < 1 for n in mesh):
        raise ValueError(f"mesh must be two positive integers (wall, meridian), got {mesh!r}")
    check_positive(outer_radius=outer_radius, thickness=thickness, unit="m")
    if fidelity == "axisymmetric":
        for name, value in (("outer_radius", outer_radius), ("thickness", thickness)):
            if jnp.ndim(value) != 0:
                raise ValueError(
                    f"{name} must be a scalar (m) at the axisymmetric level (one dome per call: "
                    f"jax.vmap for several), got shape {jnp.shape(value)}"
                )
    Ro, t = _concrete(outer_radius), _concrete(thickness)
    if Ro is not None and t is not None and not np.all(t < Ro):
        raise ValueError(f"thickness must be smaller than outer_radius, got {thickness!r} >= {outer_radius!r}")


def _reissner_compliance(outer_radius, thickness, material):
    E, nu = material.youngs_modulus, material.poisson_ratio
    R = outer_radius - thickness / 2
    return R * jnp.sqrt(3 * (1 - nu**2)) / (4 * E * thickness**2)


@functools.lru_cache(maxsize=32)
def _mesh(mesh, base):
    return _axisymmetric.Mesh(int(mesh[0]), int(mesh[1]), base)


def _as_arrays(tree):
    """Python numbers as float64 arrays, so that compiled programs are reused across values."""
    return jax.tree.map(lambda x: jnp.asarray(x, dtype=float), tree)


@eqx.filter_jit
def _axisymmetric_travels(outer_radius, thickness, material, forces, base, mesh):
    """Plate travels (k,) (m) and results (k,) at each of ``forces`` (k,) (N, > 0), every
    one found on the same followed path."""
    m = _mesh(mesh, base)
    params = (outer_radius, thickness, material)
    fixed = lax.stop_gradient(params)
    top = lax.stop_gradient(jnp.max(forces))
    max_travel = fixed[0] - fixed[1]
    step = jnp.minimum(FIRST_STEP_FRACTION * _reissner_compliance(*fixed) * top, max_travel / 4)
    c = _axisymmetric.first_crossings(m, fixed, lax.stop_gradient(forces), max_travel, step)
    # where the path never carried a force, its last state is returned, at its own force
    states = _axisymmetric.implicit(m, "force", params, jnp.where(c.found, forces, c.forces), c.states)
    path_result = DomeResult.where(
        c.failed,
        DomeResult.snapped,
        DomeResult.where(c.at_end, DomeResult.force_not_reached, DomeResult.max_steps_reached),
    )

    def level_result(found, converged):
        solved = DomeResult.where(converged, DomeResult.successful, DomeResult.not_converged)
        return DomeResult.where(found, solved, path_result)

    return states[:, -1], jax.vmap(level_result)(c.found, c.converged)


@eqx.filter_jit
def _axisymmetric_curve(outer_radius, thickness, material, travels, base, mesh):
    """(forces (n,) (N), contact radii (n,) (m), results (n,)) at ``travels`` (n,) (m)."""
    m = _mesh(mesh, base)
    params = (outer_radius, thickness, material)
    fixed = lax.stop_gradient(params)
    goals = lax.stop_gradient(travels)
    solved, reached, failed = _axisymmetric.follow_travels(m, fixed, goals, goals[0])
    states = _axisymmetric.implicit(m, "travel", params, travels, solved)
    forces = jax.vmap(lambda y: _axisymmetric.plate_force(m, y, params))(states)
    radii = jax.vmap(lambda y: _axisymmetric.contact_radius(m, y, fixed))(solved)

    def point_result(reached, failed):
        not_reached = DomeResult.where(failed, DomeResult.snapped, DomeResult.max_steps_reached)
        return DomeResult.where(reached, DomeResult.successful, not_reached)

    result = jax.vmap(point_result)(reached, failed)
    return forces, radii, result


def _force_floor(outer_radius, thickness, material):
    """Smallest force (N) the axisymmetric level solves for: DOME_MIN_TRAVEL_FRACTION t of
    Reissner's travel (see DOME_MIN_TRAVEL_FRACTION)."""
    return DOME_MIN_TRAVEL_FRACTION * thickness / _reissner_compliance(outer_radius, thickness, material)


def _travels(outer_radius, thickness, material, forces, base, mesh):
    """(travels (m), results) at ``forces`` (N, any shape), forces below the floor raised to it."""
    forces = jnp.asarray(forces, dtype=float)
    floor = lax.stop_gradient(_force_floor(outer_radius, thickness, material))
    effective = jnp.maximum(forces, floor)
    travels, result = _axisymmetric_travels(
        *_as_arrays((outer_radius, thickness, material)), effective.ravel(), base, tuple(mesh)
    )
    result = jax.tree.map(lambda value: value.reshape(forces.shape), result)
    return travels.reshape(forces.shape), result, effective


def _successful(shape):
    """A :class:`DomeResult` array of ``shape``, all successful."""
    return jax.tree.map(lambda value: jnp.broadcast_to(value, shape), DomeResult.successful)


def _raise_unless_successful(value, result, throw):
    if not throw:
        return value, result
    return result.error_if(value, result != DomeResult.successful)


def _climb(evaluate, rtol):
    """``evaluate(k)`` -> (value, error, result, ...) at ladder level k, from level 1 up: the
    first whose every element succeeded with error <= rtol |value|, else the finest, with
    tolerance_not_met where a solved element missed rtol. Returns (level, that tuple)."""
    for level in range(1, len(_ladder.LADDER)):
        value, error, result, *rest = evaluate(level)
        if _concrete(value) is None:
            raise ValueError(
                "rtol compares concrete values between mesh levels: call outside jax.jit and "
                "jax.grad, or pass the mesh it chose (mesh=ComplianceEstimate.mesh)"
            )
        solved = np.asarray(result == DomeResult.successful)
        met = np.asarray(_ladder.met(value, error, rtol))
        if np.all(solved & met):
            return level, (value, error, result, *rest)
    result = DomeResult.where(solved & ~met, DomeResult.tolerance_not_met, result)
    return level, (value, error, result, *rest)


def _compliance_estimate(params, max_force, base, mesh, rtol):
    """(level's mesh, compliance (m/N), its estimated error (m/N), result) at ``mesh`` or,
    with ``rtol``, at the level of the ladder that meets it."""
    solves = {}

    def solve(mesh):  # each level solved once per call
        if mesh not in solves:
            travels, result, forces = _travels(*params, max_force, base, mesh)
            solves[mesh] = (travels / forces, result)
        return solves[mesh]

    def evaluate(level):
        value, result = solve(_ladder.LADDER[level])
        other, other_result = solve(_ladder.LADDER[_ladder.companion(level)])
        return value, _ladder.estimate(value, other, level, other_result == DomeResult.successful), result

    if rtol is not None:
        level, (value, error, result) = _climb(evaluate, rtol)
        return _ladder.LADDER[level], value, error, result
    level = _ladder.level_of(mesh)
    if level is None:
        value, result = solve(mesh)
        return mesh, value, jnp.full_like(value, jnp.inf), result
    return (mesh, *evaluate(level))


def dome_compliance(
    *,
    outer_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractMaterial,
    max_force: Float[ArrayLike, "*k"],
    fidelity: str = "axisymmetric",
    base: str = "bonded",
    mesh: tuple[int, int] | None = None,
    rtol: float | None = None,
    estimate: bool = False,
    throw: bool = True,
) -> Float[Array, "*k"] | tuple[Float[Array, "*k"], DomeResult] | ComplianceEstimate:
    """Secant compliance (m/N) of a hemispherical dome: the plate travel at the first
    crossing of ``max_force`` on the force-travel path, divided by ``max_force``.

    Args:
        outer_radius: outer radius R_o of the hemisphere (m), > 0.
        thickness: wall thickness t (m), 0 < t < R_o.
        material: the wall's material (axisymmetric: NeoHookean or MooneyRivlin).
        max_force: plate force (N), >= 0; a scalar or an array, every force of which is
            found on one followed path. Reissner: the same compliance at every force.
            Axisymmetric: a force below DOME_MIN_TRAVEL_FRACTION t / C_Reissner (5.4 mN
            for the dome-Hall sensor's dome) is evaluated at that floor (see DOME_MIN_TRAVEL_FRACTION).
        fidelity: "reissner" (closed form, linear) or "axisymmetric" (nonlinear FE).
        base: "bonded" (rim clamped, as in the dome-Hall sensor) or "sliding" (rim free to slide radially).
        mesh: (elements through the wall, elements along the meridian), axisymmetric only;
            None: DEFAULT_MESH, or the level ``rtol`` chooses.
        rtol: relative tolerance on the estimated mesh error (axisymmetric only, not with
            ``mesh``, not under jax.jit or jax.grad): the mesh ladder is climbed until the
            estimate is <= rtol |compliance| at every force; where no level meets it the
            result is ``DomeResult.tolerance_not_met``.
        estimate: if True, a :class:`ComplianceEstimate` (value, error, result, mesh) is
            returned (with ``throw=True`` it raises as the plain value would).
        throw: if True, a solve that did not succeed raises an error naming what failed
            (:class:`DomeResult`); if False, ``(compliance, result)`` is returned instead.

    The error estimate compares two consecutive levels of a fixed mesh ladder
    (``magdesign.mechanics._ladder.LADDER``, each level refining wall and meridian
    together; DEFAULT_MESH is its lowest level): ESTIMATE_FACTOR (4) times their
    difference, and not below ESTIMATE_FLOOR (0.3 %) of the value; the lowest level is
    compared with the one above (factor 1 + ESTIMATE_FACTOR). It assumes that the
    remaining error is at most that factor times the last refinement's change: the
    largest ratio measured, with a margin, on bonded domes of t / R_o 0.05, 0.125 and 0.25
    from a travel of t / 10 to past a buckle, against meshes at least twice as fine each way.
    It costs a second mesh's solve. Past a buckle the compliance depends on which branch
    the path follows and the levels differ by percents (the 8 / 1 mm dome at 5 N: 6 % at
    DEFAULT_MESH): the estimate says so. A mesh off the ladder, or Reissner, has no
    estimate (+inf). The error is not differentiated; the value is (jax.jit and jax.grad
    work without rtol).

    Raises ValueError naming the argument for a bad configuration or value. A plain
    Python call reuses the program compiled for the same fidelity, base, mesh and shape.
    """
    _check(outer_radius, thickness, material, fidelity, base, mesh, rtol)
    check_nonnegative(max_force=max_force, unit="N")
    mesh = DEFAULT_MESH if mesh is None else tuple(mesh)
    if fidelity == "reissner":
        shape = jnp.shape(max_force)
        compliance = jnp.broadcast_to(_reissner_compliance(outer_radius, thickness, material), shape)
        out = ComplianceEstimate(compliance, jnp.full(shape, jnp.inf), _successful(shape), None)
    elif rtol is None and not estimate:
        travels, result, forces = _travels(outer_radius, thickness, material, max_force, base, mesh)
        return _raise_unless_successful(travels / forces, result, throw)
    else:
        params = (outer_radius, thickness, material)
        used, value, error, result = _compliance_estimate(params, max_force, base, mesh, rtol)
        out = ComplianceEstimate(value, error, result, used)
    if estimate:
        return out.result.error_if(out, out.result != DomeResult.successful) if throw else out
    return _raise_unless_successful(out.value, out.result, throw)


def _curve_at(params, travels, max_force, fractions, base, mesh):
    """(travels (n,), forces (n,), radii (n,), results (n,)) at one mesh: at ``travels`` or,
    where it is None, at ``fractions`` of the travel where ``max_force`` is first crossed."""
    crossing = None
    if travels is None:
        end, crossing, _ = _travels(*params, max_force, base, mesh)
        travels = end * fractions
    forces, radii, result = _axisymmetric_curve(*_as_arrays(params), travels, base, mesh)
    if crossing is not None:  # the path's own result where the wanted force was not carried
        result = DomeResult.where(crossing == DomeResult.successful, result, crossing)
    return travels, forces, radii, result


def _curve_estimate(params, travels, max_force, fractions, base, mesh, rtol, estimate):
    """:class:`DomeCurve` at ``mesh`` or, with ``rtol``, at the level of the ladder that meets
    it; without ``estimate`` (and rtol) at ``mesh`` alone, its error unknown (+inf)."""

    def evaluate(level):
        at, forces, radii, result = _curve_at(params, travels, max_force, fractions, base, _ladder.LADDER[level])
        companion = _ladder.LADDER[_ladder.companion(level)]
        _, other, _, other_result = _curve_at(params, at, None, None, base, companion)
        error = _ladder.estimate(forces, other, level, other_result == DomeResult.successful)
        return forces, error, result, at, radii

    if rtol is not None:
        level, (forces, error, result, at, radii) = _climb(evaluate, rtol)
        return DomeCurve(at, forces, radii, error, result, _ladder.LADDER[level])
    level = _ladder.level_of(mesh)
    if level is None or not estimate:
        at, forces, radii, result = _curve_at(params, travels, max_force, fractions, base, mesh)
        return DomeCurve(at, forces, radii, jnp.full_like(forces, jnp.inf), result, mesh)
    forces, error, result, at, radii = evaluate(level)
    return DomeCurve(at, forces, radii, error, result, mesh)


def dome_curve(
    *,
    outer_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractMaterial,
    travels: Float[ArrayLike, " n"] | None = None,
    max_force: Float[ArrayLike, ""] | None = None,
    fidelity: str = "axisymmetric",
    base: str = "bonded",
    mesh: tuple[int, int] | None = None,
    rtol: float | None = None,
    n_points: int = 10,
    estimate: bool = True,
    throw: bool = True,
) -> DomeCurve:
    """The force-travel path of the dome under plate-travel control (:class:`DomeCurve`).

    Give either ``travels`` (n,) (m, increasing, > 0): the path at those plate travels; or
    ``max_force`` (N, > 0): the path at ``n_points`` travels evenly spaced up to the first
    crossing of that force (whose travel :func:`dome_compliance` divides by it).

    Other arguments as :func:`dome_compliance`. ``DomeCurve.error`` is the estimated mesh
    error of each force, from the companion level of the mesh ladder solved at the same
    travels (see :func:`dome_compliance` for the estimate and what it assumes); with
    ``rtol`` the ladder is climbed until every point's estimate is <= rtol |force|.
    ``estimate=False`` (without ``rtol``) skips the companion level's solve, half the cost
    (and half the compile under jax.jit), and leaves ``DomeCurve.error`` +inf. With
    ``throw=True`` a point that did not succeed raises an error naming what failed; with
    ``throw=False`` each point carries its :class:`DomeResult`. A thin dome's path is
    followed through its softening: the force may fall as the travel grows.
    """
    _check(outer_radius, thickness, material, fidelity, base, mesh, rtol)
    if (travels is None) == (max_force is None):
        raise ValueError("give exactly one of travels (m) and max_force (N)")
    mesh = DEFAULT_MESH if mesh is None else tuple(mesh)
    fractions = None
    if travels is None:
        check_positive(max_force=max_force, unit="N")
        if int(n_points) != n_points or n_points < 1:
            raise ValueError(f"n_points must be a positive integer, got {n_points!r}")
        fractions = np.arange(1, n_points + 1) / n_points
    else:
        travels = jnp.asarray(travels, dtype=float)
        concrete = _concrete(travels)
        if travels.ndim != 1 or (concrete is not None and not (np.all(concrete > 0) and np.all(np.diff(concrete) > 0))):
            raise ValueError(f"travels must be a 1-D array of increasing positive plate travels (m), got {travels!r}")
        flat = _concrete(outer_radius - thickness)
        if concrete is not None and flat is not None and concrete[-1] >= flat:
            raise ValueError(
                f"travels must stay below outer_radius - thickness = {float(flat)!r} m (the wall "
                f"pressed flat), got {float(concrete[-1])!r} m"
            )
    if fidelity == "reissner":
        reissner = _reissner_compliance(outer_radius, thickness, material)
        if travels is None:
            travels = jnp.asarray(reissner * max_force * fractions, dtype=float)
        unknown = jnp.full_like(travels, jnp.inf)
        return DomeCurve(
            travels, travels / reissner, jnp.zeros_like(travels), unknown, _successful(travels.shape), None
        )
    params = (outer_radius, thickness, material)
    curve = _curve_estimate(params, travels, max_force, fractions, base, mesh, rtol, estimate)
    if throw:
        curve = curve.result.error_if(curve, curve.result != DomeResult.successful)
    return curve
