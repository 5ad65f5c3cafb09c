"""Finite-strain axisymmetric model of a thick hemispherical dome pressed by a flat plate.

Geometry and mesh. The wall (radii R_o - t .. R_o, apex on the axis, base rim on z = 0) is
meshed in the meridian section with 9-node quadratic quadrilaterals on a polar grid:
``n_wall`` elements through the wall (radius rho) and ``n_meridian`` along the meridian
(polar angle phi from 0 at the apex to pi / 2 at the base), nodes on arcs. Element
boundaries sit at phi = (pi / 2) s^g, s = 0, 1/n, .., 1, with the grading exponent g:
small elements at the apex, where a light load bends the wall over a short length
~ sqrt(R t). Node (i, j) sits at phi_i, rho_j; its unknowns are the displacements (u_r, u_z) (m).

Kinematics. F = [[dr/dR, dr/dZ, 0], [dz/dR, dz/dZ, 0], [0, 0, (R + u_r) / R]] in
(r, z, theta) order, evaluated at 3 x 3 Gauss points, which never lie on the axis. Its five
non-zero entries are affine in the element's 18 nodal displacements: F5 = F_rest + H5,
H5 = B u. The energy is formed from H5 without cancellation (as in
materials.excess_invariants). The nodes of the apex row lie on the axis: their u_r is held
at 0 (symmetry).

Volumetric locking. The energy is split as W(F) = W(J^(-1/3) F) + W(J^(1/3) I) (exact for
the decoupled laws of :mod:`materials`: isochoric part plus U(J)). The isochoric part is
integrated at the 3 x 3 points; the volumetric part uses Jbar = A J, the L2 projection (over
the element's ring volume) of J onto the linear fields {1, xi, eta} of the element: the
energy form of the Q9/P3 mixed element (discontinuous linear pressure, inf-sup stable),
without spurious pressure or hourglass modes.

Contact. A rigid frictionless plate at z = R_o - d (d the plate travel, m) and the outer
surface: penalty energy (kappa / 2) ramp(g)^2 per reference area of the outer surface at
3 Gauss points per element edge, g = z + u_z - (R_o - d) the penetration, ramp a softplus
smoothed max(g, 0) (so that design derivatives are continuous), kappa = CONTACT_PENALTY
mu / t. The plate force is the reaction dPi / dd.

Tangent. The Hessian of the energy is assembled from exact element Hessians
B^T (d^2 E / dF5^2) B: per Gauss point a 5 x 5 block (isochoric energy and the curvature of
J), plus the rank-3 coupling of the projected Jbar; JAX differentiates only the
five-argument densities. This is the Hessian of :func:`potential` to rounding (tested
against ``jax.hessian``) at a tenth of the cost of differentiating the element energy,
assembled straight into the blocks of its factor (:mod:`._blocks`).

Solution. Newton's method on the total potential with the exact tangent, factored as a
block tridiagonal matrix bordered by the plate travel (:mod:`._blocks`), a Levenberg
shift only where the tangent is not positive definite, and a backtracking line search on
the potential (skipped where the decrease it would test is below the potential's rounding,
DOME_ENERGY_RESOLUTION); converged when the largest out-of-balance force is below DOME_RESIDUAL_TOL
mu t^2 (or, where float64's rounding of the forces stops Newton short of that, below
DOME_ROUNDING_SLACK times it). Two controls: the plate travel held (the natural control: it passes limit points
where the force falls) or the force held (d an unknown, Pi - F d minimised). The path
followers (:func:`follow_travels`, :func:`first_crossings`) step the plate travel
adaptively from the undeformed dome with a secant predictor; a force level that a step
carried is solved from the cubic Hermite interpolant from the step's start (or a lighter
level already solved in that step) to the step's end, whose tangents come from Newton's
last Hessian. Their equilibria are differentiated implicitly
(:func:`implicit`: a custom JVP solving with the same tangent, whose own derivative,
the second order that a design's Hessians take, is a rule of its own: the JVP of
:func:`state_tangent`), so derivatives with respect to geometry, material, travel and
force are exact whatever the iterations did, in forward and reverse mode and to any order.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from magdesign._numerics import (
    CONTACT_SMOOTHING,
    DOME_ENERGY_RESOLUTION,
    DOME_LEVENBERG_START,
    DOME_RESIDUAL_TOL,
    DOME_ROUNDING_SLACK,
    smooth_ramp,
)
from magdesign._tracing import traced_once
from magdesign.mechanics import _blocks
from magdesign.mechanics.materials import isochoric_excess

# Penalty stiffness of the contact, kappa t / mu: the penetration it leaves is a 1/1000 of
# the wall's own compression p t / E under the contact pressure p, a small part of the
# plate travel itself (measured below 1e-4 of it, see tests/mechanics/test_dome.py);
# stiffer penalties only slow Newton down.
CONTACT_PENALTY = 1000.0
# Grading exponent of the meridian mesh (element boundaries at (pi / 2) s^GRADING).
GRADING = 2.0
# Newton iterations of one solve at most: a force-held solve or a path's first step, and
# any later step of a path (a step that needs more is retried at a quarter of its length).
NEWTON_MAX_ITER = 40
PATH_NEWTON_MAX_ITER = 20
# Halvings of the step of one line search at most, and the Armijo fraction of the
# predicted decrease that a step must achieve.
LINE_SEARCH_MAX = 30
ARMIJO = 0.25
# Index of the largest Levenberg shift tried (each ten times the previous one; see _factor).
LEVENBERG_MAX = 12
# Path following: steps at most, and the Newton iterations at or below which a step doubles
# and from which on it halves. A step that needed many iterations is not repeated at the same
# length: the next one, as long, is likely to fail after PATH_NEWTON_MAX_ITER.
PATH_MAX_STEPS = 80
PATH_EASY_ITER = 8
PATH_HARD_ITER = 12
# A failed step is retried at a quarter of its length until it is shorter than this
# fraction of the wall: then the path has met a snap (the equilibrium with the travel held
# ceases to exist, as where the apex of a thin dome inverts and leaves the plate), and the
# next step jumps: Newton descends the potential from the last state, with up to
# SNAP_MAX_ITER iterations, to the equilibrium the dome snaps to at a travel this much
# further. A failed jump ends the path.
SNAP_STEP = 1e-2
SNAP_MAX_ITER = 200
# Bisections of the interval of a path step that find where its Hermite interpolated
# force meets a level (2^-50: the travel to rounding).
HERMITE_BISECTIONS = 50

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

    def __init__(self, n_wall: int, n_meridian: int, base: str, grading: float = GRADING):
        self.n_wall, self.n_meridian = n_wall, n_meridian
        self.rows, self.cols = 2 * n_meridian + 1, 2 * n_wall + 1
        self.n_dof = 2 * self.rows * self.cols
        self.size = self.n_dof + 1
        node = np.arange(self.rows * self.cols).reshape(self.rows, self.cols)
        a, b = np.arange(n_meridian), np.arange(n_wall)
        rows = 2 * a[:, None, None, None] + np.arange(3)[:, None]  # (n_mer, 1, 3, 1)
        cols = 2 * b[None, :, None, None] + np.arange(3)[None, :]  # (1, n_wall, 1, 3)
        elem_nodes = node[rows, cols].reshape(n_meridian * n_wall, 9)
        self.elem_nodes = elem_nodes  # (n_elem, 9), local node (a, b) at 3 a + b
        self.elem_dofs = (2 * elem_nodes[:, :, None] + np.arange(2)).reshape(-1, 18)
        self.edge_nodes = node[:, -1][2 * a[:, None] + np.arange(3)]  # (n_mer, 3) outer edges
        # each edge's unknowns: the u_z of its three nodes, then the plate travel
        self.edge_dofs = np.concatenate([2 * self.edge_nodes + 1, np.full((n_meridian, 1), self.n_dof)], axis=1)
        free = np.ones((self.rows, self.cols, 2))
        free[0, :, 0] = 0.0  # apex row, on the axis: u_r = 0 by symmetry
        free[-1, :, 1] = 0.0  # base rim on z = 0
        if base == "bonded":
            free[-1, :, 0] = 0.0
        self.free_u = free.ravel()
        corners = (np.pi / 2) * (np.arange(n_meridian + 1) / n_meridian) ** grading
        phi = np.empty(self.rows)
        phi[0::2] = corners
        phi[1::2] = 0.5 * (corners[:-1] + corners[1:])  # mid-nodes halfway along each arc
        self.phi = phi
        self.layout = _blocks.Layout(self.rows, self.cols)
        self.gradient_tables, self.hessian_tables = _assembly_tables(self)

    def mask(self, force_control: bool) -> np.ndarray:
        """1 for the unknowns of a solve, 0 for held values: (n_dof + 1,)."""
        return np.append(self.free_u, 1.0 if force_control else 0.0)

    def reference(self, outer_radius, thickness):
        """Reference nodal coordinates (rows cols, 2): (R, Z) in m."""
        rho = outer_radius - thickness + thickness * np.arange(self.cols) / (self.cols - 1)
        X = jnp.stack([rho[None, :] * np.sin(self.phi)[:, None], rho[None, :] * np.cos(self.phi)[:, None]], -1)
        return X.reshape(-1, 2)


def _assembly_tables(mesh):
    """(gradient, tangent) :func:`_blocks.summing_tables` of a mesh: from the elements'
    gradients (n_elem, 18) then the edges' (n_meridian, 4), to the gradient (n_dof + 1,);
    from the elements' Hessians (n_elem, 18, 18) then the edges' (n_meridian, 4, 4), to
    the flattened tangent blocks. Entries of fixed displacements are dropped (they enter
    the energy as 0), and so are the travel's own entries of each edge: the travel's
    gradient entry and diagonal entry sum every edge's, and are summed apart (that one
    place receives n_meridian entries, where no other receives more than 4)."""
    free = np.append(mesh.free_u, 1.0)
    dofs = np.concatenate([mesh.elem_dofs.ravel(), mesh.edge_dofs.ravel()])
    gradient = np.where((free[dofs] > 0) & (dofs < mesh.n_dof), dofs, -1)
    rows = np.concatenate([np.repeat(d, d.shape[1], axis=1).ravel() for d in (mesh.elem_dofs, mesh.edge_dofs)])
    cols = np.concatenate([np.tile(d, (1, d.shape[1])).ravel() for d in (mesh.elem_dofs, mesh.edge_dofs)])
    hessian = np.where((free[rows] > 0) & (free[cols] > 0), mesh.layout.positions(rows, cols), -1)
    return _blocks.summing_tables(gradient, mesh.size), _blocks.summing_tables(hessian, mesh.layout.flat_size)


def _excess(H5):
    """(Ibar1 - 3, Ibar2 - 3, J - 1) of the axisymmetric displacement gradient H5 = F5 - F_rest:
    :func:`materials.excess_invariants` of H = [[a, b, 0], [c, e, 0], [0, 0, h]] with its
    zero entries left out, under half of its traced operations (a product with a literal 0
    is still an operation for JAX and XLA, and the element's derivatives multiply them)."""
    a, b, c, e, h = H5
    # C - I = H + H^T + H^T H: its in-plane block and its hoop entry
    d00, d11, d01, d22 = 2.0 * a + a * a + c * c, 2.0 * e + b * b + e * e, b + c + a * b + c * e, 2.0 * h + h * h
    i1 = d00 + d11 + d22
    i2 = 2.0 * i1 + d00 * d11 - d01 * d01 + (d00 + d11) * d22  # 2 tr D + the second invariant of D
    in_plane = a + e + a * e - b * c  # det of the in-plane block of F, less 1
    return isochoric_excess(i1, i2, in_plane + h + h * in_plane)


def _densities(material):
    """(isochoric density of H5, volumetric density of j = J - 1) (J/m^3) of a decoupled
    law: W(J^(-1/3) F) and W(J^(1/3) I)."""

    def isochoric(H5):
        i1, i2, _ = _excess(H5)
        return material.invariant_energy(i1, i2, 0.0)

    def volumetric(j):
        return material.invariant_energy(0.0, 0.0, j)

    return isochoric, volumetric


def _volume_change(H5):
    return _excess(H5)[2]


def _kinematics(X):
    """B (9 points, 5, 18), ring volumes (9,) (m^3) and the volumetric projection A (9, 9)
    (Jbar = A J) of one element with reference nodal coordinates X (9, 2) (m)."""
    jac = jnp.einsum("gkn,nc->gck", _DN, X)  # d X_c / d xi_k, (9, 2, 2)
    det = jac[:, 0, 0] * jac[:, 1, 1] - jac[:, 0, 1] * jac[:, 1, 0]
    inv = jnp.stack([jnp.stack([jac[:, 1, 1], -jac[:, 0, 1]], -1), jnp.stack([-jac[:, 1, 0], jac[:, 0, 0]], -1)], -2)
    inv = inv / det[:, None, None]  # d xi_k / d X_c, (9, 2, 2)
    dN = jnp.einsum("gkn,gkd->gnd", _DN, inv)  # d N_n / d X_d, (9, 9, 2)
    R = _N @ X[:, 0]
    zero = jnp.zeros_like(dN[..., 0])
    on_ur = jnp.stack([dN[..., 0], dN[..., 1], zero, zero, _N / R[:, None]], axis=1)  # (9, 5, 9)
    on_uz = jnp.stack([zero, zero, dN[..., 0], dN[..., 1], zero], axis=1)
    B = jnp.stack([on_ur, on_uz], axis=-1).reshape(9, 5, 18)
    volume = 2 * jnp.pi * R * det * _W
    weighted = volume[:, None] * _P
    A = _P @ _inverse3(_P.T @ weighted) @ weighted.T
    return B, volume, A


def _inverse3(M):
    """Inverse of a 3 x 3 matrix by cofactors (smaller compiled code than an LU)."""
    adjugate_T = jnp.stack([jnp.cross(M[1], M[2]), jnp.cross(M[2], M[0]), jnp.cross(M[0], M[1])])
    return adjugate_T.T / jnp.dot(M[0], adjugate_T[0])


def _element_energy(X, u, material):
    """Elastic energy (J) of one element's ring: X (9, 2) nodal (R, Z), u (18,) displacements."""
    B, volume, A = _kinematics(X)
    H5 = B @ u
    isochoric, volumetric = _densities(material)
    j_bar = A @ jax.vmap(_volume_change)(H5)  # A reproduces constants: Jbar - 1 = A (J - 1)
    return jnp.dot(volume, jax.vmap(isochoric)(H5) + jax.vmap(volumetric)(j_bar))


def _element_derivatives(X, u, material, with_hessian=True):
    """Gradient (18,) and Hessian (18, 18) (None unless ``with_hessian``) of
    :func:`_element_energy` in u, assembled from the derivatives of the densities in F5
    (see the module docstring)."""
    B, volume, A = _kinematics(X)
    H5 = B @ u
    isochoric, volumetric = _densities(material)
    J, dJ = jax.vmap(lambda h: (_volume_change(h), jax.grad(_volume_change)(h)))(H5)
    J_bar = A @ J
    dE_dJ = A.T @ (volume * jax.vmap(jax.grad(volumetric))(J_bar))
    G = volume[:, None] * jax.vmap(jax.grad(isochoric))(H5) + dE_dJ[:, None] * dJ  # dE / dF5, (9, 5)
    gradient = jnp.einsum("gi,gij->j", G, B)
    if not with_hessian:
        return gradient, None
    d2J = jax.vmap(jax.hessian(_volume_change))(H5)
    h_iso = jax.vmap(jax.jacfwd(jax.jacfwd(isochoric)))(H5)  # forward over forward: the quickest here
    U2 = jax.vmap(jax.grad(jax.grad(volumetric)))(J_bar)
    d2E_dJ2 = A.T @ ((volume * U2)[:, None] * A)
    D = volume[:, None, None] * h_iso + dE_dJ[:, None, None] * d2J  # dE / dF5's point-wise blocks
    L = jnp.einsum("gi,gij->gj", dJ, B)  # dJ / du, (9, 18)
    hessian = jnp.einsum("gij,gik,gkl->jl", B, D, B) + L.T @ d2E_dJ2 @ L
    return gradient, hessian


def _penalty(params):
    """Contact penalty stiffness kappa (Pa/m): CONTACT_PENALTY mu / t."""
    _, thickness, material = params
    return CONTACT_PENALTY * material.shear_modulus / thickness


def _edge_energy(X_edge, z_and_d, outer_radius, kappa, width):
    """Penalty energy (J) of one outer edge: X_edge (3, 2) reference (R, Z) of its nodes,
    z_and_d (4,) their u_z (m) and the plate travel d (m)."""
    R = _EDGE_N @ X_edge[:, 0]
    ds = jnp.linalg.norm(_EDGE_DN @ X_edge, axis=-1)
    penetration = _EDGE_N @ (X_edge[:, 1] + z_and_d[:3]) - (outer_radius - z_and_d[3])
    ramp = smooth_ramp(penetration, width)
    return jnp.sum(_EDGE_W * ds * 2 * jnp.pi * R * kappa / 2 * ramp**2)


def _parts(mesh, params, y):
    """Per-element (X (9, 2), u (18,)) and per-edge (X (3, 2), (u_z, d) (4,)) arrays."""
    outer_radius, thickness, _ = params
    X = mesh.reference(outer_radius, thickness)
    u = y[:-1] * mesh.free_u
    full = jnp.append(u, y[-1])
    return X[mesh.elem_nodes], full[mesh.elem_dofs], X[mesh.edge_nodes], full[mesh.edge_dofs]


def _contact_args(mesh, params):
    outer_radius, thickness, _ = params
    return outer_radius, _penalty(params), CONTACT_SMOOTHING * thickness


def potential(mesh, y, params, force=0.0):
    """Total potential (J) of state y: elastic + contact energy - force d.

    params = (outer_radius (m), thickness (m), material); force (N).
    """
    X_elem, u_elem, X_edge, z_edge = _parts(mesh, params, y)
    elastic = jax.vmap(_element_energy, (0, 0, None))(X_elem, u_elem, params[2])
    contact = jax.vmap(_edge_energy, (0, 0) + (None,) * 3)(X_edge, z_edge, *_contact_args(mesh, params))
    return jnp.sum(elastic) + jnp.sum(contact) - force * y[-1]


@traced_once
def derivatives(mesh, y, params, with_hessian=True):
    """Gradient (size,) and Hessian (:class:`_blocks.Blocks`; None unless
    ``with_hessian``) of :func:`potential` (force 0) in y, fixed displacements held out
    (their rows and columns 0).

    The last gradient entry, dPi / dd, is the plate force (N)."""
    X_elem, u_elem, X_edge, z_edge = _parts(mesh, params, y)
    element = functools.partial(_element_derivatives, with_hessian=with_hessian)
    g_elem, H_elem = jax.vmap(element, (0, 0, None))(X_elem, u_elem, params[2])
    contact = (X_edge, z_edge) + _contact_args(mesh, params)
    in_axes = (0, 0) + (None,) * 3
    g_edge = jax.vmap(jax.grad(_edge_energy, argnums=1), in_axes)(*contact)
    g = _blocks.gather_sum(mesh.gradient_tables, jnp.concatenate([g_elem.ravel(), g_edge.ravel()]))
    g = g.at[-1].set(jnp.sum(g_edge[:, -1]))
    if not with_hessian:
        return g, None
    H_edge = jax.vmap(jax.hessian(_edge_energy, argnums=1), in_axes)(*contact)
    flat = _blocks.gather_sum(mesh.hessian_tables, jnp.concatenate([H_elem.ravel(), H_edge.ravel()]))
    return g, _blocks.Blocks.from_flat(mesh.layout, flat, jnp.sum(H_edge[:, -1, -1]))


def plate_force(mesh, y, params):
    """The plate force (N) at state y: the reaction dPi / dd."""
    return jax.grad(lambda d: potential(mesh, y.at[-1].set(d), params))(y[-1])


def contact_radius(mesh, y, params):
    """Largest current radius (m) of an outer-surface Gauss point pressed into the plate
    (0 if none): where the contact ends. Not differentiable (held constant)."""
    y, params = lax.stop_gradient((y, params))
    _, _, X_edge, z_edge = _parts(mesh, params, y)
    u_r = (y[:-1] * mesh.free_u).reshape(-1, 2)[mesh.edge_nodes, 0]
    r = (X_edge[..., 0] + u_r) @ _EDGE_N.T  # (edges, 3 points)
    z = (X_edge[..., 1] + z_edge[:, :3]) @ _EDGE_N.T
    touching = z > params[0] - y[-1]
    return jnp.max(jnp.where(touching, r, 0.0))


def _unit_last(mesh):
    return np.append(np.zeros(mesh.n_dof), 1.0)


def _factor(mesh, H, resume=1):
    """(Cholesky factor (:class:`_blocks.Factor`) of H (:class:`_blocks.Blocks`) + lambda D,
    the index of its shift lambda): the smallest tried shift lambda >= 0 that makes it
    positive definite, tried in the order lambda = 0 (index 0), then DOME_LEVENBERG_START
    10^(index - 1) from index ``resume`` (>= 1) on, growing tenfold. D = |diag H|
    (Marquardt's scaling, floored at DOME_LEVENBERG_START times its largest entry): each
    unknown is shifted in proportion to its own stiffness, so the contact's penalty, the
    stiffest, does not set the shift of the soft bending modes (with lambda I it did, and
    a snap's jump crawled). One loop makes every try, so the program holds one factor (and
    a batch of matrices factors again while any one of them needs a shift). Where no try
    makes it positive definite: a factor that is not finite, and index LEVENBERG_MAX."""
    diagonal = jnp.abs(H.diagonal_entries(mesh.layout))
    scale = DOME_LEVENBERG_START * jnp.maximum(diagonal, DOME_LEVENBERG_START * jnp.max(diagonal))

    def index(tries):
        return jnp.where(tries == 0, 0, resume + tries - 1)

    def attempt(carry):
        _, tries = carry
        k = index(tries)
        return _blocks.factor_blocks(mesh.layout, H, jnp.where(k == 0, 0.0, scale * 10.0 ** (k - 1))), tries + 1

    def cond(carry):
        F, tries = carry
        return (tries == 0) | (~F.finite() & (index(tries) <= LEVENBERG_MAX))

    shapes = jax.eval_shape(lambda H: _blocks.factor_blocks(mesh.layout, H), H)
    untried = jax.tree.map(lambda a: jnp.full(a.shape, jnp.nan, a.dtype), shapes)
    F, tries = lax.while_loop(cond, attempt, (untried, jnp.asarray(0)))
    return F, index(tries - 1)


def _tolerance(params):
    """Largest out-of-balance force (N) of a converged state: DOME_RESIDUAL_TOL mu t^2."""
    return DOME_RESIDUAL_TOL * params[2].shear_modulus * params[1] ** 2


def newton(mesh, mask, held, force, params, y0, max_iter, shift=0):
    """Minimise Pi - force d over the unknowns (mask 1) from y0, the others held at
    ``held``: (state, converged, iterations, the Hessian of the potential at the state
    (its blocks), the plate force at the state (N): the reaction dPi/dd, read off the
    gradient, the shift hint for the next solve). ``shift``, the hint: the index (see :func:`_factor`)
    of the shift that the last factor needing one found, in this solve or an earlier one
    (0: none yet); a factor that needs a shift resumes its tries a tenth below it. The
    path's steps need a shift in their first iterations, of index 4 to 6 on the dome-Hall
    sensor's dome, much the same from step to step, which the tries from index 1 climbed to each
    time. The hint comes down a tenth with each factor that needs a shift, not with one
    that needs none.
    Converged: the largest entry of the residual (an out-of-balance force, N) is at most
    :func:`_tolerance`, or at most DOME_ROUNDING_SLACK times it where a Newton step no
    longer halves it (float64's floor, see magdesign._numerics)."""
    tol = _tolerance(params)
    y0 = mask * y0 + (1 - mask) * held
    unit = _unit_last(mesh)

    def energy(y):
        value = potential(mesh, y, params, force)
        return jnp.where(jnp.isfinite(value), value, jnp.inf)

    def on_floor(size, previous):
        return (size > previous / 2) & (size <= DOME_ROUNDING_SLACK * tol)

    def step(y, pi0, g, H, shift):
        """(y less Newton's step for the gradient g and Hessian H, cut back until Armijo's
        test holds, the potential there, whether the search gave up, the shift index);
        pi0 the potential at y, NaN where not yet evaluated."""
        F, used = _factor(mesh, H.restricted(mesh.layout, mask), jnp.maximum(shift - 1, 1))
        dy = _blocks.solve(mesh.layout, F, g)
        slope = jnp.dot(g, dy)

        # The potential at alpha = 2^-k for k = -1 (y itself, where pi0 is not yet known),
        # 0 (the full step, whatever the test), 1, 2, ... while Armijo's test fails: one
        # evaluation of the potential in the compiled loop.
        def alpha_of(k):
            return jnp.where(k < 0, 0.0, jnp.ldexp(1.0, -jnp.maximum(k, 0)))

        def search_cond(search):
            k, trial, pi0 = search
            resolved = slope > DOME_ENERGY_RESOLUTION * jnp.abs(pi0)
            alpha = alpha_of(k)
            return (k < 0) | (resolved & (trial > pi0 - ARMIJO * alpha * slope) & (alpha > 2.0**-LINE_SEARCH_MAX))

        def shorter(search):
            k, trial, pi0 = search
            k = k + 1
            value = energy(jnp.where(k < 0, y, y - alpha_of(k) * dy))
            return k, jnp.where(k < 0, trial, value), jnp.where(k < 0, value, pi0)

        start = (jnp.where(jnp.isnan(pi0), -2, -1), jnp.inf, pi0)
        k, pi, _ = lax.while_loop(search_cond, shorter, start)
        alpha = alpha_of(k)
        # the hint: the shift a factor last needed (one that found none keeps it)
        return y - alpha * dy, pi, alpha <= 2.0**-LINE_SEARCH_MAX, jnp.where((used > 0) & F.finite(), used, shift)

    # Each turn linearises at y, then steps unless y is where the solve ends: one
    # evaluation of the derivatives in the compiled loop (as many evaluations as with one
    # before the loop and one after each step). pi0: the potential at y, carried from the
    # line search that reached y (NaN at y0, where the first search evaluates it).
    def body(carry):
        y, pi0, previous, it, gave_up, shift, _ = carry
        g, H = derivatives(mesh, y, params)
        reaction = g[-1]
        g = mask * (g - force * unit)
        size = jnp.max(jnp.abs(g))
        stopped = gave_up | on_floor(size, previous)
        done = ~(size > tol) | (it >= max_iter) | stopped  # a NaN residual stops it too
        y, pi, gave_up, shift = lax.cond(done, lambda: (y, pi0, gave_up, shift), lambda: step(y, pi0, g, H, shift))
        return y, pi, size, it + jnp.where(done, 0, 1), gave_up, shift, (done, stopped, H, reaction)

    unset = (False, False, _blocks.Blocks.zeros(mesh.layout), jnp.zeros(()))
    carry = (y0, jnp.nan, jnp.inf, 0, False, jnp.asarray(shift), unset)
    y, _, size, iterations, _, shift, (_, stopped, H, reaction) = lax.while_loop(lambda c: ~c[-1][0], body, carry)
    converged = (size <= tol) | (stopped & (size <= DOME_ROUNDING_SLACK * tol))
    return y, converged, iterations, H, reaction, shift


def _control(mesh, force_control, value):
    """(mask, held state, force) of a solve with the force (``force_control``, a bool that
    may be traced) or the travel held at ``value`` (N or m)."""
    mask = jnp.where(force_control, mesh.mask(True), mesh.mask(False))
    held = jnp.zeros(mesh.size).at[-1].set(jnp.where(force_control, 0.0, value))
    return mask, held, jnp.where(force_control, value, 0.0)


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1))
def implicit(mesh, control, params, values, states):
    """``states`` (n, size), unchanged: equilibria with the plate travel (``control``
    "travel", ``values`` (n,) in m) or the plate force ("force", N) held at ``values``,
    found by any solver. Its derivatives are those of the equilibria with respect to
    params = (outer_radius (m), thickness (m), material) and the values, from the implicit
    function theorem (a linear solve with the tangent), whatever the solver did."""
    return states


