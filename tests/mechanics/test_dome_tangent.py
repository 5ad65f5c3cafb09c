"""The axisymmetric dome's tangent and its block factor, against jax.hessian and numpy.

The Newton solves and the implicit derivatives of the dome rest on two pieces checked here
directly: the assembled Hessian (from the densities' derivatives) against ``jax.hessian``
of the total potential, and the block tridiagonal factor with its border (the plate
travel) against numpy's dense solve of the same matrix.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from magdesign.mechanics import MooneyRivlin, _axisymmetric, _blocks
from magdesign.mechanics._axisymmetric.equilibrium import DOME_LEVENBERG_START
from magdesign.mechanics.materials import excess_invariants

RESIN = MooneyRivlin(c10=0.1182e6, c01=0.1769e6)
PARAMS = (jnp.asarray(8e-3), jnp.asarray(2e-3), RESIN)
# jitted: the mesh and the layout are static index tables
derivatives = jax.jit(_axisymmetric.derivatives, static_argnums=0)
gradient_alone = jax.jit(functools.partial(_axisymmetric.derivatives, with_hessian=False), static_argnums=0)
hessian = jax.jit(jax.hessian(_axisymmetric.potential, argnums=1), static_argnums=0)
gradient = jax.jit(jax.grad(_axisymmetric.potential, argnums=1), static_argnums=0)
factor = jax.jit(_blocks.factor, static_argnums=0)
factor_blocks = jax.jit(_blocks.factor_blocks, static_argnums=0)
solve = jax.jit(_blocks.solve, static_argnums=0)


def pressed_state(mesh, amplitude=1e-9):
    """The plate 0.2 mm into the undeformed wall, the displacements perturbed by
    ``amplitude`` (m) at random: a positive definite tangent with the travel coupled to
    the outer surface. (A deformed state that is not an equilibrium can have an
    indefinite tangent: the nearly incompressible wall's pressure.)"""
    rng = np.random.default_rng(1)
    return jnp.asarray(np.append(amplitude * rng.standard_normal(mesh.n_dof) * mesh.free_u, 0.2e-3))


@pytest.mark.parametrize("scale", [1e-4, 1e-2, 0.2])
def test_axisymmetric_invariants_equal_the_general_ones(scale):
    # the axisymmetric kinematics' invariants (zero entries of H left out) against the
    # general 3 x 3 ones and against their definitions through C = F^T F
    H5 = np.random.default_rng(3).uniform(-scale, scale, size=(50, 5))
    mine = np.array(jax.vmap(lambda h: jnp.stack(_axisymmetric._excess(h)))(H5))

    def general(h):
        a, b, c, e, hoop = h
        return jnp.stack(excess_invariants([[a, b, 0.0], [c, e, 0.0], [0.0, 0.0, hoop]]))

    np.testing.assert_allclose(mine, np.array(jax.vmap(general)(H5)), rtol=1e-9 / scale, atol=0)
    if scale >= 1e-2:  # the definitions lose digits to cancellation at small strains
        F = np.zeros((50, 3, 3))
        F[:, :2, :2] = np.eye(2) + H5[:, :4].reshape(50, 2, 2)
        F[:, 2, 2] = 1 + H5[:, 4]
        C = np.einsum("nki,nkj->nij", F, F)
        J = np.linalg.det(F)
        I1 = np.trace(C, axis1=1, axis2=2)
        I2 = 0.5 * (I1**2 - np.einsum("nij,nji->n", C, C))
        reference = np.stack([J ** (-2 / 3) * I1 - 3, J ** (-4 / 3) * I2 - 3, J - 1], axis=-1)
        np.testing.assert_allclose(mine, reference, rtol=1e-10 / scale**2, atol=0)


@pytest.mark.parametrize("shape", [(1, 4), (2, 6)])
@pytest.mark.slow
def test_assembled_hessian_equals_jax_hessian_of_the_potential(shape):
    mesh = _axisymmetric.Mesh(*shape, "bonded")
    y = pressed_state(mesh, amplitude=1e-5)
    g, H = derivatives(mesh, y, PARAMS)
    free = np.append(mesh.free_u, 1.0)
    g_ref = free * gradient(mesh, y, PARAMS)
    H_ref = free[:, None] * np.asarray(hessian(mesh, y, PARAMS)) * free[None, :]
    np.testing.assert_allclose(g, g_ref, rtol=0, atol=1e-12 * np.max(np.abs(g_ref)))
    g_alone, none = gradient_alone(mesh, y, PARAMS)
    assert none is None
    np.testing.assert_allclose(g_alone, g_ref, rtol=0, atol=1e-12 * np.max(np.abs(g_ref)))
    np.testing.assert_allclose(H.dense(mesh.layout), H_ref, rtol=0, atol=1e-11 * np.max(np.abs(H_ref)))
    # what the solver reads of the blocks, against the same matrix
    np.testing.assert_allclose(
        H.diagonal_entries(mesh.layout), np.diag(H_ref), rtol=0, atol=1e-11 * np.max(np.abs(H_ref))
    )
    np.testing.assert_allclose(H.last_column(mesh.layout), H_ref[:, -1], rtol=0, atol=1e-11 * np.max(np.abs(H_ref)))
    for force_control in (False, True):
        mask = mesh.mask(force_control)
        M_ref = mask[:, None] * H_ref * mask[None, :] + np.diag(1 - mask)
        M = H.restricted(mesh.layout, jnp.asarray(mask)).dense(mesh.layout)
        np.testing.assert_allclose(M, M_ref, rtol=0, atol=1e-11 * np.max(np.abs(H_ref)))


@pytest.mark.parametrize("shape", [(1, 12), (2, 16), (3, 5)])
@pytest.mark.parametrize("force_control", [False, True])
@pytest.mark.slow
def test_block_factor_solves_as_numpy_does(shape, force_control):
    mesh = _axisymmetric.Mesh(*shape, "bonded")
    _, H = derivatives(mesh, pressed_state(mesh), PARAMS)
    restricted = H.restricted(mesh.layout, jnp.asarray(mesh.mask(force_control)))
    M = restricted.dense(mesh.layout)
    rhs = np.random.default_rng(2).standard_normal(mesh.size)
    F = factor_blocks(mesh.layout, restricted)
    assert bool(F.finite())
    if force_control:
        assert np.max(np.abs(M[:-1, -1])) > 0  # the border is used
    x = solve(mesh.layout, F, jnp.asarray(rhs))
    x_ref = np.linalg.solve(np.asarray(M), rhs)
    np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-9 * np.max(np.abs(x_ref)))


