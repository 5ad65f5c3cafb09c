"""A small dense convex quadratic programme, solved by a primal-dual interior-point method.

    minimise 1/2 w^T Q w + q^T w   subject to   A w = b,  G w <= h

with Q positive semi-definite. This is the subproblem of each step of the design solver's
sequential quadratic programming: its solution says which limits and bounds are active, so
it is the part of the solver that no library does for us in JAX (optimistix has no
constrained solvers; jaxopt's BoxOSQP, an ADMM method, reaches 1e-3 by default and needs
thousands of iterations for the 1e-10 that identifies an active set reliably; see
benchmarks/design.py). Mehrotra's predictor-corrector reaches that in 10-20 iterations on
the design solver's problems (a few variables, a few dozen rows).

The problems are tiny, so everything is dense; the loop runs a fixed maximum of iterations
and stops early where all residuals are small, which keeps it vmappable.

Successive steps of the design solver mostly share their active set, so the solver passes
the rows it found active at the last step as a guess, and the QP is first solved by a few
rounds of the primal-dual active-set method (Hintermueller, Ito and Kunisch 2002): solve
with the guessed rows as equations and the others dropped (one linear solve), then keep the
rows with a positive multiplier and add the dropped rows that the answer violates. An answer
is taken only where it satisfies every optimality condition (for a convex QP they are
sufficient); where no round gives one (a cycle, or dependent rows), the interior-point
method runs. Rows that are simple bounds on one unknown (the box and the slacks' signs,
``box``) are not unknowns of a round's system: a kept one fixes its unknown, and its
multiplier is read off that unknown's stationarity row afterwards. The default design's
first QP takes two rounds of an 11 x 11 system, where the interior-point method takes 21
iterations of a 32 x 32 one (benchmarks/design.py).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int

# Fraction of the way to the boundary of s, z >= 0 that a step may go.
_TO_BOUNDARY = 0.99
# Rounds of the active-set method tried before the interior-point method.
_ACTIVE_SET_ROUNDS = 6


def where_needed(needed, compute, operands, otherwise):
    """``compute(operands)`` where ``needed`` (a bool), else ``otherwise`` (a pytree
    shaped like its result). A while loop of at most one trip: under vmap it runs only if
    some lane needs it, where a ``lax.cond`` would become a select that always runs
    ``compute``. The operands enter the loop through a select on its trip flag, so that
    XLA cannot hoist ``compute`` out of the loop as invariant (and always run it)."""

    def body(carry):
        ran = carry[1]
        return compute(jax.tree.map(lambda a: jnp.where(ran, jnp.zeros_like(a), a), operands)), jnp.asarray(True)

    return jax.lax.while_loop(lambda carry: needed & ~carry[1], body, (otherwise, jnp.asarray(False)))[0]


class QPSolution(eqx.Module):
    """w (nw,) the minimiser; y (me,) the equality multipliers and z (mi,) >= 0 the
    inequality ones, so that Q w + q + A^T y + G^T z = 0; converged: residuals below tol;
    iterations: those taken."""

    w: Float[Array, " nw"]
    y: Float[Array, " me"]
    z: Float[Array, " mi"]
    converged: Bool[Array, ""]
    iterations: Int[Array, ""]


def _solve_on_active_set(Q, q, A, b, G, h, guess, tol, box):
    """The QP's solution if the rows ``guess`` (mi,) are exactly its active ones: (w, y, z,
    ok), ok where the answer meets every optimality condition to ``tol`` (row by row, as
    the interior-point method's own test): stationarity, the equations, the dropped rows
    held, the kept rows' multipliers non-negative.

    ``box`` (see :func:`solve_qp`): a kept simple bound fixes its variable, whose
    stationarity row then leaves the linear system and gives the bound's multiplier
    afterwards, so the system has nw + me + (mi - len(box rows)) unknowns, not nw + me + mi
    (11 instead of 20 on the default design: its LU is a third of the cost)."""
    nw, me = Q.shape[0], A.shape[0]
    variables, signs = (
        (np.zeros(0, int), np.zeros(0)) if box is None else (np.asarray(box[0]), np.asarray(box[1], float))
    )
    general = G.shape[0] - variables.shape[0]
    G_rows, h_rows, kept = G[:general], h[:general], guess[:general].astype(Q.dtype)
    kept_bounds = guess[general:].astype(Q.dtype)
    on_variable = np.zeros((variables.shape[0], nw))
    on_variable[np.arange(variables.shape[0]), variables] = 1.0
    count = kept_bounds @ on_variable
    fixed = (count > 0)[:, None]
    # Two kept bounds on one variable: their mean, which the test below accepts only where
    # it is an optimum (the variable's stationarity row then holds with both multipliers 0).
    # A dropped bound may be infinite: kept * inf would be NaN.
    value = jnp.where(kept_bounds > 0, signs * h[general:], 0.0) @ on_variable / jnp.maximum(count, 1.0)
    matrix = jnp.block(
        [
            [jnp.where(fixed, jnp.eye(nw), Q), jnp.where(fixed, 0.0, A.T), jnp.where(fixed, 0.0, G_rows.T)],
            [A, jnp.zeros((me, me + general))],
            # A kept row holds as an equation; a dropped row has no multiplier.
            [kept[:, None] * G_rows, jnp.zeros((general, me)), jnp.diag(1.0 - kept)],
        ]
    )
    solution = jnp.linalg.solve(matrix, jnp.concatenate([jnp.where(fixed[:, 0], value, -q), b, kept * h_rows]))
    w, y, z_rows = jnp.split(solution, [nw, nw + me])
    stationarity = Q @ w + q + A.T @ y + G_rows.T @ z_rows
    z = jnp.concatenate([z_rows, kept_bounds * -signs * stationarity[variables]])
    ok = (
        jnp.all(jnp.isfinite(solution))
        & jnp.all(jnp.abs(Q @ w + q + A.T @ y + G.T @ z) <= tol * (1.0 + jnp.abs(q)))
        & jnp.all(jnp.abs(A @ w - b) <= tol * (1.0 + jnp.abs(b)))
        & jnp.all(G @ w - h <= tol * (1.0 + jnp.abs(h)))
        # A multiplier's sign against the rounding of a solve whose entries reach the
        # largest multiplier (the elastic slacks' 1e6): a dropped row's exact zero comes
        # back as -5e-11 on the default design with a geometry limit beside its field limit.
        & jnp.all(z >= -tol * (1.0 + jnp.max(jnp.abs(z))))
    )
    return w, y, jnp.maximum(z, 0.0), ok


def _interior_point(Q, q, A, b, G, h, needed, tol, max_iterations):
    """Mehrotra's predictor-corrector from a least-squares start: (w, y, z, converged,
    iterations) of :func:`solve_qp`'s QP; no iterations where not ``needed``."""
    nw, me, mi = Q.shape[0], A.shape[0], G.shape[0]

    def residuals(w, y, z, s):
        r_dual = Q @ w + q + A.T @ y + G.T @ z
        return r_dual, A @ w - b, G @ w + s - h

    def newton(w, s, z, r_dual, r_eq, r_ineq, r_comp):
        # The whole (unreduced) Newton system: eliminating ds and dz first would put z / s
        # on the diagonal, which overflows near the end where slacks vanish (NaN steps on
        # hs010 and hs071 of the Hock-Schittkowski tests).
        zeros = jnp.zeros
        matrix = jnp.block(
            [
                [Q, A.T, G.T, zeros((nw, mi))],
                [A, zeros((me, me + 2 * mi))],
                [G, zeros((mi, me + mi)), jnp.eye(mi)],
                [zeros((mi, nw + me)), jnp.diag(s), jnp.diag(z)],
            ]
        )
        step = jnp.linalg.solve(matrix, -jnp.concatenate([r_dual, r_eq, r_ineq, r_comp]))
        return jnp.split(step, [nw, nw + me, nw + me + mi])

    def largest_step(s, z, ds, dz):
        ratios = jnp.concatenate([jnp.where(ds < 0, -s / ds, jnp.inf), jnp.where(dz < 0, -z / dz, jnp.inf)])
        return jnp.minimum(1.0, jnp.min(ratios, initial=jnp.inf))

    def done(state):
        # Each row against its own size: the elastic slacks' costs are 1e6 times the
        # objective's, and a tolerance relative to them would leave the step inexact.
        w, y, z, s, k = state
        r_dual, r_eq, r_ineq = residuals(w, y, z, s)
        small = (
            jnp.all(jnp.abs(r_dual) <= tol * (1.0 + jnp.abs(q)))
            & jnp.all(jnp.abs(r_eq) <= tol * (1.0 + jnp.abs(b)))
            & jnp.all(jnp.abs(r_ineq) <= tol * (1.0 + jnp.abs(h)))
            # s z to tol^2: a multiplier then tells an active row (z of the objective's
            # size) from one that only lies near it (z = tol^2 / s), at any distance s.
            & jnp.all(s * z <= tol * tol)
        )
        return small, k

    def going(state):
        return needed & ~done(state)[0] & (state[4] < max_iterations)

    def body(carry):
        w, y, z, s, k = carry[0]
        r_dual, r_eq, r_ineq = residuals(w, y, z, s)
        mu = jnp.dot(s, z) / mi
        # Predictor (affine scaling), then Mehrotra's centring and second-order correction.
        dw, dy, dz, ds = newton(w, s, z, r_dual, r_eq, r_ineq, s * z)
        alpha = largest_step(s, z, ds, dz)
        sigma = (jnp.dot(s + alpha * ds, z + alpha * dz) / mi / mu) ** 3
        dw, dy, dz, ds = newton(w, s, z, r_dual, r_eq, r_ineq, s * z + ds * dz - sigma * mu)
        alpha = _TO_BOUNDARY * largest_step(s, z, ds, dz)
        state = w + alpha * dw, y + alpha * dy, z + alpha * dz, s + alpha * ds, k + 1
        return state, going(state)

    # Start where the dual and equality residuals vanish (the KKT system with s = -z, as
    # cvxopt does), then shift s and z into the positive orthant: a start at z = 1 takes
    # dozens of iterations to grow multipliers of the elastic slacks' size, or diverges.
    def interior_start():
        matrix = jnp.block([[Q, A.T, G.T], [A, jnp.zeros((me, me + mi))], [G, jnp.zeros((mi, me)), -jnp.eye(mi)]])
        first = jnp.linalg.solve(matrix, jnp.concatenate([-q, b, h]))
        w0, y0, z0 = first[:nw], first[nw : nw + me], first[nw + me :]
        shift = lambda v: v + jnp.maximum(0.0, 1.0 - jnp.min(v, initial=1.0))  # noqa: E731
        return w0, y0, shift(z0), shift(-z0)

    # Whether to go on is decided once, in the body, and carried. A vmapped while loop
    # evaluates its condition twice, in the loop's condition (any lane going on) and in
    # its body (to hold the lanes that stop), and XLA:CPU may compile the two copies with
    # other rounding (jaxlib 0.12.1 with AVX-512 code, 4 or 8 lanes). This test sits at
    # the rounding of stationarity rows whose terms reach the slacks' 1e6, so the copies
    # can disagree: the condition goes on for a lane that the body holds, forever.
    state = (*interior_start(), jnp.asarray(0))
    state, _ = jax.lax.while_loop(lambda carry: carry[1], body, (state, going(state)))
    w, y, z, _, iterations = state
    return w, y, z, done(state)[0], iterations