@implicit.defjvp
def _implicit_jvp(mesh, control, primals, tangents):
    params, values, states = primals
    params_dot, values_dot, _ = tangents
    # through the primal again, so that a derivative of this rule (second order) sees the
    # states move with params and values
    states = implicit(mesh, control, params, values, states)
    tangent = functools.partial(state_tangent, mesh, control == "force")
    return states, jax.vmap(tangent, (None, 0, None, 0))(params, states, params_dot, values_dot)


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1))
def state_tangent(mesh, force_control, params, y, params_dot, value_dot):
    """dy (size,): the derivative of the equilibrium y, whose plate force (``force_control``)
    or travel is held, along params_dot and the held value's value_dot (N or m). Its own
    derivative (a second derivative of y) is a rule of its own (:func:`_state_tangent_jvp`)."""
    return _first_order(mesh, force_control, params, y, params_dot, value_dot)[0]


def _gradient(mesh, y, params):
    """The gradient (size,) of :func:`potential` (force 0) in y: :func:`derivatives` without the Hessian."""
    return derivatives(mesh, y, params, with_hessian=False)[0]


def _first_order(mesh, force_control, params, y, params_dot, value_dot):
    """(dy, solve): see :func:`state_tangent`; solve(g_dot, value_dot) -> dy for a tangent
    g_dot (size,) of the gradient and value_dot of the held value."""
    mask = mesh.mask(force_control)
    _, H = derivatives(mesh, y, params)
    # only the solve's matvec is differentiated (custom_linear_solve): a factor with
    # tangents would cost a Cholesky derivative per direction
    F, _ = _factor(mesh, lax.stop_gradient(H.restricted(mesh.layout, mask)))

    def solve(g_dot, value_dot):
        # The residual, mask (dPi/dy - force e_d) + (1 - mask)(y - held), has the tangent
        # mask g_dot - value_dot e_d (the held travel or force moves along e_d, either way)
        # plus its Jacobian times dy. Held values move with their hold (r = y - held
        # there); the unknowns follow from the symmetric system of their own rows.
        r_dot = mask * g_dot - value_dot * _unit_last(mesh)
        held_dot = (1 - mask) * -r_dot
        b = -mask * (r_dot + H.matvec(mesh.layout, held_dot))

        def matvec(v):
            return mask * H.matvec(mesh.layout, mask * v) + (1 - mask) * v

        free_dot = lax.custom_linear_solve(matvec, b, lambda _, c: _blocks.solve(mesh.layout, F, c), symmetric=True)
        return free_dot + held_dot

    _, g_dot = jax.jvp(lambda p: _gradient(mesh, y, p), (params,), (params_dot,))
    return solve(g_dot, value_dot), solve


