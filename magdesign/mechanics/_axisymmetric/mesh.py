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

from magdesign.mechanics import _blocks

# Grading exponent of the meridian mesh (element boundaries at (pi / 2) s^GRADING).
GRADING = 2.0

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
