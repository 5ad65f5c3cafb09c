"""Parts of the design solver checked on their own: the one-trip loop that runs work only
where a vmapped lane needs it, the polish's KKT and feasibility equations and their
derivatives (against plain forward-mode differentiation of the same equations), its
Newton step, the model's evaluations in the solver's loop, the jet the polish hands to the
implicit derivatives and those derivatives against closed forms, the QP's active-set
rounds on a subproblem that once sent a whole batch to the interior-point method, the
polish's linear solver (LU, else SVD) against numpy, and the conditions of the loops of the
vmapped program."""

import importlib

import equinox as eqx
import jax
import jax.extend as jex
import jax.numpy as jnp
import lineax as lx
import numpy as np
import pytest

from magdesign._tracing import checked
from magdesign.design import Limit, Objective, Problem, Target, Variable, solve, sweep
from magdesign.design._linear import LUOrSVD
from magdesign.design._sqp.core import CoreSolution, _core
from magdesign.design._sqp.jet import Jet, _jet, _values, problem_arrays
from magdesign.design._sqp.loop import run
from magdesign.design._sqp.polish import _KKT, _Active, _Feasibility, _linearised, _newton, _newton_step, _polish_at
from magdesign.design._sqp.program import _compiled, _host, _start, _structure, settings_of
from magdesign.design._sqp.search import CONVERGED, NONFINITE_START
from magdesign.design._sqp.sqp import SQP
from magdesign.design._sqp.step import _no_slack_rows, subproblem, subproblem_box
from magdesign.design.status import STATUS_NAMES
from magdesign.design.sweep import with_fixed
from magdesign.spec.design import default_spec, problem_from_spec
from magdesign.units import mm

qp = importlib.import_module("magdesign.design._qp")


def test_where_needed_under_vmap_computes_only_the_needed_lanes():
    x = jnp.arange(6.0)
    needed = jnp.array([True, False, True, False, False, True])
    got = jax.vmap(lambda flag, v: qp.where_needed(flag, lambda a: a**2 + 1.0, v, jnp.asarray(-1.0)))(needed, x)
    np.testing.assert_array_equal(got, np.where(needed, np.arange(6.0) ** 2 + 1.0, -1.0))
    assert qp.where_needed(jnp.asarray(False), lambda a: a + 1.0, jnp.asarray(2.0), jnp.asarray(7.0)) == 7.0


