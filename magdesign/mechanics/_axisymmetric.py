"""Finite-strain axisymmetric model of a thick hemispherical dome pressed by a flat plate.

Geometry and mesh. The wall (radii R_o - t .. R_o, apex on the axis, base rim on z = 0) is
meshed in the meridian section with 9-node quadratic quadrilaterals on a polar grid:
``n_wall`` elements through the wall (radius rho) and ``n_meridian`` along the meridian
(polar angle phi from 0 at the apex to pi / 2 at the base), nodes on arcs. Node (i, j)
sits at phi_i, rho_j; its unknowns are the displacements (u_r, u_z) (m).

Kinematics. F = [[dr/dR, dr/dZ, 0], [dz/dR, dz/dZ, 0], [0, 0, (R + u_r) / R]] in
(r, z, theta) order, evaluated at 3 x 3 Gauss points, which never lie on the axis. The
nodes of the apex row lie on the axis: their u_r is held at 0 (symmetry).

Volumetric locking. The energy is split as W(F) = W(J^(-1/3) F) + W(J^(1/3) I) (exact for
the decoupled laws of :mod:`materials`: isochoric part plus U(J)). The isochoric part is
integrated at the 3 x 3 points; the volumetric part uses Jbar, the L2 projection (over the
element's ring volume) of J onto the linear fields {1, xi, eta} of the element: the
energy form of the Q9/P3 mixed element (discontinuous linear pressure, inf-sup stable),
without spurious pressure or hourglass modes.

Contact. A rigid frictionless plate at z = R_o - d (d the plate travel, m) and the outer
surface: penalty energy (kappa / 2) ramp(g)^2 per reference area of the outer surface at
3 Gauss points per element edge, g = z + u_z - (R_o - d) the penetration, ramp a softplus
smoothed max(g, 0) (so that design derivatives are continuous), kappa = CONTACT_PENALTY
mu / t.

Solution. Pi(U, d) = elastic + contact energy, minimised over the free displacements by
Newton's method with the exact tangent (element Hessians by ``jax.hessian``, assembled
into a dense matrix: a few hundred unknowns), a Levenberg shift where that matrix is not
positive definite and a backtracking line search on Pi, inside ``lax.while_loop``. A load
path in plate travel (displacement control, warm starts, secant predictor) is followed by
a force-controlled solve (d an unknown, Pi - F d minimised), whose result is differentiated
implicitly (a custom JVP solving with the same tangent), so derivatives with respect to
geometry, material and force are exact whatever the iterations did, in forward and
reverse mode and to any order.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from magdesign._numerics import (
    CONTACT_SMOOTHING,
    DOME_LEVENBERG_START,
    DOME_LINE_SEARCH_SLACK,
    DOME_NEWTON_TOL,
    safe_div,
    smooth_ramp,
)

# Penalty stiffness of the contact, kappa t / mu. The penetration it leaves is about
# p t / (CONTACT_PENALTY mu), p ~ 0.3 mu the contact pressure of a dome: 0.03 % of the wall,
# less than 0.01 % of the plate travel; stiffer penalties only slow Newton down.
CONTACT_PENALTY = 1000.0
# Newton iterations per solve at most (a solve that hits it reports converged = False).
NEWTON_MAX_ITER = 60
# Halvings of the step of one line search at most, and the Armijo fraction of the
# predicted decrease that a step must achieve.
LINE_SEARCH_MAX = 30
ARMIJO = 0.25
# Levenberg shifts tried per iteration at most (each ten times the previous one).
LEVENBERG_MAX = 12

_GAUSS3 = np.polynomial.legendre.leggauss(3)


def _lagrange(x):
    """Quadratic Lagrange basis at nodes -1, 0, 1 and its derivative, each (n, 3)."""
    x = np.asarray(x, dtype=float)[:, None]
    values = np.concatenate([x * (x - 1) / 2, 1 - x**2, x * (x + 1) / 2], axis=-1)
    slopes = np.concatenate([x - 0.5, -2 * x, x + 0.5], axis=-1)
    return values, slopes


def _quadrature():
    """3 x 3 Gauss rule: shape functions N (9 points, 9 nodes), derivatives
    dN (9 points, 2, 9 nodes), weights (9,), linear pressure basis P (9 points, 3);
    and the edge rule: N (3, 3), dN/dxi (3, 3), weights (3,)."""
    points, weights = _GAUSS3
    xi, eta = (a.ravel() for a in np.meshgrid(points, points, indexing="ij"))
    lx, dlx = _lagrange(xi)
    ly, dly = _lagrange(eta)
    N = (lx[:, :, None] * ly[:, None, :]).reshape(9, 9)
    dN = np.stack(
        [(dlx[:, :, None] * ly[:, None, :]).reshape(9, 9), (lx[:, :, None] * dly[:, None, :]).reshape(9, 9)],
        axis=1,
    )
    w = np.outer(weights, weights).ravel()
    P = np.stack([np.ones_like(xi), xi, eta], axis=-1)
    edge_N, edge_dN = _lagrange(points)
    return N, dN, w, P, edge_N, edge_dN, weights


_N, _DN, _W, _P, _EDGE_N, _EDGE_DN, _EDGE_W = _quadrature()


class Mesh:
    """Static index tables of an (n_wall, n_meridian) mesh with a base condition.

    Nodes form a grid of rows i = 0 .. 2 n_meridian (apex to base) and columns
    j = 0 .. 2 n_wall (inner to outer surface). The state vector y (n_dof + 1,) holds the
    nodal displacements (node (i, j) at 2 (i cols + j), u_r then u_z) and, last, the
    plate travel d (m).
    """

    def __init__(self, n_wall: int, n_meridian: int, base: str):
        self.n_wall, self.n_meridian = n_wall, n_meridian
        self.rows, self.cols = 2 * n_meridian + 1, 2 * n_wall + 1
        self.n_dof = 2 * self.rows * self.cols
        node = np.arange(self.rows * self.cols).reshape(self.rows, self.cols)
        a, b = np.arange(n_meridian), np.arange(n_wall)
        rows = 2 * a[:, None, None, None] + np.arange(3)[:, None]  # (n_mer, 1, 3, 1)
        cols = 2 * b[None, :, None, None] + np.arange(3)[None, :]  # (1, n_wall, 1, 3)
        elem_nodes = node[rows, cols].reshape(n_meridian * n_wall, 9)
        self.elem_nodes = elem_nodes  # (n_elem, 9), local node (a, b) at 3 a + b
        self.elem_dofs = (2 * elem_nodes[:, :, None] + np.arange(2)).reshape(-1, 18)
        self.edge_rows = 2 * a[:, None] + np.arange(3)  # (n_mer, 3) rows of outer edges
        self.edge_nodes = node[:, -1][self.edge_rows]  # (n_mer, 3)
        self.outer_z_dofs = 2 * node[:, -1] + 1  # (rows,)
        free = np.ones((self.rows, self.cols, 2))
        free[0, :, 0] = 0.0  # apex row, on the axis: u_r = 0 by symmetry
        free[-1, :, 1] = 0.0  # base rim on z = 0
        if base == "bonded":
            free[-1, :, 0] = 0.0
        self.free_u = free.ravel()

    def mask(self, force_control: bool) -> np.ndarray:
        """1 for the unknowns of a solve, 0 for held values: (n_dof + 1,)."""
        return np.append(self.free_u, 1.0 if force_control else 0.0)

    def reference(self, outer_radius, thickness):
        """Reference nodal coordinates (rows cols, 2): (R, Z) in m."""
        rho = outer_radius - thickness + thickness * np.arange(self.cols) / (self.cols - 1)
        phi = np.arange(self.rows) * (np.pi / 2) / (self.rows - 1)
        X = jnp.stack([rho[None, :] * np.sin(phi)[:, None], rho[None, :] * np.cos(phi)[:, None]], -1)
        return X.reshape(-1, 2)


def _element_energy(X, u, material):
    """Elastic energy (J) of one element's ring: X, u (9, 2) nodal (R, Z) and (u_r, u_z)."""
    jac = jnp.einsum("gkn,nc->gck", _DN, X)  # d X_c / d xi_k, (9, 2, 2)
    det = jac[:, 0, 0] * jac[:, 1, 1] - jac[:, 0, 1] * jac[:, 1, 0]
    inv = jnp.stack([jnp.stack([jac[:, 1, 1], -jac[:, 0, 1]], -1), jnp.stack([-jac[:, 1, 0], jac[:, 0, 0]], -1)], -2)
    inv = inv / det[:, None, None]  # d xi_k / d X_c, (9, 2, 2)
    grad = jnp.einsum("gkn,nc,gkd->gcd", _DN, u, inv)  # d u_c / d X_d
    R, ur = _N @ X[:, 0], _N @ u[:, 0]
    zero = jnp.zeros_like(R)
    F = jnp.stack(
        [
            jnp.stack([1 + grad[:, 0, 0], grad[:, 0, 1], zero], -1),
            jnp.stack([grad[:, 1, 0], 1 + grad[:, 1, 1], zero], -1),
            jnp.stack([zero, zero, 1 + ur / R], -1),
        ],
        -2,
    )
    J = (F[:, 0, 0] * F[:, 1, 1] - F[:, 0, 1] * F[:, 1, 0]) * F[:, 2, 2]
    volume = 2 * jnp.pi * R * det * _W  # reference ring volume of each point (m^3)
    # Jbar: L2 projection of J onto {1, xi, eta} over the element (Q9/P3)
    mass = _P.T @ (volume[:, None] * _P)
    J_bar = _P @ (_inverse3(mass) @ (_P.T @ (volume * J)))
    # isochoric part W(J^-1/3 F) and volumetric part W(Jbar^1/3 I) in one call
    stretched = jnp.concatenate(
        [jnp.cbrt(1 / J)[:, None, None] * F, jnp.cbrt(J_bar)[:, None, None] * jnp.eye(3)]
    )
    densities = jax.vmap(material.strain_energy)(stretched)
    return jnp.sum(jnp.concatenate([volume, volume]) * densities)


