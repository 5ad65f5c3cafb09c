"""From readings back to the source's displacement, by least squares on the forward chain.

For one reading vector r (S, C) the displacement u (3,) minimises

    chi2(u) = || (forward(u) - r) / noise ||^2

with forward the scene's static, deterministic chain (:func:`forward_readings`: no
noise, no time-series lag, no quantisation, whose staircase has a zero derivative),
solved by optimistix (Levenberg-Marquardt by default, Gauss-Newton on request),
``throw=False``. Unknowns are scaled by the wanted ``resolution``: u = resolution y.

Starts. A least-squares solver only finds the minimum nearest its start, and reports
"successful" there whether or not the residual is small. So each reading vector is
compared with the readings of a table of ``candidates`` displacements (computed once
per call, like the 77 reference points of the GMR-inductor paper); the solver runs from each of the
``starts`` nearest (in reading space), and the smallest chi2 wins.

Status, in this order of precedence (:class:`InverseStatus`):

- ``no_match``: even the best fit misses the readings by more than their noise allows
  (chi2 > NO_MATCH_CHI2): readings outside the modelled range, or every start stuck.
- ``ill_conditioned``: at the solution the smallest singular value of the scaled
  Jacobian d((forward - r) / noise) / dy is below 1, i.e. some displacement step of one
  ``resolution`` changes the readings by less than their noise (e.g. a saturated sensor).
- ``ambiguous``: another start reached a second, distinct displacement (more than one
  ``resolution`` away) that also fits the readings within their noise.
- ``not_converged``: the solver stopped without converging.
- ``successful``: otherwise.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array, ArrayLike, Float, Int

from magdesign.inverse._jacobian import FD_JACOBIAN_STEP, LSQ_ATOL, LSQ_RTOL, difference_jacobian
from magdesign.scene.core import STATIC_WITHOUT, AbstractScene, chain
from magdesign.transducers.resolution import cramer_rao

# Effects that the static, deterministic forward model of an inverse leaves out: those of the
# static chain (noise and the lag are not functions of one displacement), and quantisation,
# piecewise constant (zero derivative) and treated as part of the noise.
NOT_INVERTED = (*STATIC_WITHOUT, "quantisation")
SOLVERS = ("levenberg_marquardt", "gauss_newton")
# Largest chi2 (in units of the noise variance) of a fit that counts as explaining the
# readings: with one to a few spare readings, chi2 > 25 has a probability below 1e-4
# for Gaussian noise, while a fit stuck in a wrong minimum misses by far more.
NO_MATCH_CHI2 = 25.0


class InverseStatus(eqx.Enumeration):
    """Outcome of an inversion (see the module docstring)."""

    successful = "the readings determine the displacement to the wanted resolution"
    ill_conditioned = "a displacement step of the wanted resolution changes the readings by less than their noise"
    ambiguous = "a second, distinct displacement explains the readings within their noise"
    no_match = "no displacement reproduces the readings within their noise"
    not_converged = "the least-squares solver did not converge (see solver_result)"


class Inversion(eqx.Module):
    """An inversion's result; every field has the leading (batch) shape of the readings.

    Attributes:
        displacement: (..., 3) the fitted displacement (m).
        status: :class:`InverseStatus`.
        solver_result: the optimistix result (``optx.RESULTS``) of the best start.
        conditioning: (...) smallest singular value of the scaled Jacobian (-): the reading
            change, in noise units, of the least visible displacement step of one
            resolution; < 1 is ill-conditioned.
        uncertainty: (..., 3) standard deviation of each displacement component (m), from
            the Cramer-Rao bound noise^2 (J^T J)^-1 (:func:`magdesign.transducers.cramer_rao`);
            a direction the readings do not see gets a huge variance (the status flags it).
        chi2: (...) the best fit's sum of squared residuals in noise units (-).
        residual: (..., S, C) readings minus the forward model at the solution.
        steps: (...) solver steps of the best start.
    """

    displacement: Float[Array, "*batch 3"]
    status: InverseStatus
    solver_result: optx.RESULTS
    conditioning: Float[Array, "*batch"]
    uncertainty: Float[Array, "*batch 3"]
    chi2: Float[Array, "*batch"]
    residual: Float[Array, "*batch s c"]
    steps: Int[Array, "*batch"]


def forward_readings(scene: AbstractScene, displacement: Float[ArrayLike, "*batch 3"]) -> Float[Array, "*batch s c"]:
    """The static deterministic readings (..., S, C) of the scene at displacements (..., 3) (m)."""
    displacement = jnp.asarray(displacement, dtype=float)
    flat = displacement.reshape(-1, 3)
    readings = chain(scene, flat, without=NOT_INVERTED).readings
    return readings.reshape(displacement.shape[:-1] + readings.shape[1:])


def _solver(name):
    if name not in SOLVERS:
        raise ValueError(f"solver: expected one of {SOLVERS}, got {name!r}")
    if name == "gauss_newton":
        return optx.GaussNewton(rtol=LSQ_RTOL, atol=LSQ_ATOL)
    return optx.LevenbergMarquardt(rtol=LSQ_RTOL, atol=LSQ_ATOL)


def _scaled_forward(scene, resolution):
    """y (3,) -> readings (S C,) at u = resolution y, with a central-difference derivative."""
    return difference_jacobian(lambda y: forward_readings(scene, y * resolution).ravel(), FD_JACOBIAN_STEP)


def _fit(scene, readings, y0, noise, resolution, solver, max_steps):
    """Least squares from one scaled start y0 (3,): (y, chi2, result, steps)."""
    forward = _scaled_forward(scene, resolution)

    def residual(y, target):
        return (forward(y) - target.ravel()) / noise

    solution = optx.least_squares(residual, solver, y0, args=readings, max_steps=max_steps, throw=False)
    r = residual(solution.value, readings)
    return solution.value, jnp.sum(r * r), solution.result, solution.stats["num_steps"]


@eqx.filter_jit
def _invert(scene, readings, candidates, noise, resolution, starts, solver, max_steps):
    table = forward_readings(scene, candidates).reshape(candidates.shape[0], -1) / noise
    flat = readings.reshape(-1, table.shape[1]) / noise

    def one(target):
        distance = jnp.sum((table - target) ** 2, axis=-1)
        nearest = jnp.argsort(distance)[:starts]
        fits = jax.vmap(lambda y0: _fit(scene, target * noise, y0, noise, resolution, solver, max_steps))(
            candidates[nearest] / resolution
        )
        y, chi2 = fits[0], fits[1]
        best = jnp.argmin(chi2)
        y_best, chi2_best, result, steps = jax.tree_util.tree_map(lambda leaf: leaf[best], fits)

        forward = _scaled_forward(scene, resolution)

        def scaled(v):
            return (forward(v) - target * noise) / noise

        bound = cramer_rao(jax.jacfwd(scaled)(y_best), 1.0)
        separation = jnp.sqrt(jnp.sum((y - y_best) ** 2, axis=-1))
        second = jnp.any((chi2 <= NO_MATCH_CHI2) & (separation > 1.0))
        status = InverseStatus.where(
            result == optx.RESULTS.successful, InverseStatus.successful, InverseStatus.not_converged
        )
        status = InverseStatus.where(second, InverseStatus.ambiguous, status)
        status = InverseStatus.where(bound.conditioning < 1.0, InverseStatus.ill_conditioned, status)
        status = InverseStatus.where(chi2_best > NO_MATCH_CHI2, InverseStatus.no_match, status)
        return Inversion(
            displacement=y_best * resolution,
            status=status,
            solver_result=result,
            conditioning=bound.conditioning,
            uncertainty=resolution * bound.deviation,
            chi2=chi2_best,
            residual=(-scaled(y_best) * noise).reshape(readings.shape[-2:]),
            steps=steps,
        )

    batch = readings.shape[:-2]
    result = jax.vmap(one)(flat)
    return jax.tree_util.tree_map(lambda leaf: leaf.reshape(batch + leaf.shape[1:]), result)


def invert_displacement(
    scene: AbstractScene,
    readings: Float[ArrayLike, "*batch s c"],
    *,
    noise: Float[ArrayLike, ""],
    resolution: Float[ArrayLike, ""],
    candidates: Float[ArrayLike, "k 3"] | None = None,
    starts: int = 3,
    solver: str = "levenberg_marquardt",
    max_steps: int = 100,
) -> Inversion:
    """The displacements (m) of the scene's source that give ``readings`` (..., S, C).

    Args:
        scene: the scene whose forward chain is inverted.
        readings: measured readings (the scene's reading unit), any batch shape in front;
            the whole batch is solved by one compiled, vectorised solver.
        noise: standard deviation of one reading (reading unit), > 0.
        resolution: the displacement step the readings should resolve (m), > 0.
        candidates: (K, 3) reference displacements (m) to start from (e.g.
            :func:`displacement_grid` over the working range); the rest position alone
            by default.
        starts: how many of the nearest candidates (in reading space) each solve starts
            from (static), at most K; with one, second solutions are not looked for.
        solver: "levenberg_marquardt" or "gauss_newton".
        max_steps: solver step limit per start.

    Returns:
        An :class:`Inversion` with the batch shape of ``readings``.
    """
    readings = jnp.asarray(readings, dtype=float)
    if readings.ndim < 2:
        raise ValueError(f"readings: expected shape (..., S, C), got {readings.shape}")
    candidates = jnp.zeros((1, 3)) if candidates is None else jnp.asarray(candidates, dtype=float)
    if candidates.ndim != 2 or candidates.shape[1] != 3:
        raise ValueError(f"candidates: expected shape (K, 3), got {candidates.shape}")
    if not 1 <= starts:
        raise ValueError(f"starts: expected an integer >= 1, got {starts!r}")
    starts = min(starts, candidates.shape[0])
    noise, resolution = jnp.asarray(noise, dtype=float), jnp.asarray(resolution, dtype=float)
    return _invert(scene, readings, candidates, noise, resolution, starts, _solver(solver), max_steps)


def displacement_grid(
    x: Float[ArrayLike, " nx"], y: Float[ArrayLike, " ny"], z: Float[ArrayLike, " nz"]
) -> Float[Array, "n 3"]:
    """All (nx ny nz, 3) combinations of the given x, y, z values (m), x varying slowest."""
    grid = jnp.meshgrid(
        jnp.asarray(x, dtype=float), jnp.asarray(y, dtype=float), jnp.asarray(z, dtype=float), indexing="ij"
    )
    return jnp.stack(grid, axis=-1).reshape(-1, 3)