@state_tangent.defjvp
def _state_tangent_jvp(mesh, force_control, primals, tangents):
    # dy solves J dy = -(mask g_p params_dot - value_dot e_d), J the residual's Jacobian.
    # Differentiated along the tangents (of y, params, params_dot, value_dot) with dy
    # held, that equation gives J d(dy) = -(mask D - value_dot' e_d), D the derivative of
    # the gradient's directional derivative g_y dy + g_p params_dot along them: one second
    # directional derivative of the gradient, where differentiating the first-order rule
    # took the tangent of the whole Hessian (a third derivative per entry) as well.
    params, y, params_dot, value_dot = primals
    params_q, y_q, params_dot_q, value_dot_q = tangents
    dy, solve = _first_order(mesh, force_control, params, y, params_dot, value_dot)

    def directional(y, params, params_dot):
        return jax.jvp(lambda y, p: _gradient(mesh, y, p), (y, params), (dy, params_dot))[1]

    _, second = jax.jvp(directional, (y, params, params_dot), (y_q, params_q, params_dot_q))
    return dy, solve(second, value_dot_q)


class Path(eqx.Module):
    """A point of a followed force-travel path: the state y (size,) at travel y[-1] (m),
    its plate force (N), its tangent dy/dd (size,) and stiffness dF/dd (N/m) along the
    path, the state before it (for the secant predictor), the next travel step (m), and
    the count of steps tried. ``cut``: the last step tried failed (and ``step`` was cut to a
    quarter of it); ``failed``: a snap's jump did not converge; ``shift``: the index of the
    Levenberg shift its steps last needed (0: none yet; see :func:`newton`)."""

    y: jax.Array
    force: jax.Array
    tangent: jax.Array
    stiffness: jax.Array
    previous: jax.Array
    step: jax.Array
    count: jax.Array
    cut: jax.Array
    failed: jax.Array
    shift: jax.Array

    def can_go_on(self, max_travel):
        return ~self.failed & (self.count < PATH_MAX_STEPS) & (self.y[-1] < max_travel)


