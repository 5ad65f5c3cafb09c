"""The polish: Newton (optimistix) on the KKT or feasibility equations of the search's
active set, and the implicit derivatives of its root."""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from magdesign.design._sqp.jet import Jet, Settings, _first_jet, _lagrangian_hessian, _scaled_rows, _values
from magdesign.design._sqp.search import SearchState
from magdesign.design._sqp.step import _held_rows
from magdesign.design.problem import Problem


class _Active(eqx.Module):
    """The active set of the polish: limit rows held as equations, variables fixed on a bound."""

    limits: Bool[Array, " l"]
    at_lower: Bool[Array, " n"]
    at_upper: Bool[Array, " n"]

    @property
    def fixed(self):
        """(n,) the variables held on a bound."""
        return self.at_lower | self.at_upper

    def fixed_residual(self, y, y_max):
        """(n,) each fixed variable's distance from its bound, 0 for the free ones."""
        return jnp.where(self.at_lower, y, jnp.where(self.at_upper, y - y_max, 0.0))


class _KKT(eqx.Module):
    """The KKT residual of an active set (the polish's equations with an objective): at
    z = (y, multipliers), stationarity of the Lagrangian on the free variables, the
    fixed variables' distance to their bound, the targets and active limit rows, and the
    inactive rows' multipliers, from the model's :class:`Jet` at y (its derivative in z
    from the model's Hessians)."""

    problem: Problem
    weight: Float[Array, ""]
    active: _Active
    equations: Bool[Array, " m"]
    y_max: Float[Array, " n"]

    def rows(self, z, jet):
        """The residual at z from the model's rows and their Jacobian (with the objective's) in ``jet``."""
        n = self.y_max.shape[0]
        y, lam = z[:n], z[n:]
        stationarity = self.weight * jet.J[0] + jet.J[1:].T @ lam
        r_y = jnp.where(self.active.fixed, self.active.fixed_residual(y, self.y_max), stationarity)
        return jnp.concatenate([r_y, jnp.where(self.equations, jet.v[1:], lam)])

    def tangent(self, jet, z, dz):
        """(n + m,) the residual's derivative along dz (n + m,) at z, where the model's
        :class:`Jet` is ``jet``."""
        n = self.y_max.shape[0]
        lam, dy, dlam = z[n:], dz[:n], dz[n:]
        d_stationarity = _lagrangian_hessian(jet, lam, self.weight) @ dy + jet.J[1:].T @ dlam
        return jnp.concatenate(
            [jnp.where(self.active.fixed, dy, d_stationarity), jnp.where(self.equations, jet.J[1:] @ dy, dlam)]
        )

    def unknowns(self, y, multipliers):
        """(n + m,) z at y (n,) with the held rows' ``multipliers`` (m,)."""
        return jnp.concatenate([y, jnp.where(self.equations, multipliers, 0.0)])


class _Feasibility(eqx.Module):
    """The polish's equations without an objective: the targets and active limit rows,
    and the fixed variables' distance to their bound, from the model's :class:`Jet` at y
    (its values and Jacobian)."""

    problem: Problem
    active: _Active
    equations: Bool[Array, " m"]
    y_max: Float[Array, " n"]

    def rows(self, y, jet):
        """The residual at y from the model's rows in ``jet``."""
        return jnp.concatenate([jnp.where(self.equations, jet.v[1:], 0.0), self.active.fixed_residual(y, self.y_max)])

    def tangent(self, jet, y, dy):
        """The residual's derivative along dy (n,) at y, where the model's :class:`Jet` is ``jet``."""
        return jnp.concatenate([jnp.where(self.equations, jet.J[1:] @ dy, 0.0), jnp.where(self.active.fixed, dy, 0.0)])

    def unknowns(self, y, multipliers):
        """(n,) the unknowns at y (n,): y itself (no multipliers)."""
        return y