def solve_qp(Q, q, A, b, G, h, *, guess=None, box=None, tol=1e-12, max_iterations=60) -> QPSolution:
    """Solve the QP above (shapes Q (nw, nw), q (nw,), A (me, nw), b (me,), G (mi, nw),
    h (mi,)); ``A`` must have full row rank and the feasible set must be non-empty and
    bounded in the directions where Q is singular (the design solver's QPs have box rows
    for every variable and elastic slacks, so both hold). ``guess`` (mi,) bool: the rows
    expected to be active (see the module docstring); ``iterations`` is 0 where it was
    right. ``box``: None, or (variables, signs), two static sequences saying that the last
    len(variables) rows of G are simple bounds, signs[k] * w[variables[k]] <= h[k] (signs
    +-1), which the active-set rounds then solve with a smaller system."""
    nw, me, mi = Q.shape[0], A.shape[0], G.shape[0]

    if guess is None:
        return QPSolution(*_interior_point(Q, q, A, b, G, h, jnp.asarray(True), tol, max_iterations))

    def active_set_round(round_state):
        rows, _, _, _, _, k = round_state
        w, y, z, ok = _solve_on_active_set(Q, q, A, b, G, h, rows, tol, box)
        # Next: the kept rows with a positive multiplier, and the dropped rows that are
        # violated. A dropped row's multiplier is zero only up to the solve's rounding
        # (1e-10 beside the slacks' 1e6), and must not bring it back: where its row is
        # parallel to a kept one (two limits on one quantity) the next solve is singular.
        violated = G @ w - h > tol * (1.0 + jnp.abs(h))
        rows = jnp.where(ok, rows, jnp.where(rows, z > 0.0, violated))
        return rows, w, y, z, ok, k + 1

    first_round = (guess, jnp.zeros(nw), jnp.zeros(me), jnp.zeros(mi), jnp.asarray(False), jnp.asarray(0))
    _, w_g, y_g, z_g, guessed, _ = jax.lax.while_loop(
        lambda st: ~st[4] & (st[5] < _ACTIVE_SET_ROUNDS), active_set_round, first_round
    )
    # Inside where_needed, not a lax.cond (under vmap both branches would run, the loop to
    # its end), nor beside it: XLA hoists the interior-point loop's invariant parts (its
    # Newton matrix's blocks) out of the loop, computed at every step in every lane.
    interior = where_needed(
        ~guessed,
        lambda operands: _interior_point(*operands, tol, max_iterations),
        (Q, q, A, b, G, h, ~guessed),
        (jnp.zeros(nw), jnp.zeros(me), jnp.zeros(mi), jnp.asarray(False), jnp.asarray(0)),
    )
    w, y, z = (jnp.where(guessed, a, b) for a, b in ((w_g, interior[0]), (y_g, interior[1]), (z_g, interior[2])))
    return QPSolution(w, y, z, guessed | interior[3], interior[4])