def _tangent(mesh, H):
    """(dy/dd (size,), dF/dd (N/m)) along the travel-held equilibria through a state whose
    Hessian is H: the unknowns' rows of the tangent system with the travel moving, t[-1] = 1."""
    mask = mesh.mask(False)
    column = H.last_column(mesh.layout)
    tangent = -_blocks.solve(mesh.layout, _factor(mesh, H.restricted(mesh.layout, mask))[0], mask * column)
    tangent = tangent.at[-1].set(1.0)
    return tangent, column @ tangent


def _start_path(mesh, step):
    """The undeformed dome as the start of a path, with first travel step ``step`` (m);
    its tangent and stiffness zero, not worked out (see :func:`first_crossings`)."""
    zero = jnp.zeros(mesh.size)
    return Path(
        zero,
        jnp.zeros(()),
        zero,
        jnp.zeros(()),
        zero,
        jnp.asarray(step, float),
        jnp.asarray(0),
        jnp.asarray(False),
        jnp.asarray(False),
        jnp.asarray(0),
    )


def _path_guess(path, goal, thickness):
    """(guess state, its travel, Newton iterations allowed, jump) of the next step towards
    the travel ``goal``: the secant prediction at min(d + step, goal). The first step, from
    the undeformed dome with the plate pressed in (no secant yet), may take a full solve's
    iterations; a jump (see SNAP_STEP: only after failed steps, so a short step asked for
    at a light load is a plain step) starts from the last state."""
    y = path.y
    d = y[-1]
    jump = path.cut & (path.step < SNAP_STEP * thickness)
    d_new = jnp.minimum(d + jnp.where(jump, SNAP_STEP * thickness, path.step), goal)
    last = d - path.previous[-1]
    ratio = jnp.where((last > 0) & ~jump, (d_new - d) / jnp.where(last > 0, last, 1.0), 0.0)
    guess = (y + ratio * (y - path.previous)).at[-1].set(d_new)
    max_iter = jnp.where(jump, SNAP_MAX_ITER, jnp.where(d > 0, PATH_NEWTON_MAX_ITER, NEWTON_MAX_ITER))
    return guess, d_new, max_iter, jump