def _rows_in(problem, jet, theta):
    """The model's :class:`Jet` ``jet`` with its rows read again from its outputs in theta
    (targets' values and limits' bounds)."""
    c, _ = _scaled_rows(problem, dict(zip(problem.outputs, jet.outputs)), theta)
    return eqx.tree_at(lambda j: j.v, jet, jnp.concatenate([jet.v[:1], c]))


def _in_theta(equations, z, jet, theta):
    """The model's :class:`Jet` ``jet`` at y = z[:n], with what the rows of ``equations``
    read of it as functions of theta, for derivatives in theta: without fixed inputs
    theta moves only the targets' and limits' bounds (the rows c, from the outputs); with
    them it moves the model, whose values (and, for the KKT residual, first derivatives,
    so that their derivative in theta is a mixed second derivative) are evaluated again."""
    problem, n = equations.problem, len(equations.problem.variables)
    if not problem.fixed_names:
        return _rows_in(problem, jet, theta)
    if problem.objective is None:  # the feasibility rows read the values alone
        v, outputs = _values(problem, z[:n], theta)
        return eqx.tree_at(lambda j: (j.v, j.outputs), jet, (v, outputs))
    J, (v, outputs) = _first_jet(problem, z[:n], theta)
    return eqx.tree_at(lambda j: (j.v, j.J, j.outputs), jet, (v, J, outputs))


def _implicit_derivatives(equations, z, jet, theta, usable):
    """(len(z), p) d z / d theta at a root z of the polish's ``equations``, where the
    model's :class:`Jet` is ``jet`` (the polish's last): the implicit function theorem
    applied to the equations to first order about z (:func:`_linearised`), so that the
    model is not evaluated again, nor traced again, unless it depends on theta (fixed
    inputs). Forward mode through the polish's loop itself would trace it whole under
    JAX's jvp and vmap, and with it the model.

    One solve with the polish's linear solver per column of theta, ``throw=False``: a
    column that is not finite stays NaN in its own batch member (the caller masks it), not
    an error that would stop the batch. ``usable``: False where z or the equations there
    are not finite; the equations are then zero, and so are the derivatives."""
    import lineax as lx  # here, as in _newton: a run that loads its compiled solver never needs it

    from magdesign.design._linear import LUOrSVD

    operator = lx.JacobianLinearOperator(lambda root, _: _linearised(equations, z, jet, usable, root, theta), z)

    def column(direction):
        moved = jax.jvp(lambda t: _linearised(equations, z, jet, usable, z, t), (theta,), (direction,))[1]
        return -lx.linear_solve(operator, moved, LUOrSVD(), throw=False).value

    return jax.vmap(column, out_axes=1)(jnp.eye(theta.shape[0], dtype=theta.dtype))


def _solvable(equations, z, jet, theta, dz, *, sqp):
    """(p,) bool: whether the linear system that the implicit derivatives dz (len(z), p)
    solve at the root z has a solution in each column of theta that is a target's value or
    a limit's bound (the others: True). Held rows that are dependent (a limit whose two
    bounds are equal, a limit given twice) leave none for a bound moved alone, and the
    least-squares answer, which splits the move between the rows, is no derivative: a
    pinned limit's two sides get 0.25 each where raising the upper one alone moves the
    optimum by 0.5 (and lowering it leaves no design)."""
    problem = equations.problem
    n_rows = len(problem.targets) + len(problem.limit_rows)

    moved = jax.jacfwd(lambda bounds: equations.rows(z, _rows_in(problem, jet, theta.at[:n_rows].set(bounds))))(
        theta[:n_rows]
    )  # (len(z), rows)
    reached = jax.vmap(lambda d: equations.tangent(jet, z, d), in_axes=1, out_axes=1)(dz[:, :n_rows])
    size = jnp.max(jnp.abs(moved), axis=0, initial=0.0) + jnp.max(jnp.abs(reached), axis=0, initial=0.0)
    solvable = jnp.max(jnp.abs(reached + moved), axis=0, initial=0.0) <= sqp.solvable_rtol * size
    return jnp.concatenate([solvable, jnp.ones(theta.shape[0] - n_rows, bool)])