def _inverse3(M):
    """Inverse of a 3 x 3 matrix by cofactors (smaller compiled code than an LU)."""
    adjugate_T = jnp.stack([jnp.cross(M[1], M[2]), jnp.cross(M[2], M[0]), jnp.cross(M[0], M[1])])
    return adjugate_T.T / jnp.dot(M[0], adjugate_T[0])


def _contact_energy(X_edge, z_edge, d, outer_radius, thickness, material):
    """Penalty energy (J) of one outer edge: X_edge (3, 2) reference (R, Z) of its nodes,
    z_edge (3,) their current heights (m), plate travel d (m)."""
    R = _EDGE_N @ X_edge[:, 0]
    ds = jnp.linalg.norm(_EDGE_DN @ X_edge, axis=-1)
    penetration = _EDGE_N @ z_edge - (outer_radius - d)
    kappa = CONTACT_PENALTY * material.shear_modulus / thickness
    ramp = smooth_ramp(penetration, CONTACT_SMOOTHING * thickness)
    return jnp.sum(_EDGE_W * ds * 2 * jnp.pi * R * kappa / 2 * ramp**2)


def _parts(mesh, params):
    outer_radius, thickness = params[0], params[1]
    X = mesh.reference(outer_radius, thickness)
    return X[mesh.elem_nodes], X[mesh.edge_nodes]