def _path_update(params, path, y_new, force_new, tangent_new, ok, iterations, jump, shift):
    """The path after Newton's answer to :func:`_path_guess`: a converged step is taken
    (the next step doubles if it was easy, halves if it was hard; after a jump the secant
    starts afresh); a failed one is refused and the step cut to a quarter.
    ``force_new``: the plate force (N) at ``y_new``; ``tangent_new``: (dy/dd, dF/dd) at
    ``y_new`` (:func:`_tangent`), or None, which keeps the path's tangent (a path whose
    tangents are not read); ``shift``: Newton's last Levenberg shift index, for the next."""
    factor = jnp.where(iterations <= PATH_EASY_ITER, 2.0, jnp.where(iterations >= PATH_HARD_ITER, 0.5, 1.0))
    step = jnp.where(ok, jnp.maximum(path.step, SNAP_STEP * params[1]) * factor, path.step / 4)
    tangent, stiffness = (
        (path.tangent, path.stiffness)
        if tangent_new is None
        else jax.tree.map(lambda new, old: jnp.where(ok, new, old), tangent_new, (path.tangent, path.stiffness))
    )
    return Path(
        y=jnp.where(ok, y_new, path.y),
        force=jnp.where(ok, force_new, path.force),
        tangent=tangent,
        stiffness=stiffness,
        previous=jnp.where(ok, jnp.where(jump, y_new, path.y), path.previous),
        step=step,
        count=path.count + 1,
        cut=~ok,
        failed=~ok & jump,
        shift=shift,
    )


