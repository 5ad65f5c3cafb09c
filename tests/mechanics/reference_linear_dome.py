"""Independent reference: linear-elastic hemispherical dome pressed by a rigid flat plate.

Self-contained (numpy + scipy only; nothing from ``magdesign``).  SI units throughout:
lengths in m, moduli and pressures in Pa, forces in N.

Method
------
* Axisymmetric small-strain linear elasticity, displacements (u_rho, u_z), strains
  (e_rho, e_z, e_theta = u_rho / rho, g_rhoz); stiffness K = int B^T D B 2 pi rho dA.
* 8-node serendipity quadrilaterals, full 3x3 Gauss integration, isoparametric.
  Structured mesh in (phi, r): phi = polar angle from the +z axis (apex) to pi/2 (base),
  r = radius from Ri = Ro - t to Ro.  Corner nodes at phi_k = (pi/2) (k/n_meridian)^grading
  (grading > 1 refines toward the apex), r uniform (or graded toward the outer surface with
  ``wall_grading`` > 1); mid-side nodes at the arithmetic mean of (phi, r) of their corners,
  all nodes placed exactly on the spheres (rho = r sin phi, z = r cos phi).
* Boundary conditions: u_rho = 0 on the axis (phi = 0); base annulus (phi = pi/2) clamped.
* Contact: node-to-plane, frictionless, on the outer-surface nodes, gap from the initial
  geometry: g_i = (Ro - d) - z_i - u_z,i >= 0.  K is factorised once and condensed onto the
  outer-surface u_z dofs (compliance matrix C); the LCP p >= 0, g >= 0, p.g = 0 is solved
  exactly by an active-set iteration (active nodes: g = 0; release p < 0, add g < 0; repeat
  until the set does not change).
* Plate force F = sum of the nodal contact forces p (equals the vertical base reaction).
  Contact radius = midpoint between the current radial positions of the outermost
  node in contact and the next (free) outer node, i.e. resolved to +- half a node spacing.
"""

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

_XI = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0]], float)
_G1, _W1 = np.polynomial.legendre.leggauss(3)
_GP = np.array([[a, b] for a in _G1 for b in _G1])
_GW = np.array([wa * wb for wa in _W1 for wb in _W1])


def _q8(xi, eta):
    """Q8 shape functions N (8,) and derivatives dN/d(xi, eta) (8, 2) at one point."""
    N, dN = np.zeros(8), np.zeros((8, 2))
    for a, (xa, ea) in enumerate(_XI):
        if xa != 0 and ea != 0:
            N[a] = 0.25 * (1 + xa * xi) * (1 + ea * eta) * (xa * xi + ea * eta - 1)
            dN[a, 0] = 0.25 * xa * (1 + ea * eta) * (2 * xa * xi + ea * eta)
            dN[a, 1] = 0.25 * ea * (1 + xa * xi) * (xa * xi + 2 * ea * eta)
        elif xa == 0:
            N[a] = 0.5 * (1 - xi**2) * (1 + ea * eta)
            dN[a] = [-xi * (1 + ea * eta), 0.5 * ea * (1 - xi**2)]
        else:
            N[a] = 0.5 * (1 + xa * xi) * (1 - eta**2)
            dN[a] = [0.5 * xa * (1 - eta**2), -eta * (1 + xa * xi)]
    return N, dN


def dome_mesh(outer_radius, thickness, n_wall, n_meridian, grading=1.0, wall_grading=1.0):
    """Q8 mesh of the hemispherical shell.

    Returns (xy, elems, grid): xy (n_nodes, 2) = (rho, z) in m; elems (n_elem, 8) node ids in
    the _XI order (xi along the meridian, eta outward through the wall); grid
    (2 n_meridian + 1, 2 n_wall + 1) node ids on the (phi, r) index grid (-1 = element centre,
    unused).  grid[0] = axis, grid[-1] = base, grid[:, 0] = inner, grid[:, -1] = outer surface.
    """
    Ro, Ri = outer_radius, outer_radius - thickness
    pc = 0.5 * np.pi * (np.arange(n_meridian + 1) / n_meridian) ** grading
    rc = Ro - thickness * (1 - np.arange(n_wall + 1) / n_wall) ** wall_grading
    phi = np.empty(2 * n_meridian + 1)
    phi[::2] = pc
    phi[1::2] = 0.5 * (pc[1:] + pc[:-1])
    r = np.empty(2 * n_wall + 1)
    r[::2] = rc
    r[1::2] = 0.5 * (rc[1:] + rc[:-1])
    r[0] = Ri
    P, R = np.meshgrid(phi, r, indexing="ij")
    used = ~((np.arange(phi.size)[:, None] % 2 == 1) & (np.arange(r.size)[None, :] % 2 == 1))
    grid = -np.ones(P.shape, int)
    grid[used] = np.arange(used.sum())
    xy = np.column_stack([R[used] * np.sin(P[used]), R[used] * np.cos(P[used])])
    k, j = np.meshgrid(2 * np.arange(n_meridian), 2 * np.arange(n_wall), indexing="ij")
    k, j = k.ravel(), j.ravel()
    offs = [(0, 0), (2, 0), (2, 2), (0, 2), (1, 0), (2, 1), (1, 2), (0, 1)]
    elems = np.column_stack([grid[k + dk, j + dj] for dk, dj in offs])
    return xy, elems, grid