def potential(mesh, y, params):
    """Total potential (J) of state y: elastic + contact energy - F d.

    params = (outer_radius (m), thickness (m), material, force F (N)).
    """
    outer_radius, thickness, material, force = params
    X_elem, X_edge = _parts(mesh, params)
    u = (y[:-1] * mesh.free_u).reshape(-1, 2)
    elastic = jax.vmap(_element_energy, (0, 0, None))(X_elem, u[mesh.elem_nodes], material)
    z_edge = X_edge[..., 1] + u[mesh.edge_nodes, 1]
    contact = jax.vmap(_contact_energy, (0, 0, None, None, None, None))(
        X_edge, z_edge, y[-1], outer_radius, thickness, material
    )
    return jnp.sum(elastic) + jnp.sum(contact) - force * y[-1]


def residual(mesh, mask, y, held, params):
    """dPi/dy on the unknowns (mask 1); y - held on the held values (mask 0)."""
    return mask * jax.grad(potential, argnums=1)(mesh, y, params) + (1 - mask) * (y - held)


def _project_psd(H):
    """The nearest positive semi-definite matrix to the symmetric H (its negative
    eigenvalues set to 0)."""
    values, vectors = jnp.linalg.eigh(H)
    return (vectors * jnp.maximum(values, 0.0)[..., None, :]) @ jnp.swapaxes(vectors, -1, -2)