def _hermite_guess(before: Path, after: Path, level):
    """A state under the plate force ``level`` (N) between two points of a path with
    before.force < level <= after.force: the cubic Hermite interpolants of the force and
    the state in the travel, from their values and tangents at both ends, the force's
    inverted by bisection (a path step spans up to half the wall, over which a straight
    line between the states is far from equilibrium and makes Newton damp its steps)."""
    h = after.y[-1] - before.y[-1]

    def at(s, v0, t0, v1, t1):
        return (
            (2 * s**3 - 3 * s**2 + 1) * v0
            + (s**3 - 2 * s**2 + s) * h * t0
            + (3 * s**2 - 2 * s**3) * v1
            + (s**3 - s**2) * h * t1
        )

    def halve(_, bracket):
        low, high = bracket
        middle = 0.5 * (low + high)
        below = at(middle, before.force, before.stiffness, after.force, after.stiffness) < level
        return jnp.where(below, middle, low), jnp.where(below, high, middle)

    low, high = lax.fori_loop(0, HERMITE_BISECTIONS, halve, (jnp.zeros(()), jnp.ones(())))
    return at(0.5 * (low + high), before.y, before.tangent, after.y, after.tangent)


def follow_travels(mesh, params, travels, step):
    """Converged states (n, size) at each of ``travels`` (n,) (m, increasing from > 0),
    following the path from the undeformed dome with first step ``step`` (m); whether
    each was reached, and whether the path failed (at a snap) before it. Each travel may
    take PATH_MAX_STEPS steps. Not differentiated (see :func:`implicit`)."""

    def advance(path, goal):
        guess, d_new, max_iter, jump = _path_guess(path, goal, params[1])
        mask, held, force = _control(mesh, False, d_new)
        y, ok, iterations, _, reaction, shift = newton(mesh, mask, held, force, params, guess, max_iter, path.shift)
        return _path_update(params, path, y, reaction, None, ok, iterations, jump, shift)

    def to(path, goal):
        path = eqx.tree_at(lambda p: p.count, path, jnp.asarray(0))
        path = lax.while_loop(lambda p: (p.y[-1] < goal) & p.can_go_on(jnp.inf), lambda p: advance(p, goal), path)
        return path, (path.y, path.y[-1] >= goal, path.failed)

    _, (states, reached, failed) = lax.scan(to, _start_path(mesh, step), travels)
    return states, reached, failed