def stiffness(xy, elems, youngs_modulus, poisson_ratio):
    """Global axisymmetric stiffness (N/m), dofs interleaved (u_rho, u_z) per node."""
    E, nu = youngs_modulus, poisson_ratio
    c = E / ((1 + nu) * (1 - 2 * nu))
    D = c * np.array([[1 - nu, nu, nu, 0], [nu, 1 - nu, nu, 0], [nu, nu, 1 - nu, 0], [0, 0, 0, 0.5 - nu]])
    X = xy[elems]  # (ne, 8, 2)
    ne = len(elems)
    Ke = np.zeros((ne, 16, 16))
    for (xi, eta), w in zip(_GP, _GW):
        N, dN = _q8(xi, eta)
        J = np.einsum("ai,eaj->eij", dN, X)  # J[e, i, j] = d x_j / d xi_i
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        dNx = np.linalg.solve(J, np.broadcast_to(dN.T, (ne, 2, 8)))  # (ne, 2, 8)
        rho = X[:, :, 0] @ N
        B = np.zeros((ne, 4, 16))
        B[:, 0, 0::2] = dNx[:, 0]
        B[:, 1, 1::2] = dNx[:, 1]
        B[:, 2, 0::2] = N[None, :] / rho[:, None]
        B[:, 3, 0::2] = dNx[:, 1]
        B[:, 3, 1::2] = dNx[:, 0]
        Ke += np.einsum("eki,kl,elj,e->eij", B, D, B, 2 * np.pi * rho * np.abs(det) * w)
    dofs = np.stack([2 * elems, 2 * elems + 1], axis=2).reshape(ne, 16)
    rows = np.repeat(dofs, 16, axis=1).ravel()
    cols = np.tile(dofs, (1, 16)).ravel()
    n = 2 * len(xy)
    return sp.coo_matrix((Ke.ravel(), (rows, cols)), shape=(n, n)).tocsr()


def solve_dirichlet(K, f, fixed, values):
    """Solve K u = f + reactions with u[fixed] = values; returns (u, reactions = K u - f)."""
    n = K.shape[0]
    u = np.zeros(n)
    u[fixed] = values
    free = np.setdiff1d(np.arange(n), fixed)
    Kf = K[free][:, free].tocsc()
    u[free] = spla.spsolve(Kf, f[free] - K[free][:, fixed] @ u[fixed])
    return u, K @ u - f


def _base_dofs(grid):
    """Dofs fixed in the dome problem: u_rho on the axis, both components on the base."""
    axis = grid[0][grid[0] >= 0]
    base = grid[-1][grid[-1] >= 0]
    return np.unique(np.concatenate([2 * axis, 2 * base, 2 * base + 1]))


def contact_lcp(C, h, max_iter=200):
    """Exact solution of the discrete contact LCP by a primal-dual active set.

    Nodal plate forces p >= 0 (N), gaps g = h + C p >= 0 (m), p . g = 0, with C (m/N) the
    condensed, symmetric positive-definite compliance of the contact dofs and h the initial
    gaps.  Returns (p, gap, iterations).
    """
    active = h < 0
    for it in range(max_iter):
        p = np.zeros(h.size)
        if active.any():
            p[active] = np.linalg.solve(C[np.ix_(active, active)], -h[active])
        gap = h + C @ p
        tol = 1e-12 * np.abs(h).max()
        new = (active & (p >= 0)) | (~active & (gap < -tol))
        if np.array_equal(new, active):
            return p, gap, it + 1
        active = new
    raise RuntimeError("contact active set did not converge")