def _linearised(equations, z, jet, usable, root, theta):
    """The equations to first order in the root about z: exact derivatives at z, in the
    root from the model's jet there, in theta from :func:`_in_theta`; zero where not
    ``usable``."""
    return jnp.where(
        usable, equations.rows(z, _in_theta(equations, z, jet, theta)) + equations.tangent(jet, z, root - z), 0.0
    )


def _about(equations, z, jet):
    """fn(root, args) -> (the polish's ``equations`` to first order in the root about z,
    where the model's :class:`Jet` is ``jet``; no aux): what Newton's step from z solves,
    as optimistix's Newton takes it."""
    return lambda root, _: (equations.rows(z, jet) + equations.tangent(jet, z, root - z), None)


def _equations(problem: Problem, search: SearchState, y_max):
    """The polish's equations on the active set of the search's last subproblem: the KKT
    system with an objective, else the feasibility equations."""
    step = search.step
    active = _Active(step.active_limits, step.at_lower, step.at_upper)
    held = _held_rows(step)
    if problem.objective is None:
        return _Feasibility(problem, active, held, y_max)
    return _KKT(problem, search.weight, active, held, y_max)


def _newton(settings: Settings):
    """The polish's root finder: optimistix's Newton, to a tenth of the design's tolerance
    on its residual and on its step relative to (1 + |z|) (from the search's point
    typically one or two steps), its linear systems through LU, else an SVD (LUOrSVD: the
    feasibility equations are not square, in general; with more unknowns than equations
    Newton through an SVD is Gauss-Newton with minimum-norm steps). Optimistix and lineax
    are imported here, when the solver is traced: a run that loads its compiled solver
    (magdesign._export) never imports them."""
    import optimistix as optx

    from magdesign.design._linear import LUOrSVD

    return optx.Newton(rtol=settings.rtol * 0.1, atol=settings.rtol * 0.1, linear_solver=LUOrSVD())


class PolishState(eqx.Module):
    """The polish's state: ``z`` the point where Newton evaluates the model next,
    ``evaluated`` the last point where it did, ``jet`` the model's :class:`Jet` there,
    ``newton`` optimistix's Newton state (its ``f`` the equations' residual at
    ``evaluated``), ``done`` where Newton has stopped."""

    z: Float[Array, " u"]
    evaluated: Float[Array, " u"]
    jet: Jet
    newton: eqx.Module
    done: Bool[Array, ""]


def _polish_at(equations, z, jet, newton):
    """The polish's state before its first step, at z, where the model's :class:`Jet` is
    ``jet`` (or where it will be evaluated first)."""
    state = newton.init(
        _about(equations, z, jet), z, None, {}, jax.eval_shape(equations.rows, z, jet), None, frozenset()
    )
    return PolishState(z, z, jet, state, jnp.asarray(False))


def _polish_start(equations, search: SearchState, newton):
    """The polish's state before its first step on ``equations`` (:func:`_equations` of
    the search): at the search's point and multipliers."""
    return _polish_at(equations, equations.unknowns(search.y, search.step.multipliers), search.jet, newton)


def _newton_step(equations, newton, polish: PolishState, jet, max_steps):
    """The polish after Newton's step from its point z, where the model's :class:`Jet` is
    ``jet``. Stepped as optimistix's interactive use of a solver (its ``step`` and
    ``terminate``) inside the solver's loop, so that the search and the polish evaluate the
    model at one place of the program; the steps and stopping rule of
    ``optimistix.root_find`` (which stops at a point that is not finite too), and a stop
    at a residual that is not finite, where no step can lead."""
    z, fn = polish.z, _about(equations, polish.z, jet)
    z_next, state, _ = newton.step(fn, z, None, {}, polish.newton, frozenset())
    stop, _ = newton.terminate(fn, z, None, {}, state, frozenset())
    finite = jnp.all(jnp.isfinite(z)) & jnp.all(jnp.isfinite(state.f))
    done = stop | (state.step >= max_steps) | ~finite
    return PolishState(z_next, z, jet, state, done)