class Crossings(eqx.Module):
    """The equilibria under force levels (k,) found on a followed path: ``states``
    (k, size), ``found`` (the path carried the level), ``converged`` (its force-held solve
    did), and the path's end: ``failed`` (a step did not converge), ``at_end`` (it reached
    the largest travel). A level the path never carried holds the path's last state and
    force (``forces``), itself an equilibrium under that force."""

    states: jax.Array
    forces: jax.Array
    found: jax.Array
    converged: jax.Array
    failed: jax.Array
    at_end: jax.Array


def first_crossings(mesh, params, levels, max_travel, step):
    """The equilibria at the first crossing of each of ``levels`` (k,) (N, > 0) on the path
    followed from the undeformed dome (first step ``step``, m) up to the travel
    ``max_travel`` (m). The first loop turn linearises the undeformed dome for its tangent
    (a Newton call with no step, not a step of the path); each later turn makes one Newton
    solve: a step of the path with the travel held, or, once a step has carried a level,
    that level's solve with the force held, from the cubic Hermite interpolant of the
    step's two ends (their states, forces and tangents along the path), the lower end
    moving up to each level solved below the next; so one compiled Newton serves all
    three. Not differentiated (see :func:`implicit`)."""
    k = levels.shape[0]
    blank = jnp.zeros((k, mesh.size))
    on_level = lambda mask, now, old: jnp.where(mask.reshape((k,) + (1,) * (now.ndim - 1)), now, old)  # noqa: E731

    def cond(carry):
        path, _, found, solved, _, _ = carry
        return jnp.any(found & ~solved) | (~jnp.all(found) & path.can_go_on(max_travel))

    def body(carry):
        # The path does not move while levels it crossed are pending: they all lie
        # between ``before`` and ``path``.
        path, before, found, solved, c, started = carry
        # The first turn works out the undeformed dome's tangent: its linearisation at
        # travel 0, no Newton step (so the compiled loop holds the one linearisation).
        starting = ~started
        pending = found & ~solved
        level = jnp.argmax(pending)
        solving = pending[level]
        guess, d_new, max_iter, jump = _path_guess(path, max_travel, params[1])
        guess = jnp.where(solving, _hermite_guess(before, path, levels[level]), guess)
        max_iter = jnp.where(solving, NEWTON_MAX_ITER, jnp.where(starting, 0, max_iter))
        d_new = jnp.where(starting, 0.0, d_new)
        mask, held, force = _control(mesh, solving, jnp.where(solving, levels[level], d_new))
        y, ok, iterations, H, reaction, shift = newton(mesh, mask, held, force, params, guess, max_iter, path.shift)
        just = jnp.arange(k) == level
        # A solved level's state, inside the step, is a closer lower end for the levels
        # still pending above it: their Hermite guesses span less of the step, and each
        # level needs fewer Newton iterations than from the step's start.
        still = pending & ~just
        above = jnp.all(jnp.where(still, levels >= levels[level], True))
        closer = solving & ok & jnp.any(still) & above & (y[-1] > before.y[-1]) & (y[-1] < path.y[-1])
        tangent = lax.cond(
            starting | (ok & (~solving | closer)), lambda: _tangent(mesh, H), lambda: (path.tangent, path.stiffness)
        )

        c = eqx.tree_at(
            lambda c: (c.states, c.converged),
            c,
            (
                on_level(just & solving, jnp.broadcast_to(y, blank.shape), c.states),
                jnp.where(just & solving, ok, c.converged),
            ),
        )
        new = _path_update(params, path, y, reaction, tangent, ok & ~solving, iterations, jump, shift)
        new = jax.tree.map(lambda a, b: jnp.where(solving, b, a), new, path)
        with_tangent = eqx.tree_at(lambda p: (p.tangent, p.stiffness), path, tangent)
        new = jax.tree.map(lambda a, b: jnp.where(starting, a, b), with_tangent, new)
        crossed = ~starting & ~solving & ok & ~found & (new.force >= levels)
        before = jax.tree.map(lambda a, b: jnp.where(jnp.any(crossed), a, b), path, before)
        solved_point = eqx.tree_at(lambda p: (p.y, p.force, p.tangent, p.stiffness), before, (y, reaction, *tangent))
        before = jax.tree.map(lambda a, b: jnp.where(closer, a, b), solved_point, before)
        return new, before, found | crossed, solved | (just & solving), c, jnp.asarray(True)

    none = jnp.zeros(k, bool)
    c = Crossings(blank, levels, none, none, jnp.asarray(False), jnp.asarray(False))
    start = _start_path(mesh, step)
    path, _, found, _, c, _ = lax.while_loop(cond, body, (start, start, none, none, c, jnp.asarray(False)))
    return Crossings(
        states=on_level(found, c.states, jnp.broadcast_to(path.y, blank.shape)),
        forces=jnp.where(found, levels, path.force),
        found=found,
        converged=jnp.where(found, c.converged, ~path.failed),
        failed=path.failed,
        at_end=path.y[-1] >= max_travel,
    )