def test_block_factor_flags_matrices_that_are_not_positive_definite():
    mesh = _axisymmetric.Mesh(2, 6, "bonded")
    _, H = derivatives(mesh, pressed_state(mesh), PARAMS)
    M = H.restricted(mesh.layout, jnp.asarray(mesh.mask(True))).dense(mesh.layout)
    assert bool(factor(mesh.layout, M).finite())
    # a negative pivot in the displacements' blocks
    assert not bool(factor(mesh.layout, M.at[40, 40].set(-1.0)).finite())
    # positive definite displacements, but the travel's Schur complement negative
    assert not bool(factor(mesh.layout, M.at[-1, -1].set(0.0)).finite())
    assert np.linalg.eigvalsh(np.asarray(M.at[-1, -1].set(0.0)))[0] < 0


@pytest.mark.parametrize("resume", [1, 3, 11])
@pytest.mark.slow
def test_levenberg_shift_is_the_smallest_tried_that_makes_the_tangent_definite(resume):
    """Tried: no shift, then the shifts from index ``resume`` on (Newton resumes where its
    last shifted factor needed one); the chosen shift and its index against numpy's
    eigenvalues of each shifted matrix (the indefinite one needs index 9 at least: from
    11 on, the first tried)."""
    mesh = _axisymmetric.Mesh(2, 6, "bonded")
    _, H = derivatives(mesh, pressed_state(mesh), PARAMS)
    definite = H.restricted(mesh.layout, jnp.asarray(mesh.mask(True))).dense(mesh.layout)
    matrices = jnp.stack([definite, definite.at[40, 40].set(-1e-3 * definite[40, 40])])
    rhs = np.random.default_rng(3).standard_normal(mesh.size)

    def shifted_solve(M):
        F, index = _axisymmetric._factor(mesh, _blocks.blocks(mesh.layout, M), resume)
        return _blocks.solve(mesh.layout, F, jnp.asarray(rhs)), index

    one_by_one = [jax.jit(shifted_solve)(M) for M in matrices]
    batched = jax.jit(jax.vmap(shifted_solve))(matrices)  # lanes with and without a shift
    chosen = []
    for M, (x, index), x_batched, index_batched in zip(np.asarray(matrices), one_by_one, *batched):
        diagonal = np.abs(np.diag(M))  # Marquardt's scaling, floored
        scale = DOME_LEVENBERG_START * np.maximum(diagonal, DOME_LEVENBERG_START * diagonal.max())
        tried = [0] + list(range(resume, _axisymmetric.LEVENBERG_MAX + 1))
        shifts = [0.0 * scale if k == 0 else scale * 10.0 ** (k - 1) for k in tried]
        positive = [np.linalg.eigvalsh(M + np.diag(s))[0] > 0 for s in shifts]
        chosen.append(tried[positive.index(True)])
        assert int(index) == int(index_batched) == chosen[-1]
        x_ref = np.linalg.solve(M + np.diag(shifts[positive.index(True)]), rhs)
        np.testing.assert_allclose(x, x_ref, rtol=0, atol=1e-9 * np.max(np.abs(x_ref)))
        np.testing.assert_allclose(x_batched, x_ref, rtol=0, atol=1e-9 * np.max(np.abs(x_ref)))
    assert chosen[0] == 0 and chosen[1] >= resume