def tangent(mesh, mask, y, params, project=False):
    """d residual / dy (n_dof + 1, n_dof + 1): the Hessian of Pi on the unknowns,
    identity on the held values; assembled from element and edge Hessians."""
    outer_radius, thickness, material, _ = params
    X_elem, X_edge = _parts(mesh, params)
    u = (y[:-1] * mesh.free_u).reshape(-1, 2)
    H_elem = jax.vmap(jax.hessian(_element_energy, argnums=1), (0, 0, None))(
        X_elem, u[mesh.elem_nodes], material
    ).reshape(-1, 18, 18)
    if project:
        H_elem = _project_psd(H_elem)

    def contact(z_and_d):
        z_edge = X_edge[..., 1] + z_and_d[:-1][mesh.edge_rows]
        energies = jax.vmap(_contact_energy, (0, 0, None, None, None, None))(
            X_edge, z_edge, z_and_d[-1], outer_radius, thickness, material
        )
        return jnp.sum(energies)

    H_contact = jax.hessian(contact)(jnp.append(u[:, 1].reshape(mesh.rows, mesh.cols)[:, -1], y[-1]))
    dofs = mesh.elem_dofs
    contact_dofs = np.append(mesh.outer_z_dofs, mesh.n_dof)
    n = mesh.n_dof + 1
    H = jnp.zeros((n, n)).at[dofs[:, :, None], dofs[:, None, :]].add(H_elem)
    H = H.at[contact_dofs[:, None], contact_dofs[None, :]].add(H_contact)
    return mask[:, None] * H * mask[None, :] + jnp.diag(1 - mask)


def _factor(H):
    """Cholesky factor of H + lambda I with the smallest tried shift lambda >= 0 that
    makes it positive definite (lambda = 0 first, then DOME_LEVENBERG_START times the
    largest diagonal entry, growing tenfold)."""
    scale = DOME_LEVENBERG_START * jnp.max(jnp.abs(jnp.diag(H)))

    def cond(carry):
        _, ok, k = carry
        return ~ok & (k < LEVENBERG_MAX)

    def body(carry):
        _, _, k = carry
        shift = jnp.where(k == 0, 0.0, scale * 10.0 ** (k - 1))
        L = jnp.linalg.cholesky(H + shift * jnp.eye(H.shape[0]))
        return L, jnp.all(jnp.isfinite(L)), k + 1

    L, _, _ = lax.while_loop(cond, body, (jnp.zeros_like(H), False, 0))
    return L


def _cho_solve(L, b):
    return jax.scipy.linalg.cho_solve((L, True), b)