def linear_dome_force(
    outer_radius,
    thickness,
    youngs_modulus,
    poisson_ratio,
    travel,
    n_wall=8,
    n_meridian=80,
    grading=2.5,
    wall_grading=1.5,
    return_details=False,
):
    """Plate force F (N) and contact radius (m) for plate travel ``travel`` (m).

    Mesh: n_wall x n_meridian Q8 elements, see ``dome_mesh``.  The default (8, 80, 2.5, 1.5)
    changed F by <= 0.10 % on doubling both counts, for t/Ro = 0.01..0.1, d = t/100 and t/10,
    nu = 0.3 and 0.45 (~0.2-1 s); (16, 160) takes ~1.5-4 s.

    Linear elasticity, frictionless unilateral contact with a rigid flat plate at
    z = Ro - travel, clamped base annulus; see the module docstring for the method.
    The stiffness (with the axis and base conditions) is factorised once; the compliance
    C_ij = u_z,i per unit force at outer node j is formed for the candidate outer-surface
    nodes (initial gap < 2 d, enlarged if any other outer node would penetrate) and the
    contact LCP is solved exactly on it (``contact_lcp``).
    With ``return_details`` also returns a dict (u, xy, nodal forces, base reaction, ...).
    """
    Ro, d = outer_radius, travel
    xy, elems, grid = dome_mesh(Ro, thickness, n_wall, n_meridian, grading, wall_grading)
    K = stiffness(xy, elems, youngs_modulus, poisson_ratio)
    n = K.shape[0]
    free = np.setdiff1d(np.arange(n), _base_dofs(grid))
    outer = grid[:-1, -1]  # outer-surface nodes above the clamp
    h_all = Ro - d - xy[outer, 1]  # initial gaps (m)
    lu = spla.splu(K[free][:, free].tocsc())
    reach = 2.0  # candidates: initial gap < reach * d
    while True:
        cand = outer[h_all < reach * d]
        pos = np.searchsorted(free, 2 * cand + 1)
        X = np.empty((free.size, cand.size))  # displacements per unit upward force
        for j, q in enumerate(pos):  # (column-wise: fast in SuperLU)
            e = np.zeros(free.size)
            e[q] = 1.0
            X[:, j] = lu.solve(e)
        p, _, iters = contact_lcp(X[pos], h_all[h_all < reach * d])  # downward forces (N)
        u = np.zeros(n)
        u[free] = -X @ p
        gap = h_all - u[2 * outer + 1]
        if gap.min() >= -1e-9 * d:  # no penetration outside candidates
            break
        reach *= 4.0
    force = p.sum()
    k = np.nonzero(p > 0)[0].max()  # outermost node in contact
    rho = xy[cand[k : k + 2], 0] + u[2 * cand[k : k + 2]]
    a = rho.mean()  # midway to the first free node
    if not return_details:
        return force, a
    base = grid[-1][grid[-1] >= 0]
    return (
        force,
        a,
        dict(
            u=u,
            xy=xy,
            p=p,
            gap=gap,
            contact_nodes=cand,
            iterations=iters,
            a_bracket=rho,
            base_reaction=(K @ u)[2 * base + 1].sum(),
            n_dof=n,
        ),
    )


def reissner_compliance(outer_radius, thickness, youngs_modulus, poisson_ratio):
    """Reissner thin-shell point-load compliance (m/N), R = mid-surface radius."""
    R, t, nu = outer_radius - thickness / 2, thickness, poisson_ratio
    return R * np.sqrt(3 * (1 - nu**2)) / (4 * youngs_modulus * t**2)


def lame_sphere_check(
    outer_radius, thickness, youngs_modulus, poisson_ratio, pressure, n_wall=4, n_meridian=16, grading=1.0
):
    """Validation: thick hollow sphere under internal pressure (Pa), same mesh/element code.

    Hemisphere with symmetry BCs (u_z = 0 on z = 0, u_rho = 0 on the axis); consistent
    nodal loads from the pressure on the inner surface (3-point Gauss on each quadratic
    edge).  Returns max |u_FE - u_Lame| / max |u_Lame| over all nodes.
    """
    b, a, p = outer_radius, outer_radius - thickness, pressure
    E, nu = youngs_modulus, poisson_ratio
    xy, elems, grid = dome_mesh(b, thickness, n_wall, n_meridian, grading)
    K = stiffness(xy, elems, E, nu)
    f = np.zeros(K.shape[0])
    inner = grid[:, 0]
    for k in range(0, len(inner) - 2, 2):
        ids = inner[k : k + 3]
        X = xy[ids]
        for s, w in zip(_G1, _W1):
            N = np.array([0.5 * s * (s - 1), 1 - s**2, 0.5 * s * (s + 1)])
            dN = np.array([s - 0.5, -2 * s, s + 0.5])
            x, tg = N @ X, dN @ X
            nvec = np.array([tg[1], -tg[0]])  # |nvec| = ds/dxi
            nvec *= np.sign(nvec @ x)  # traction points away from the centre
            f[2 * ids] += p * N * nvec[0] * 2 * np.pi * x[0] * w
            f[2 * ids + 1] += p * N * nvec[1] * 2 * np.pi * x[0] * w
    axis, base = grid[0][grid[0] >= 0], grid[-1][grid[-1] >= 0]
    fixed = np.unique(np.concatenate([2 * axis, 2 * base + 1]))
    u, _ = solve_dirichlet(K, f, fixed, np.zeros(fixed.size))
    R = np.hypot(xy[:, 0], xy[:, 1])
    ur = p * a**3 / (E * (b**3 - a**3)) * ((1 - 2 * nu) * R + (1 + nu) * b**3 / (2 * R**2))
    exact = np.column_stack([ur * xy[:, 0] / R, ur * xy[:, 1] / R]).ravel()
    return np.abs(u - exact).max() / np.abs(exact).max()