@pytest.mark.parametrize("force_control", [False, True])
@pytest.mark.slow
def test_second_order_rule_equals_jax_differentiating_the_first_order_formula(force_control):
    # state_tangent's own JVP rule against JAX's plain forward mode through the
    # first-order formula (its solve differentiated through the matvec), with every
    # tangent non-zero: the state's, the parameters', and those of params_dot and value_dot
    mesh = _axisymmetric.Mesh(1, 4, "bonded")
    y = pressed_state(mesh, amplitude=1e-5)
    rng = np.random.default_rng(4)
    y_q = jnp.asarray(rng.standard_normal(mesh.size) * 1e-6 * np.append(mesh.free_u, 1.0))
    params_dot = (jnp.asarray(1.0), jnp.asarray(0.5), MooneyRivlin(c10=0.3, c01=0.2))
    params_q = (jnp.asarray(-0.4), jnp.asarray(1.0), MooneyRivlin(c10=0.1, c01=0.25))
    params_dot_q = (jnp.asarray(0.2), jnp.asarray(-0.7), MooneyRivlin(c10=0.05, c01=0.1))
    primals = (PARAMS, y, params_dot, jnp.asarray(0.3))
    tangents = (params_q, y_q, params_dot_q, jnp.asarray(-1.7))

    def rule(*a):
        return _axisymmetric.state_tangent(mesh, force_control, *a)

    def plain(*a):
        return _axisymmetric._first_order(mesh, force_control, *a)[0]

    dy, d_dy = jax.jit(lambda p, t: jax.jvp(rule, p, t))(primals, tangents)
    dy_ref, d_dy_ref = jax.jit(lambda p, t: jax.jvp(plain, p, t))(primals, tangents)
    np.testing.assert_allclose(dy, dy_ref, rtol=0, atol=1e-12 * np.max(np.abs(dy_ref)))
    np.testing.assert_allclose(d_dy, d_dy_ref, rtol=0, atol=1e-10 * np.max(np.abs(d_dy_ref)))
    assert np.max(np.abs(d_dy_ref)) > 0
