"""The meridian mesh of the axisymmetric dome and its quadrature.

Geometry and mesh. The wall (radii R_o - t .. R_o, apex on the axis, base rim on z = 0) is
meshed in the meridian section with 9-node quadratic quadrilaterals on a polar grid:
``n_wall`` elements through the wall (radius rho) and ``n_meridian`` along the meridian
(polar angle phi from 0 at the apex to pi / 2 at the base), nodes on arcs. Element
boundaries sit at phi = (pi / 2) s^g, s = 0, 1/n, .., 1, with the grading exponent g:
small elements at the apex, where a light load bends the wall over a short length
~ sqrt(R t). Node (i, j) sits at phi_i, rho_j; its unknowns are the displacements (u_r, u_z) (m).
"""

import jax.numpy as jnp
import numpy as np

from magdesign._numerics import CONTACT_SMOOTHING, smooth_ramp
from magdesign.mechanics import _blocks

# Grading exponent of the meridian mesh (element boundaries at (pi / 2) s^GRADING).
GRADING = 2.0

# Penalty stiffness of the contact, kappa t / mu: the penetration it leaves is a 1/1000 of
# the wall's own compression p t / E under the contact pressure p, a small part of the
# plate travel itself (measured below 1e-4 of it, see tests/mechanics/test_dome.py);
# stiffer penalties only slow Newton down.
CONTACT_PENALTY = 1000.0

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
        grid_tables(self, n_meridian, n_wall)
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

    def parts(self, params, y):
        """Per-element (X (9, 2), u (18,)) and per-edge (X (3, 2), (u_z, d) (4,)) arrays
        of state y; params = (outer_radius (m), thickness (m), material)."""
        outer_radius, thickness, _ = params
        return element_parts(self, self.reference(outer_radius, thickness), y)

    def contact_args(self, params):
        """(outer radius (m), penalty kappa (Pa/m), ramp width (m)): :meth:`edge_energy`'s."""
        _, thickness, material = params
        return params[0], CONTACT_PENALTY * material.shear_modulus / thickness, CONTACT_SMOOTHING * thickness

    @staticmethod
    def edge_energy(X_edge, z_and_d, outer_radius, kappa, width):
        """Penalty energy (J) of one outer edge against the plate at z = R_o - d: X_edge
        (3, 2) reference (R, Z) of its nodes, z_and_d (4,) their u_z (m) and the plate travel d (m)."""
        R = _EDGE_N @ X_edge[:, 0]
        ds = jnp.linalg.norm(_EDGE_DN @ X_edge, axis=-1)
        penetration = _EDGE_N @ (X_edge[:, 1] + z_and_d[:3]) - (outer_radius - z_and_d[3])
        ramp = smooth_ramp(penetration, width)
        return jnp.sum(_EDGE_W * ds * 2 * jnp.pi * R * kappa / 2 * ramp**2)

    def reference(self, outer_radius, thickness):
        """Reference nodal coordinates (rows cols, 2): (R, Z) in m."""
        rho = outer_radius - thickness + thickness * np.arange(self.cols) / (self.cols - 1)
        X = jnp.stack([rho[None, :] * np.sin(self.phi)[:, None], rho[None, :] * np.cos(self.phi)[:, None]], -1)
        return X.reshape(-1, 2)


def grid_tables(mesh, n_rows, n_cols):
    """Set the node tables of a grid of n_rows x n_cols 9-node elements on ``mesh``:
    rows, cols (node rows 2 n_rows + 1 of 2 n_cols + 1 nodes), n_dof, size (n_dof + the
    load's unknown), elem_nodes (n_elem, 9; local node (a, b) at 3 a + b), elem_dofs
    (n_elem, 18) and edge_nodes (n_rows, 3): the edges along the last node column."""
    mesh.rows, mesh.cols = 2 * n_rows + 1, 2 * n_cols + 1
    mesh.n_dof = 2 * mesh.rows * mesh.cols
    mesh.size = mesh.n_dof + 1
    node = np.arange(mesh.rows * mesh.cols).reshape(mesh.rows, mesh.cols)
    a, b = np.arange(n_rows), np.arange(n_cols)
    rows = 2 * a[:, None, None, None] + np.arange(3)[:, None]  # (n_rows, 1, 3, 1)
    cols = 2 * b[None, :, None, None] + np.arange(3)[None, :]  # (1, n_cols, 1, 3)
    mesh.elem_nodes = node[rows, cols].reshape(n_rows * n_cols, 9)
    mesh.elem_dofs = (2 * mesh.elem_nodes[:, :, None] + np.arange(2)).reshape(-1, 18)
    mesh.edge_nodes = node[:, -1][2 * a[:, None] + np.arange(3)]


def element_parts(mesh, X, y):
    """Per-element (X (9, 2), u (18,)) and per-edge (X (3, 2), its edge_dofs' values)
    arrays of state y, X (nodes, 2) the reference nodal coordinates (m); held
    displacements enter as 0."""
    u = y[:-1] * mesh.free_u
    full = jnp.append(u, y[-1])
    return X[mesh.elem_nodes], full[mesh.elem_dofs], X[mesh.edge_nodes], full[mesh.edge_dofs]


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