def _newton(mesh, mask, params, y0, held, tol=DOME_NEWTON_TOL):
    """Minimise Pi over the unknowns (mask 1) from y0, the others held at ``held``:
    (state, converged, iterations). Converged: the last Newton step was below
    ``tol`` t (default DOME_NEWTON_TOL)."""
    tol = tol * params[1]
    y0 = mask * y0 + (1 - mask) * held

    def energy(y):
        value = potential(mesh, y, params)
        return jnp.where(jnp.isfinite(value), value, jnp.inf)

    def cond(carry):
        _, it, step = carry
        return (it < NEWTON_MAX_ITER) & (step > tol)

    def body(carry):
        y, it, _ = carry
        g = residual(mesh, mask, y, held, params)
        L = _factor(tangent(mesh, mask, y, params))
        dy = _cho_solve(L, g)
        pi0, slope = energy(y), jnp.dot(g, dy)
        slack = DOME_LINE_SEARCH_SLACK * jnp.abs(pi0)

        def search_cond(alpha):
            trial = energy(y - alpha * dy)
            return (trial > pi0 - ARMIJO * alpha * slope + slack) & (alpha > 2.0**-LINE_SEARCH_MAX)

        alpha = lax.while_loop(search_cond, lambda a: a / 2, 1.0)
        step = alpha * jnp.max(jnp.abs(dy))
        return y - alpha * dy, it + 1, step

    y, iterations, step = lax.while_loop(cond, body, (y0, 0, jnp.inf))
    return y, step <= tol, iterations


def _solve_stages(mesh, params, forces, start_travel, start_tol):
    """States (n, n_dof + 1), converged flags and Newton iteration counts (n,) under each
    of ``forces`` (n,) (N) in turn. Stage 0 holds the plate at ``start_travel`` (m) from
    the undeformed dome (to tolerance ``start_tol``), establishing contact; then each
    force is held in turn, warm-started from the previous state. One compiled Newton
    iteration serves all stages (mask, held values and tolerance are data)."""
    n, size = forces.shape[0], mesh.n_dof + 1
    masks = np.stack([mesh.mask(False)] + [mesh.mask(True)] * n)
    tols = jnp.concatenate([jnp.asarray(start_tol, float)[None], jnp.full(n, DOME_NEWTON_TOL)])
    stage_forces = jnp.concatenate([jnp.zeros(1), forces])
    helds = jnp.zeros((n + 1, size)).at[0, -1].set(start_travel)

    def stage(y, inputs):
        mask, tol, force, held = inputs
        y, converged, iterations = _newton(mesh, mask, params + (force,), y, held, tol)
        return y, (y, converged, iterations)

    _, (states, converged, iterations) = lax.scan(stage, jnp.zeros(size), (masks, tols, stage_forces, helds))
    return states[1:], converged[1:], iterations


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 4))
def equilibria(mesh, params, forces, start_travel, start_tol):
    """The equilibria under each of ``forces`` (n,) (N), plate travel free, with implicit
    derivatives with respect to params = (outer_radius (m), thickness (m), material) and
    the forces. Returns (states (n, n_dof + 1), converged (n,) bool).

    ``start_travel`` (m) and ``start_tol`` only set where Newton starts (see
    :func:`_solve_stages`); the equilibria, hence the derivatives, do not depend on them.
    """
    return _solve_stages(mesh, params, forces, start_travel, start_tol)[:2]


@equilibria.defjvp
def _equilibria_jvp(mesh, start_tol, primals, tangents):
    params, forces, start_travel = primals
    params_dot, forces_dot, _ = tangents
    states, converged = equilibria(mesh, params, forces, start_travel, start_tol)
    mask = mesh.mask(True)

    def state_tangent(y, force, force_dot):
        held = jnp.zeros_like(y)
        _, r_dot = jax.jvp(
            lambda p, f: residual(mesh, mask, y, held, p + (f,)), (params, force), (params_dot, force_dot)
        )
        full = params + (force,)
        L = _factor(tangent(mesh, mask, y, full))

        def matvec(v):
            return jax.jvp(lambda z: residual(mesh, mask, z, held, full), (y,), (v,))[1]

        return lax.custom_linear_solve(matvec, -r_dot, lambda _, b: _cho_solve(L, b), symmetric=True)

    states_dot = jax.vmap(state_tangent)(states, forces, forces_dot)
    return (states, converged), (states_dot, np.zeros(converged.shape, dtype=jax.dtypes.float0))
