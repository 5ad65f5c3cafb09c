"""Calibration: fit a scene's uncertain constants to (load, reading) pairs.

The constants (named by their dotted spec keys, see
:func:`magdesign.scene.parameters`) are fitted as factors on their start values,
p = p_start * y, by least squares on

    (simulate(with_parameters(scene, p), loads).readings - readings) / noise

(noise-free chain: the scene's noise effect is left out). The uncertainty of each
fitted constant is the square root of the diagonal of noise^2 (J^T J)^-1 at the
solution; with ``noise=None`` the noise is estimated from the residuals,
sqrt(RSS / (m - p)) for m readings and p constants.
"""

from collections.abc import Sequence

import equinox as eqx
import jax
import jax.numpy as jnp
import optimistix as optx
from jaxtyping import Array, ArrayLike, Bool, Float, Int

from magdesign._numerics import safe_sqrt
from magdesign.inverse._jacobian import LSQ_ATOL, LSQ_RTOL, difference_jacobian
from magdesign.scene.core import AbstractScene, chain, parameters, with_parameters
from magdesign.scene.loads import Loads
from magdesign.transducers.resolution import cramer_rao
from magdesign.units import SpecError

# Step of the central-difference Jacobian of magdesign.inverse's calibration, in its
# unknowns (factors on the constants' start values, order one): truncation (1e-12) and
# rounding (1e-16 / 1e-6 = 1e-10) errors both far below the 1e-6 it is asked to recover.
FD_CALIBRATION_STEP = 1e-6


class Calibration(eqx.Module):
    """A calibration's result.

    Attributes:
        values: fitted constants by name (SI).
        uncertainty: their standard deviations by name (SI).
        residuals: (n, S, C) readings minus the fitted model.
        result: the optimistix result (``optx.RESULTS``) of the fit.
        mechanics_converged: whether the scene's mechanics converged at every load with
            the fitted constants (where not, the fit is not to be trusted).
        steps: solver steps taken.
    """

    values: dict[str, Float[Array, ""]]
    uncertainty: dict[str, Float[Array, ""]]
    residuals: Float[Array, "n s c"]
    result: optx.RESULTS
    mechanics_converged: Bool[Array, ""]
    steps: Int[Array, ""]


def calibrate(
    scene: AbstractScene,
    names: Sequence[str],
    loads: Loads,
    readings: Float[ArrayLike, "n s c"],
    *,
    noise: Float[ArrayLike, ""] | None = None,
    max_steps: int = 100,
) -> Calibration:
    """Fit the constants ``names`` of ``scene`` (from their current values) to
    ``readings`` (n, S, C) measured at ``loads`` (n points); Levenberg-Marquardt,
    ``throw=False``. The returned values are SI; see the module docstring.
    """
    names = tuple(names)
    values = parameters(scene)
    for name in names:
        if name not in values:
            raise SpecError(f"{name}: unknown parameter; expected one of: {', '.join(values)}")
    noise = None if noise is None else jnp.asarray(noise, dtype=float)
    return _calibrate(scene, names, loads, jnp.asarray(readings, dtype=float), noise, max_steps)


@eqx.filter_jit
def _calibrate(scene, names, loads, readings, noise, max_steps):
    start = {name: get(scene) for name, get in scene.parameter_paths.items() if name in names}
    scale = noise if noise is not None else 1.0

    def model(y):
        fitted = with_parameters(scene, {name: start[name] * y[i] for i, name in enumerate(names)})
        return chain(fitted, fitted.displacement(loads)[0], time=loads.time, without=("noise",)).readings

    flat_model = difference_jacobian(lambda y: model(y).ravel(), FD_CALIBRATION_STEP)

    def residual(y, _):
        return (flat_model(y) - readings.ravel()) / scale

    solver = optx.LevenbergMarquardt(rtol=LSQ_RTOL, atol=LSQ_ATOL)
    solution = optx.least_squares(residual, solver, jnp.ones(len(names)), max_steps=max_steps, throw=False)
    r = residual(solution.value, None)
    jacobian = jax.jacfwd(residual)(solution.value, None)
    if noise is None:
        scale = safe_sqrt(jnp.sum(r**2) / max(r.size - len(names), 1))
    sigma = scale * cramer_rao(jacobian, 1.0).deviation
    fitted = {name: start[name] * solution.value[i] for i, name in enumerate(names)}
    return Calibration(
        values=fitted,
        uncertainty={name: jnp.abs(start[name]) * sigma[i] for i, name in enumerate(names)},
        residuals=readings - model(solution.value),
        result=solution.result,
        mechanics_converged=jnp.all(with_parameters(scene, fitted).displacement(loads)[1]),
        steps=solution.stats["num_steps"],
    )