@pytest.mark.parametrize("objective", [True, False])
@pytest.mark.slow
def test_polish_equations_and_their_derivatives_match_plain_forward_mode(objective):
    """A model with curvature in both variables and a fixed input (theta) inside it, with
    one variable on a bound, one limit row held and one not: the KKT equations (with an
    objective) and the feasibility equations (without), whose derivatives in z come from
    the model's jet (Newton's steps) and in theta from the bounds and the model's values
    (and Jacobian) (the implicit derivatives), against plain forward mode of the same
    rows built from the model's values."""

    def model(v):
        a = v["a"]
        return {
            "f": a * v["x"] * v["y"] + v["x"] ** 3,
            "g": v["x"] ** 2 + a * v["y"] ** 2,
            "h": jnp.sin(v["x"] * v["y"]),
        }

    problem = Problem(
        model,
        [Variable("x", -2.0, 2.0), Variable("y", -2.0, 2.0)],
        targets=[Target("g", 1.5)],
        limits=[Limit("h", upper=0.5), Limit("f", lower=-3.0)],
        objective=Objective("f", "min") if objective else None,
        fixed={"a": 1.3},
    )
    theta = jnp.asarray(problem_arrays(problem, np)[4])
    active = _Active(jnp.array([True, False]), jnp.array([False, False]), jnp.array([False, True]))
    held, y_max = jnp.array([True, True, False]), jnp.array([1.0, 1.0])
    if objective:
        equations = _KKT(problem, jnp.asarray(0.7), active, held, y_max)
        z = jnp.array([0.3, 0.6, 0.4, -0.2, 0.9])
    else:
        equations = _Feasibility(problem, active, held, y_max)
        z = jnp.array([0.3, 0.6])

    def plain(z, theta):  # the equations from the model's values and their Jacobian by plain forward mode
        v, outputs = _values(problem, z[:2], theta)
        J = jax.jacfwd(lambda y: _values(problem, y, theta)[0])(z[:2])
        return equations.rows(z, Jet(v, J, jnp.zeros((*J.shape, 2)), outputs))

    jet = _jet(problem, z[:2], theta)
    np.testing.assert_allclose(equations.rows(z, jet), plain(z, theta), rtol=1e-15)
    in_z = jax.vmap(lambda dz: equations.tangent(jet, z, dz), out_axes=1)(jnp.eye(z.size))
    np.testing.assert_allclose(in_z, jax.jacfwd(plain)(z, theta), rtol=1e-13, atol=1e-13)
    # The equations to first order about z, as the implicit derivatives see them: in the
    # root from the jet, in theta through the model's values (and Jacobian) again.
    linearised = lambda root, theta: _linearised(equations, z, jet, jnp.asarray(True), root, theta)  # noqa: E731
    for argnum in (0, 1):
        expected = jax.jacfwd(plain, argnums=argnum)(z, theta)
        np.testing.assert_allclose(jax.jacfwd(linearised, argnums=argnum)(z, theta), expected, rtol=1e-13, atol=1e-13)
        assert np.any(np.asarray(expected) != 0.0), argnum
    # Newton's step from z (optimistix's, as the polish takes it) against numpy's
    # minimum-norm solve with the plain equations' forward-mode Jacobian (singular at
    # this point with an objective, not square without).
    expected = z - np.linalg.pinv(jax.jacfwd(plain)(z, theta), rcond=1e-12) @ plain(z, theta)
    newton = _newton(settings_of(1e-10, 1e-13, 10))
    stepped = _newton_step(equations, newton, _polish_at(equations, z, jet, newton), jet, 10)
    np.testing.assert_allclose(stepped.z, expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(stepped.evaluated, z)
    np.testing.assert_allclose(stepped.newton.f, plain(z, theta), rtol=1e-15)
    assert not bool(stepped.done)


def _r2_problem(model=None):
    """minimise x + 2 y (+ a x^2 through ``model``) on the circle x^2 + y^2 = 2."""
    model = model or (lambda v: {"f": v["x"] + 2.0 * v["y"], "r2": v["x"] ** 2 + v["y"] ** 2})
    return Problem(
        model,
        [Variable("x", -3.0, 3.0, start=-0.9), Variable("y", -3.0, 3.0, start=-1.8)],
        targets=[Target("r2", 2.0)],
        objective=Objective("f", "min"),
    )


@pytest.mark.slow
def test_polish_ends_with_the_residual_and_jet_of_the_point_it_returns():
    """The solver's one loop evaluates the model at the point the search tries, then at
    Newton's iterates, and the polish keeps the residual and the jet (which the implicit
    derivatives use) of the last point it evaluated, which it returns: they must belong
    to that point. Cut to two steps, so that the polish ends off the root and a residual or
    jet from another point would show."""
    problem = _r2_problem()
    feasibility = Problem(problem.model, problem.variables, targets=problem.targets)
    settings = settings_of(1e-10, 1e-13, 2)
    y_max = jnp.array([1.0, 1.0])  # scaled variables: (x + 3) / 6
    y0, theta = jnp.array([0.35, 0.2]), jnp.asarray(problem_arrays(problem, np)[4])
    for p in (problem, feasibility):
        loop = jax.jit(lambda y0: run(p, y0, theta, settings, y_max))(y0)
        polish, search = loop.polish, loop.search
        assert int(search.steps) == 2 and int(polish.newton.step) == 2
        z = polish.evaluated
        y = z[:2]
        # the model at y, by plain forward mode
        v, outputs = _values(p, y, theta)
        J = jax.jacfwd(lambda y: _values(p, y, theta)[0])(y)
        x = -3.0 + 6.0 * y
        if p.objective is not None:
            r = jnp.concatenate([search.weight * J[0] + J[1:].T @ z[2:], v[1:]])
            # f = x + 2 y has no curvature; r2 = x^2 + y^2 in scaled variables: 72 I / 2 (target scale 2)
            np.testing.assert_allclose(polish.jet.H[0], 0.0, atol=1e-12)
            np.testing.assert_allclose(polish.jet.H[1], 36.0 * np.eye(2), rtol=1e-12)
        else:
            r = jnp.concatenate([v[1:], jnp.zeros(2)])
        assert float(jnp.max(jnp.abs(r))) > 1e-9  # two steps from this start: not yet converged
        np.testing.assert_allclose(polish.newton.f, r, rtol=1e-12, atol=1e-15)
        named = dict(zip(p.outputs, np.asarray(polish.jet.outputs)))
        np.testing.assert_allclose(named["r2"], x[0] ** 2 + x[1] ** 2, rtol=1e-14)
        if p.objective is not None:
            np.testing.assert_allclose(named["f"], x[0] + 2.0 * x[1], rtol=1e-14)
        np.testing.assert_allclose(polish.jet.v, v, rtol=1e-12)
        np.testing.assert_allclose(polish.jet.J, J, rtol=1e-12)


@pytest.mark.parametrize("objective", [True, False])
@pytest.mark.slow
def test_the_model_is_evaluated_once_a_trip_and_the_polish_starts_from_the_search_jet(objective):
    """Counted by a callback in the model: the search evaluates it once per step, and the
    polish, whose first Newton step is taken from the search's last jet, once per further
    Newton step (the model at the search's point is not evaluated again)."""
    calls = []

    def model(v):
        jax.debug.callback(lambda: calls.append(1))
        return {"f": v["x"] + 2.0 * v["y"] + v["a"] * v["x"] ** 2, "r2": v["x"] ** 2 + v["y"] ** 2}

    problem = _r2_problem(model)
    problem = Problem(
        model,
        problem.variables,
        targets=problem.targets,
        fixed={"a": 0.1},
        objective=problem.objective if objective else None,
    )
    lower, upper, scale, start, theta = (jnp.asarray(a) for a in problem_arrays(problem, np))
    solved = jax.jit(lambda y0: run(problem, y0, theta, settings_of(1e-10, 1e-13, 100), (upper - lower) / scale))
    jax.block_until_ready(solved((start - lower) / scale))
    calls.clear()
    loop = jax.block_until_ready(solved((start - lower) / scale))
    assert int(loop.search.phase) == CONVERGED
    # with an objective two Newton steps (one evaluation); without, the search's point
    # already solves the feasibility equations, and Newton's first step confirms it
    assert int(loop.polish.newton.step) == (2 if objective else 1)
    assert len(calls) == int(loop.search.steps) + int(loop.polish.newton.step) - 1
    assert solve(problem).status == "successful"


@pytest.mark.slow
def test_lanes_of_a_batch_that_end_on_different_trips_equal_their_own_solves():
    """The solver's loop under vmap: lanes whose search and polish end on different trips
    (different starts and targets), and one where the model is NaN from the start (its
    search accepts no point, so its polish must not step from the search's blank jet: it
    evaluates the model at the start, finds it NaN and stops after one step), each equal
    to the same lane solved alone."""

    def model(v):
        return {"f": v["x"] + 2.0 * v["y"] + 0.1 * v["x"] ** 2, "r2": (v["x"] ** 2 + v["y"] ** 2) * jnp.sqrt(v["b"])}

    problem = _r2_problem(model)
    problem = Problem(model, problem.variables, targets=problem.targets, objective=problem.objective, fixed={"b": 1.0})
    lower, upper, scale, _, theta = problem_arrays(problem, np)
    settings = settings_of(1e-10, 1e-13, 100)
    starts = (np.array([[-0.9, -1.8], [2.5, 2.5], [0.3, -0.2], [-0.9, -1.8]]) - lower) / scale
    thetas = np.array([[2.0, 1.0], [3.0, 1.0], [1.0, 2.0], [2.0, -1.0]])  # (target r2, b); b < 0: NaN
    core = lambda y0, theta: _core(problem, y0, theta, settings)  # noqa: E731
    batched = jax.jit(jax.vmap(core))(jnp.asarray(starts), jnp.asarray(thetas))
    statuses = [STATUS_NAMES[int(k)] for k in batched.status]
    assert statuses == ["successful"] * 3 + ["nonfinite"]
    assert len(set(np.asarray(batched.steps[:3]).tolist())) > 1  # the lanes end on different trips
    one = jax.jit(core)
    for lane in range(4):
        alone = one(jnp.asarray(starts[lane]), jnp.asarray(thetas[lane]))
        for name, got, expected in zip(CoreSolution._fields, batched, alone):
            np.testing.assert_allclose(
                np.asarray(got[lane], float),
                np.asarray(expected, float),
                rtol=1e-12,
                atol=1e-15,
                err_msg=f"lane {lane}: {name}",
            )
    y_max = jnp.asarray((upper - lower) / scale)
    loop = jax.jit(lambda y0, theta: run(problem, y0, theta, settings, y_max))(
        jnp.asarray(starts[3]), jnp.asarray(thetas[3])
    )
    assert int(loop.search.phase) == NONFINITE_START and int(loop.search.steps) == 1
    assert int(loop.polish.newton.step) == 1 and not np.all(np.isfinite(loop.polish.newton.f))
    np.testing.assert_array_equal(loop.polish.evaluated[:2], starts[3])


@pytest.mark.slow
def test_first_qp_with_parallel_limit_rows_needs_no_interior_point_iterations():
    """The default design at outer radius 6 mm and compliance 0.2545 mm/N: its field limit
    and closest-gap limit rows are parallel at the start. A dropped row's multiplier of 1e-10
    (rounding) once brought the second back beside the first, the next solve was singular
    and the QP went to 21 interior-point iterations (in a vmapped sweep, every lane did).
    A 6 mm dome under the default 7.4 mm gap breaks the guards that hold the magnet on its
    dome (embed, reach): the problem leaves them out, as this is about the two parallel rows."""
    problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
    limits = [limit for limit in problem.limits if limit.output not in ("embed", "reach")]
    problem = Problem(problem.model, problem.variables, problem.targets, limits, problem.objective)
    problem = with_fixed(problem, ["mechanics.outer_radius"])
    lower, upper, scale, start, theta = problem_arrays(problem, np)
    theta = theta.copy()
    theta[0], theta[-1] = np.linspace(0.25, 0.4, 100)[5] * mm, 6.0 * mm
    y0, y_max = jnp.asarray((start - lower) / scale), jnp.asarray((upper - lower) / scale)
    jet = _jet(problem, y0, jnp.asarray(theta))
    n, n_targets, m = y0.shape[0], len(problem.targets), jet.v.shape[0] - 1
    parts = subproblem(jet, y0, y_max, jnp.zeros(m), 1.0 / jnp.linalg.norm(jet.J[0]), n_targets, True)
    guess = _no_slack_rows(n, n_targets, m - n_targets)
    reference = qp.solve_qp(*parts)
    assert int(reference.iterations) > 0
    for box in (None, subproblem_box(n, n_targets, m - n_targets)):
        guessed = qp.solve_qp(*parts, guess=guess, box=box)
        assert bool(guessed.converged) and int(guessed.iterations) == 0
        np.testing.assert_allclose(guessed.w, reference.w, rtol=0, atol=1e-9)
        np.testing.assert_allclose(guessed.z, reference.z, rtol=1e-6, atol=1e-6)


@pytest.mark.slow
def test_active_set_rounds_with_simple_bounds_match_the_closed_form():
    """minimise (w0 - 2)^2 + (w1 + 3)^2 + (w2 - 2)^2 subject to w0 + w2 = 1.5,
    w0 / 2 - w1 + w2 <= 1.5 and the box [-1, 1]^3, the box given as simple bounds
    (``box``). By hand: at w = (1, -0.5, 0.5) the gradient is (-2, 5, -3); stationarity
    row by row gives the general row's multiplier 5, the equation's -2 and w0 <= 1's 1.5,
    the other bounds' 0: a KKT point of a convex QP, so its minimum. The fixed variable w0
    appears in the equation and the general row, so each of their terms in the bound's
    multiplier counts. Batched (vmap) over every guess of one or two rows, none and all:
    each ends at the minimum; the right guess without interior-point iterations (with a
    wrong multiplier the optimality test would reject it, and the rounds would cycle into
    that method), also with an infinite bound among the dropped rows."""
    Q, q = 2.0 * jnp.eye(3), jnp.array([-4.0, 6.0, -4.0])
    A, b = jnp.array([[1.0, 0.0, 1.0]]), jnp.array([1.5])
    G = jnp.concatenate([jnp.array([[0.5, -1.0, 1.0]]), jnp.eye(3), -jnp.eye(3)])
    h = jnp.array([1.5, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    box = (np.array([0, 1, 2, 0, 1, 2]), np.array([1.0, 1.0, 1.0, -1.0, -1.0, -1.0]))
    expected_w, expected_y = np.array([1.0, -0.5, 0.5]), np.array([-2.0])
    expected_z = np.array([5.0, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0])
    right = expected_z > 0
    rows = np.eye(7, dtype=bool)
    guesses = np.stack([np.zeros(7, bool), np.ones(7, bool)] + [rows[i] | rows[j] for i in range(7) for j in range(7)])
    solve = jax.jit(jax.vmap(lambda guess, h: qp.solve_qp(Q, q, A, b, G, h, guess=guess, box=box), in_axes=(0, None)))
    solution = solve(jnp.asarray(guesses), h)
    assert np.all(solution.converged)
    np.testing.assert_allclose(solution.w, np.broadcast_to(expected_w, (len(guesses), 3)), rtol=0, atol=1e-9)
    np.testing.assert_allclose(solution.y, np.broadcast_to(expected_y, (len(guesses), 1)), rtol=0, atol=1e-8)
    np.testing.assert_allclose(solution.z, np.broadcast_to(expected_z, (len(guesses), 7)), rtol=0, atol=1e-8)
    iterations = np.asarray(solution.iterations)
    assert iterations[np.all(guesses == right, axis=1)].tolist() == [0, 0]  # rows (0, 1) and (1, 0)
    unbounded_below = solve(jnp.asarray(right[None]), h.at[5].set(jnp.inf))
    assert int(unbounded_below.iterations[0]) == 0
    np.testing.assert_allclose(unbounded_below.w[0], expected_w, rtol=0, atol=1e-12)
    np.testing.assert_allclose(unbounded_below.z[0], np.where(np.arange(7) == 5, 0.0, expected_z), rtol=0, atol=1e-12)


def _solve_with(solver, matrix, vector):
    return np.asarray(lx.linear_solve(lx.MatrixLinearOperator(jnp.asarray(matrix)), jnp.asarray(vector), solver).value)


def _takes_lu(matrix):
    (_, _, well, _), _, _ = LUOrSVD().init(lx.MatrixLinearOperator(jnp.asarray(matrix)), {})
    return bool(well)


def test_polish_linear_solver_agrees_with_numpy_on_regular_singular_and_nonsquare_systems():
    """LU where the matrix is regular; where it is singular (a degenerate active set), badly
    scaled so that its LU's pivots look regular, or not square, the minimum-norm
    least-squares answer (numpy's lstsq), never LU's NaN or an arbitrary member of the
    solutions; each also batched, one member singular."""
    rng = np.random.default_rng(3)
    regular = rng.normal(size=(5, 5)) + 5 * np.eye(5)
    # rank 3: two rows repeat others, the right side consistent with them
    singular = rng.normal(size=(5, 5))
    singular[3], singular[4] = singular[0], singular[1] + singular[2]
    # condition 1e20 with pivots 1 and 1: numerically of rank 1
    scaled = np.array([[1.0, 1e10], [0.0, 1.0]])
    wide = rng.normal(size=(3, 5))
    vector = rng.normal(size=5)
    consistent = singular @ rng.normal(size=5)
    assert _takes_lu(regular) and not _takes_lu(singular) and not _takes_lu(scaled)
    cases = (
        (regular, vector),
        (singular, consistent),
        (singular, vector),
        (scaled, vector[:2]),
        (wide, vector[:3]),
        (wide.T, vector),
    )
    for matrix, b in cases:
        expected = np.linalg.lstsq(matrix, b, rcond=None)[0]
        np.testing.assert_allclose(_solve_with(LUOrSVD(), matrix, b), expected, rtol=1e-9, atol=1e-12)
    batched = jax.vmap(lambda m, b: lx.linear_solve(lx.MatrixLinearOperator(m), b, LUOrSVD()).value)(
        jnp.stack([regular, singular]), jnp.stack([vector, consistent])
    )
    np.testing.assert_allclose(batched[0], np.linalg.solve(regular, vector), rtol=1e-10)
    np.testing.assert_allclose(batched[1], np.linalg.lstsq(singular, consistent, rcond=None)[0], rtol=1e-9, atol=1e-12)
    # a non-finite right side or matrix (the latter sent to the SVD) is NaN, not an error,
    # where the caller asks for no errors; in a batch, the other members are unharmed
    nonfinite = jax.jit(
        jax.vmap(lambda m, b: lx.linear_solve(lx.MatrixLinearOperator(m), b, LUOrSVD(), throw=False).value)
    )
    broken = regular.copy()
    broken[1, 2] = np.nan
    got = nonfinite(jnp.stack([regular, regular, broken]), jnp.stack([jnp.full(5, jnp.nan), vector, vector]))
    assert np.all(np.isnan(got[0])) and np.all(np.isnan(got[2]))
    np.testing.assert_allclose(got[1], np.linalg.solve(regular, vector), rtol=1e-10)


def test_polish_linear_solver_transposes_for_reverse_mode():
    """Reverse mode solves with the transposed matrix (the solver's ``transpose``): the
    gradient of sum(A^-1 b) in b is A^-T 1, for a regular, a singular (pseudo-inverse) and
    a wide A."""
    rng = np.random.default_rng(4)
    regular = rng.normal(size=(4, 4)) + 4 * np.eye(4)
    singular = regular.copy()
    singular[3] = singular[0] - singular[1]
    wide = rng.normal(size=(3, 4))
    for matrix in (regular, singular, wide):
        gradient = jax.grad(
            lambda b: jnp.sum(lx.linear_solve(lx.MatrixLinearOperator(jnp.asarray(matrix)), b, LUOrSVD()).value)
        )(jnp.ones(matrix.shape[0]))
        np.testing.assert_allclose(gradient, np.linalg.pinv(matrix).T @ np.ones(matrix.shape[1]), rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("objective", [Objective("f", "min"), None])
@pytest.mark.slow
def test_the_model_is_traced_once_for_a_solve_and_a_sweep(objective):
    """The search, the polish (its Newton steps, optimistix's shape checks, the implicit
    derivatives in theta) and a batch all use the model or its derivatives: JAX transforms
    one trace of the model instead of tracing it again at each place (four times before,
    with an objective; a feasibility problem's polish alike)."""
    calls = []

    def model(v):
        calls.append(1)
        return {"f": (v["x"] - 0.3) ** 2 + v["a"] * v["y"] ** 2, "g": v["x"] + v["y"], "h": v["x"] - v["y"]}

    targets = [Target("g", 0.5)] + ([] if objective else [Target("h", 0.3)])
    problem = Problem(
        model,
        [Variable("x", -1.0, 1.0), Variable("y", -1.0, 1.0)],
        targets=targets,
        objective=objective,
        fixed={"a": 2.0},
    )
    result = solve(problem)
    assert result.status == "successful"
    # with the objective: x - 0.3 = 2 y (stationarity) and x + y = 0.5; without: x + y = 0.5, x - y = 0.3
    expected = [13 / 30, 1 / 15] if objective else [0.4, 0.1]
    np.testing.assert_allclose([result.parameters["x"], result.parameters["y"]], expected, atol=1e-9)
    assert len(calls) == 1
    batch = sweep(problem, {"g": [0.2, 0.5]})
    assert np.all(batch.successful)
    assert len(calls) == 1


def _raising_problem(check):
    def model(v):
        return {"f": check(v["x"] ** 2, v["x"] > 0.5, "x above 0.5"), "g": v["x"]}

    problem = Problem(model, [Variable("x", -1.0, 1.0)], targets=[Target("g", 0.8)], objective=Objective("f", "min"))
    return problem, jnp.asarray([0.9]), jnp.asarray(problem_arrays(problem, np)[4])


@pytest.mark.parametrize("solve_first", [False, True])
@pytest.mark.slow
def test_a_model_traced_outside_the_solver_keeps_raising_its_errors_and_inside_gives_a_status(solve_first):
    """The solver traces the library's checks (``checked``, as a saturating soft part's)
    as NaN, reported as a status; a plain call raises; neither reuses the other's trace,
    whichever comes first."""
    problem, y0, theta = _raising_problem(checked)
    for step in ("solve", "plain", "solve") if solve_first else ("plain", "solve", "plain"):
        if step == "solve":
            # the NaN beyond x = 0.5 stops the search short of the target: a status, no exception
            assert solve(problem).status == "infeasible_target"
        else:
            with pytest.raises(Exception, match="x above 0.5"):
                jax.block_until_ready(_jet(problem, y0, theta))


def test_a_models_own_runtime_error_reaches_the_user():
    """A model's own equinox check that fails during a solve stops it with the model's
    message: the solver does not turn a model's error into a number or a status."""
    problem, _, _ = _raising_problem(eqx.error_if)
    with pytest.raises(Exception, match="x above 0.5"):
        solve(problem)


@pytest.mark.parametrize("fixed_input", [True, False])
@pytest.mark.slow
def test_implicit_derivatives_from_the_polished_jet_match_the_closed_form(fixed_input):
    """The optimum's derivatives, from the polish's last jet (in the variables) and the
    rows' dependence on theta (through the model where it has a fixed input).
    With a fixed input a: minimise (x - sin a)^2 + 2 y^2 with x + y = t, whose optimum is
    x = (2 t + sin a) / 3, y = (t - sin a) / 3: the derivatives in a need the model's mixed
    derivative. Without: minimise (x - 2)^2 + (y - 1)^2 with x + y <= u active,
    x = 2 - (3 - u) / 2, y = 1 - (3 - u) / 2."""
    variables = [Variable("x", -3.0, 3.0, start=0.1), Variable("y", -3.0, 3.0, start=0.2)]
    if fixed_input:
        a, t = 0.7, 1.1
        problem = Problem(
            lambda v: {"f": (v["x"] - jnp.sin(v["a"])) ** 2 + 2.0 * v["y"] ** 2, "s": v["x"] + v["y"]},
            variables,
            targets=[Target("s", t)],
            objective=Objective("f", "min"),
            fixed={"a": a},
        )
        expected = {"s": {"x": 2 / 3, "y": 1 / 3}, "a": {"x": np.cos(a) / 3, "y": -np.cos(a) / 3}}
        optimum = {"x": (2 * t + np.sin(a)) / 3, "y": (t - np.sin(a)) / 3}
    else:
        u = 1.4
        problem = Problem(
            lambda v: {"f": (v["x"] - 2.0) ** 2 + (v["y"] - 1.0) ** 2, "s": v["x"] + v["y"]},
            variables,
            limits=[Limit("s", upper=u)],
            objective=Objective("f", "min"),
        )
        expected = {"s.upper": {"x": 0.5, "y": 0.5}}
        optimum = {"x": 2 - (3 - u) / 2, "y": 1 - (3 - u) / 2}
    result = solve(problem)
    assert result.status == "successful"
    for name, value in optimum.items():
        assert result.parameters[name] == pytest.approx(value, rel=1e-9)
    for key, row in expected.items():
        for name, value in row.items():
            assert result.derivatives[key][name] == pytest.approx(value, rel=1e-9), (key, name)


@pytest.mark.slow
def test_the_solver_takes_its_thresholds_from_the_sqp_it_is_given():
    """min (x - 0.5)^2 - (y - 0.5)^2 on [0, 1]^2 from (0.8, 0.5): the gradient has no y
    part on the line y = 0.5, so the steps reach the saddle (0.5, 0.5) (curvature -2 along
    y); the search leaves it along y and ends on a bound of y (f = -0.25, a minimum on the
    box). With ``SQP(escapes=0)`` it may not leave, and the saddle is "not_a_minimum".
    Thresholds that only the host reads for batches key no program of their own."""
    problem = Problem(
        lambda p: {"f": (p["x"] - 0.5) ** 2 - (p["y"] - 0.5) ** 2},
        [Variable("x", 0.0, 1.0, start=0.8), Variable("y", 0.0, 1.0, start=0.5)],
        objective=Objective("f", "min"),
    )
    left = solve(problem)
    assert left.status == "successful"
    assert left.parameters["x"] == pytest.approx(0.5, abs=1e-9)
    assert min(left.parameters["y"], 1.0 - left.parameters["y"]) == pytest.approx(0.0, abs=1e-12)
    assert solve(problem, solver=SQP(escapes=0)).status == "not_a_minimum"
    key = lambda sqp: _structure(problem, settings_of(1e-10, 1e-13, 100, sqp))[0]  # noqa: E731
    assert key(SQP(point_seconds=0.0, chain=2)) == key(SQP())
    assert key(SQP(escapes=0)) != key(SQP())


def test_the_solvers_program_calls_no_python():
    """The default design's compiled core holds no host callback (an equinox runtime check
    is one): JAX's persistent cache keeps no program that calls back to Python, and the
    command would compile the solver afresh on every run. Traced here outside
    ``errors_as_nan``, so that a library's own check would show."""
    problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
    settings = settings_of(1e-8, 1e-8, 20)
    key, arrays = _structure(problem, settings)
    host = _host(problem)
    text = _compiled(key, False).lower(arrays, _start(problem, None, host.arrays), host.arrays[4]).as_text()
    assert "callback" not in text


# Primitives that compute their result exactly (no rounding): comparisons, logic, exact
# reductions, moves, and calls into nested programs (whose own primitives are checked).
_EXACT = {
    "abs", "and", "or", "not", "eq", "ne", "lt", "le", "gt", "ge", "is_finite", "neg",
    "argmax", "argmin", "reduce_max", "reduce_min", "reduce_or", "reduce_and", "max", "min",
    "broadcast_in_dim", "concatenate", "convert_element_type", "select_n", "squeeze", "reshape",
    "slice", "dynamic_slice", "transpose", "copy", "iota", "stack", "pjit", "jit", "closed_call",
}  # fmt: skip


def _nested(eqn):
    """The jaxprs inside an equation's parameters (a loop's, a branch's, a call's)."""
    for value in eqn.params.values():
        for item in value if isinstance(value, (tuple, list)) else [value]:
            if isinstance(item, jex.core.ClosedJaxpr):
                yield item.jaxpr
            elif isinstance(item, jex.core.Jaxpr):
                yield item


def _primitives(jaxpr):
    return {eqn.primitive.name for eqn in jaxpr.eqns}.union(*(_primitives(j) for e in jaxpr.eqns for j in _nested(e)))


def _loop_conditions(jaxpr):
    for eqn in jaxpr.eqns:
        if eqn.primitive.name == "while":
            yield eqn.params["cond_jaxpr"].jaxpr
        for inner in _nested(eqn):
            yield from _loop_conditions(inner)


def test_loop_conditions_of_the_vmapped_design_program_do_not_round():
    """vmap evaluates a while loop's condition twice, in the loop's condition (whether any
    lane goes on) and in its body (which lanes it holds), and XLA may compile the two copies
    with other rounding (jaxlib 0.12.1 on AVX-512 did): a condition that rounds can then go
    on for a lane that the body holds, forever. The conditions of the batched default
    design's loops only compare, combine flags and take exact maxima: what rounds is
    decided in the bodies and carried."""
    problem, _ = problem_from_spec(default_spec(), fidelity="reissner")
    lower, upper, scale, start, theta = problem_arrays(problem, np)
    starts, thetas = np.stack([(start - lower) / scale] * 3), np.stack([theta] * 3)
    settings = settings_of(1e-10, 1e-13, 100)
    program = jax.make_jaxpr(jax.vmap(lambda y0, t: _core(problem, y0, t, settings)))(starts, thetas)
    conditions = list(_loop_conditions(program.jaxpr))
    assert len(conditions) >= 5  # the solver's loop, the settled step's, the QP's three, ...
    for condition in conditions:
        assert _primitives(condition) <= _EXACT, _primitives(condition) - _EXACT
