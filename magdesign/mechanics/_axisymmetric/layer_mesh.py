"""The meridian mesh of a finite-strain layer bonded to a rigid base and pressed by a
rigid sphere: the dome's elements, energy, tangent, Newton solve and implicit derivatives
(:mod:`.equilibrium`) on another body.

Geometry. The layer fills 0 <= Z <= h, 0 <= R <= L in the meridian section (axis R = 0),
meshed with 9-node quadrilaterals on a rectangular grid: node rows i along R (the axis
first), node columns j along Z (the base first), so that the top surface is the last
column, as the dome's outer surface is, and the tangent keeps the dome's block
tridiagonal layout (:mod:`magdesign.mechanics._blocks`). The node positions are fixed
fractions of h (``rho``, ``zeta``): element boundaries at R = h r_in s^LAYER_INNER_GRADING
over the inner region R <= r_in h (fine at the axis, where the contact is) and
R = h (r_in + (L / h - r_in) s^2) beyond it, and at Z = h (1 - (1 - s)^LAYER_DEPTH_GRADING)
(fine under the top surface); mid-nodes halfway, so every element is a rectangle.

Boundary conditions. Bonded base: u = 0 on Z = 0. Axis: u_r = 0 on R = 0 (symmetry). Outer
rim R = L: u = 0, the bonded layer's displacement having decayed there (it falls like
e^(-0.85 R / h) beyond the contact; the default L = 6 h holds the answer to the rim's
condition well within the discretisation error: tests/mechanics/test_finite_layer.py).

Contact. A rigid frictionless sphere of radius R_s, on the axis, its lowest point at
Z = h - d (d its travel from first touch, m, the last unknown): penalty energy
(kappa / 2) ramp(g)^2 per reference area of the top surface at 3 Gauss points per edge,
g = R_s - |x - c| the depth of the current point x = (r, z) inside the sphere (centre
c = (0, h + R_s - d)), ramp the dome's smoothed max(g, 0), kappa = CONTACT_PENALTY mu / h.
Its gradient is along the sphere's normal (frictionless) and acts on u_r and u_z alike.

Parameters of the equilibrium functions: params = (sphere radius R_s (m), thickness h (m),
material), so that :func:`.equilibrium._tolerance` (mu h^2) and the penalty read the
thickness where the dome's read its wall.
"""

import jax.numpy as jnp
import numpy as np

from magdesign._numerics import CONTACT_SMOOTHING, smooth_ramp
from magdesign.mechanics import _blocks
from magdesign.mechanics._axisymmetric.mesh import (
    _EDGE_DN,
    _EDGE_N,
    _EDGE_W,
    CONTACT_PENALTY,
    _assembly_tables,
    element_parts,
    grid_tables,
)

# Grading exponents of the layer mesh: element boundaries at r_in s^1.5 in the inner
# region (the contact's elements smallest at the axis) and at 1 - (1 - s)^1.5 through the
# thickness (smallest under the top surface, where the contact pressure varies over the
# contact radius a, often a fifth of h).
LAYER_INNER_GRADING = 1.5
LAYER_DEPTH_GRADING = 1.5


class LayerMesh:
    """Static index tables of a layer mesh: ``n_inner`` elements along R over the inner
    region R <= ``inner`` h, ``n_outer`` beyond it to R = ``extent`` h, ``n_depth``
    through the thickness (module docstring).

    The state vector y (n_dof + 1,) holds the nodal displacements (node (i, j) at
    2 (i cols + j), u_r then u_z) and, last, the sphere's travel d (m).
    """

    def __init__(self, n_inner: int, n_outer: int, n_depth: int, inner: float = 1.0, extent: float = 6.0):
        if not 0.0 < inner < extent:
            raise ValueError(f"the inner region (R <= {inner} h) must lie inside the mesh (R <= {extent} h)")
        self.shape = (n_inner, n_outer, n_depth, inner, extent)
        n_rows = n_inner + n_outer
        grid_tables(self, n_rows, n_depth)
        # each edge's unknowns: (u_r, u_z) of its three nodes, then the sphere's travel
        edge = (2 * self.edge_nodes[:, :, None] + np.arange(2)).reshape(n_rows, 6)
        self.edge_dofs = np.concatenate([edge, np.full((n_rows, 1), self.n_dof)], axis=1)
        free = np.ones((self.rows, self.cols, 2))
        free[0, :, 0] = 0.0  # on the axis: u_r = 0 by symmetry
        free[:, 0, :] = 0.0  # bonded base
        free[-1, :, :] = 0.0  # outer rim, where the displacement has decayed
        self.free_u = free.ravel()
        s_in = np.arange(n_inner + 1) / n_inner
        s_out = np.arange(1, n_outer + 1) / n_outer
        corners = np.concatenate([inner * s_in**LAYER_INNER_GRADING, inner + (extent - inner) * s_out**2])
        self.rho = _with_midpoints(corners)  # (rows,) R / h of the node rows
        self.zeta = _with_midpoints(1.0 - (1.0 - np.arange(n_depth + 1) / n_depth) ** LAYER_DEPTH_GRADING)
        self.layout = _blocks.Layout(self.rows, self.cols)
        self.gradient_tables, self.hessian_tables = _assembly_tables(self)

    def mask(self, force_control: bool) -> np.ndarray:
        """1 for the unknowns of a solve, 0 for held values: (n_dof + 1,)."""
        return np.append(self.free_u, 1.0 if force_control else 0.0)

    def reference(self, thickness):
        """Reference nodal coordinates (rows cols, 2): (R, Z) in m."""
        X = jnp.stack(np.broadcast_arrays(self.rho[:, None], self.zeta[None, :]), -1)
        return thickness * X.reshape(-1, 2)

    def parts(self, params, y):
        """Per-element (X (9, 2), u (18,)) and per-edge (X (3, 2), (u_r, u_z) x 3 and d
        (7,)) arrays of state y; params = (sphere radius (m), thickness (m), material)."""
        return element_parts(self, self.reference(params[1]), y)

    def contact_args(self, params):
        """(sphere radius (m), thickness (m), penalty kappa (Pa/m), ramp width (m)):
        :meth:`edge_energy`'s."""
        sphere_radius, thickness, material = params
        kappa = CONTACT_PENALTY * material.shear_modulus / thickness
        return sphere_radius, thickness, kappa, CONTACT_SMOOTHING * thickness

    @staticmethod
    def edge_energy(X_edge, u_and_d, sphere_radius, thickness, kappa, width):
        """Penalty energy (J) of one top edge against the sphere: X_edge (3, 2) reference
        (R, Z) of its nodes, u_and_d (7,) their (u_r, u_z) (m) and the travel d (m)."""
        R = _EDGE_N @ X_edge[:, 0]
        ds = jnp.linalg.norm(_EDGE_DN @ X_edge, axis=-1)
        x = _EDGE_N @ (X_edge + u_and_d[:6].reshape(3, 2))  # current (r, z) of the points
        height = thickness + sphere_radius - u_and_d[6] - x[:, 1]  # below the sphere's centre
        depth = sphere_radius - jnp.sqrt(x[:, 0] ** 2 + height**2)
        ramp = smooth_ramp(depth, width)
        return jnp.sum(_EDGE_W * ds * 2 * jnp.pi * R * kappa / 2 * ramp**2)


def _with_midpoints(corners):
    """Node positions (2 n + 1,) of elements with boundaries ``corners`` (n + 1,)."""
    nodes = np.empty(2 * corners.size - 1)
    nodes[0::2] = corners
    nodes[1::2] = 0.5 * (corners[:-1] + corners[1:])
    return nodes
