"""The solver's settings, a problem's arrays, and its model's jet (values, first and
second derivatives) at a scaled point."""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from magdesign._tracing import traced_once
from magdesign.design._sqp.sqp import SQP
from magdesign.design.problem import Problem, check_outputs


class Settings(eqx.Module):
    """Solver settings: tolerances on scaled quantities (traced: a program serves every
    tolerance), the steps allowed per stage, and the solver's thresholds (:class:`SQP`,
    static: part of the compiled program)."""

    rtol: Float[Array, ""]
    atol: Float[Array, ""]
    max_steps: int = eqx.field(static=True)
    sqp: SQP = eqx.field(static=True, default_factory=SQP)


def problem_arrays(problem: Problem, xp=jnp):
    """(lower, upper, scale, start, theta) of a problem as float64 arrays.

    theta stacks the target values, then each limit row's bound, then the fixed inputs
    (SI): everything the optimum has implicit derivatives with respect to. ``xp`` is jnp
    inside traced code and numpy outside, where it is much cheaper than eager jnp.
    """
    stack = lambda values: xp.stack([xp.asarray(v, xp.float64) for v in values]) if values else xp.zeros((0,))  # noqa: E731
    variables = problem.variables
    theta = [t.value for t in problem.targets] + [getattr(problem.limits[i], side) for i, side in problem.limit_rows]
    theta += list(problem.fixed_values)
    return (
        stack([v.lower for v in variables]),
        stack([v.upper for v in variables]),
        stack([v.scale for v in variables]),
        stack([v.start for v in variables]),
        stack(theta),
    )


def _evaluate(problem: Problem, y, theta):
    """Model outputs, scaled constraints c (targets == 0, limit rows <= 0) and objective."""
    lower, _, scale, _, _ = problem_arrays(problem)
    x = lower + scale * y
    n_rows = len(problem.targets) + len(problem.limit_rows)
    fixed = {name: theta[n_rows + j] for j, name in enumerate(problem.fixed_names)}
    inputs = {v.name: x[i] for i, v in enumerate(problem.variables)} | fixed
    try:
        outputs = problem.model(inputs)
    except KeyError as error:
        name = error.args[0] if error.args else None
        if isinstance(name, str) and name not in inputs:
            raise ValueError(
                f"{name}: the model reads an input that is neither a variable nor fixed (inputs: {sorted(inputs)})"
            ) from error
        raise
    check_outputs(problem, outputs)
    return outputs, *_scaled_rows(problem, outputs, theta)


def _scaled_rows(problem: Problem, outputs, theta):
    """(c, f): the scaled constraint rows and the objective from the model's ``outputs``
    {name: value (SI)} and theta's target values and limit bounds."""
    n_targets = len(problem.targets)
    rows = [(outputs[t.output] - theta[k]) / t.scale for k, t in enumerate(problem.targets)]
    for k, (i, side) in enumerate(problem.limit_rows):
        limit = problem.limits[i]
        excess = outputs[limit.output] - theta[n_targets + k]
        rows.append((excess if side == "upper" else -excess) / limit.scale)
    # A problem without targets and limits gets one limit row that never binds (-1 <= 0):
    # with zero-size rows, jax 0.10 lowers some LAPACK calls of the solver as untyped
    # custom calls that XLA cannot run ("No registered implementation for untyped custom
    # call to lapack_dgesdd_ffi"). _core drops the row again.
    c = jnp.stack(rows) if rows else jnp.full((1,), -1.0)
    objective = problem.objective
    if objective is None:
        f = jnp.zeros(())
    else:
        f = (1.0 if objective.sense == "min" else -1.0) * objective.weight * outputs[objective.output]
    return c, f


class Jet(eqx.Module):
    """The model at one scaled point y, m constraint rows and n variables.

    ``v`` = (objective f, constraint rows c...) (1 + m,), scaled as in :func:`_evaluate`
    (f unweighted); ``J`` (1 + m, n) and ``H`` (1 + m, n, n) its first and second
    derivatives in y; ``outputs`` (k,) the model outputs named by ``Problem.outputs`` (SI).
    """

    v: Float[Array, " 1+m"]
    J: Float[Array, "1+m n"]
    H: Float[Array, "1+m n n"]
    outputs: Float[Array, " k"]


@traced_once
def _values(problem, y, theta):
    """(v, outputs) at y: (objective, constraint rows...) and the named outputs."""
    outputs, c, f = _evaluate(problem, y, theta)
    return jnp.concatenate([f[None], c]), jnp.stack([outputs[name] for name in problem.outputs])


@traced_once
def _first_jet(problem, y, theta):
    """(J, (v, outputs)) at y: the model's first derivatives, by forward mode."""

    def values(y):
        v, outputs = _values(problem, y, theta)
        return v, (v, outputs)

    return jax.jacfwd(values, has_aux=True)(y)


@traced_once
def _jet(problem, y, theta) -> Jet:
    """The :class:`Jet` at y from one trace of the model (forward over forward mode)."""
    if problem.objective is None:
        # Without an objective the search's Hessian is the floor alone (see _step), so
        # tracing no second derivatives keeps models with costly kernels quick to compile.
        J, (v, outputs) = _first_jet(problem, y, theta)
        return Jet(v, J, jnp.zeros((*J.shape, y.shape[0])), outputs)

    def first(y):
        J, (v, outputs) = _first_jet(problem, y, theta)
        return J, (J, v, outputs)

    H, (J, v, outputs) = jax.jacfwd(first, has_aux=True)(y)
    return Jet(v, J, H, outputs)


def _lagrangian_hessian(jet, multipliers, weight):
    """(n, n) Hessian of weight f + multipliers . c in y."""
    return weight * jet.H[0] + jnp.einsum("i,ijk->jk", multipliers, jet.H[1:])


def _pick(condition, new, old):
    """``new`` where ``condition`` holds, else ``old``, leaf by leaf."""
    return jax.tree.map(lambda a, b: jnp.where(condition, a, b), new, old)
