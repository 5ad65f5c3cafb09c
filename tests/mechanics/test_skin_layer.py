"""Bonded elastic layer under a local surface load: checks against independent solutions.

- Half-space (h >> a): the closed forms of Boussinesq and Cerruti integrated over the load
  (K. L. Johnson, "Contact Mechanics", 1985, ch. 3).
- Finite thickness: an axisymmetric finite-element model of the layer written here (9-node
  quadrilaterals, the displacement expanded in Fourier harmonics cos(n theta), n = 0 for the
  pressure and n = 1 for the tangential traction; Zienkiewicz & Taylor, "The Finite Element
  Method", vol. 1, ch. on axisymmetric solids under non-symmetric loads).
- Thin incompressible layer: the lubrication limit w = h^3 lap(p) / (3 mu) of a layer bonded
  below with a shear-free top.
"""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sps
import scipy.sparse.linalg as spsl
import scipy.special as sp

from magdesign.fields.cells import layer_cells
from magdesign.mechanics.skin_layer import (
    ElasticLayer,
    SurfaceLoad,
    bessel_scaled,
    hertz_contact,
    layer_displacement,
    layer_displacement_grid,
    load_transform,
    spectral_grid,
    thin_layer_contact,
)

MU = 20e3  # Pa, a soft silicone
A = 1e-3  # m, load radius


def _load(profile, fn=0.0, ft=(0.0, 0.0), centre=(0.0, 0.0), radius=A):
    return SurfaceLoad(
        centre=jnp.asarray(centre), radius=radius, normal_force=fn, shear_force=jnp.asarray(ft), profile=profile
    )


def test_bessel_functions_match_scipy():
    x = np.concatenate([np.linspace(0.0, 30.0, 3001), np.geomspace(30.0, 1e4, 200)])
    j0, j1_x, j2_x2 = bessel_scaled(x)
    # the series and the asymptotic expansion are each good to ~1e-12 absolute (module constants)
    np.testing.assert_allclose(j0, sp.j0(x), atol=1e-11)
    np.testing.assert_allclose(j1_x * x, sp.j1(x), atol=1e-11)
    np.testing.assert_allclose(j2_x2 * x * x, sp.jv(2, x), atol=1e-11)
    np.testing.assert_allclose([j1_x[0], j2_x2[0]], [0.5, 0.125], rtol=1e-15)
    ka = np.array([0.2, 3.0, 40.0])
    np.testing.assert_allclose(load_transform("hertz", ka), 3.0 * (np.sin(ka) - ka * np.cos(ka)) / ka**3, rtol=1e-13)
    x = np.concatenate([np.linspace(0.01, 30.0, 300), np.geomspace(30.0, 3e3, 50)])
    np.testing.assert_allclose(load_transform("thin", x), 48.0 * sp.jv(3, x) / x**3, atol=1e-13)
    np.testing.assert_allclose(load_transform("thin", np.zeros(1)), 1.0, rtol=1e-15)
    np.testing.assert_allclose(load_transform("flat", x), np.sin(x) / x, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(load_transform("flat", np.zeros(1)), 1.0, rtol=1e-15)
    ka = np.array([1e-3, 0.05, 0.099])  # where the difference above loses digits: its Taylor series
    taylor = 1.0 - ka**2 / 10.0 + ka**4 / 280.0 - ka**6 / 15120.0 + ka**8 / 1330560.0
    np.testing.assert_allclose(load_transform("hertz", ka), taylor, rtol=1e-14)


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_a_flat_punch_presses_a_thick_layer_down_uniformly(nu):
    """Boussinesq's rigid flat punch on a half-space (Johnson 1985, eq. 3.36): its pressure
    Fn / (2 pi a^2 sqrt(1 - r^2 / a^2)) presses the whole face down by Fn (1 - nu) / (4 mu a).
    On a layer 1e4 a thick the base changes that by about a / h."""
    h, fn = 1e4 * A, 0.2
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    r = np.array([0.0, 0.3, 0.6, 0.8]) * A  # within a / 5 of the edge the window smooths the load (module docstring)
    w = -np.asarray(
        layer_displacement(np.stack([r, 0 * r, np.full_like(r, h)], -1), layer=layer, load=_load("flat", fn=fn))
    )
    np.testing.assert_allclose(w[:, 2], fn * (1.0 - nu) / (4.0 * MU * A), rtol=2e-4)
    np.testing.assert_allclose(w[:, 2], w[0, 2], rtol=1e-5)  # flat: the punch's face stays level


@pytest.mark.parametrize("nu", [0.3, 0.49])
@pytest.mark.slow
def test_thick_layer_is_boussinesq_half_space(nu):
    """Johnson (1985) eqs. 3.41-3.42 and 3.44: surface displacements of a half-space under a
    uniform pressure p and Hertz's pressure p0 sqrt(1 - r^2/a^2) on a circle."""
    h = 1e4 * A  # the base's effect on the surface is of order a / h = 1e-4
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    fn = 0.2
    r = np.array([0.0, 0.3, 0.7, 0.95]) * A
    pts = np.stack([r, np.zeros_like(r), np.full_like(r, h)], axis=-1)
    E = 2.0 * MU * (1.0 + nu)
    u = layer_displacement(pts, layer=layer, load=_load("uniform", fn=fn))
    p = fn / (np.pi * A**2)
    # uniform: centre 2 (1 - nu^2) p a / E; radial inside the circle -(1 - 2nu)(1 + nu) p r / (2E)
    np.testing.assert_allclose(u[0, 2], -2.0 * (1 - nu**2) * p * A / E, rtol=1e-4)
    np.testing.assert_allclose(u[:, 0], -(1 - 2 * nu) * (1 + nu) * p * r / (2 * E), rtol=1e-3, atol=1e-4 * abs(u[0, 2]))
    # the circle's edge: 4 (1 - nu^2) p a / (pi E)  (Johnson eq. 3.42b at r = a)
    edge = layer_displacement(jnp.array([A, 0.0, h]), layer=layer, load=_load("uniform", fn=fn))
    np.testing.assert_allclose(edge[2], -4.0 * (1 - nu**2) * p * A / (np.pi * E), rtol=1e-3)
    u = layer_displacement(pts, layer=layer, load=_load("hertz", fn=fn))
    p0 = 3.0 * fn / (2.0 * np.pi * A**2)
    # Hertz: u_z = pi (1 - nu^2) p0 (2a^2 - r^2) / (4 a E); u_r = -(1-2nu)(1+nu) a^2 p0 (1 - (1-r^2/a^2)^1.5) / (3 E r)
    np.testing.assert_allclose(u[:, 2], -np.pi * (1 - nu**2) * p0 * (2 * A**2 - r**2) / (4 * A * E), rtol=2e-4)
    rr = r[1:]
    ur = -(1 - 2 * nu) * (1 + nu) * A**2 * p0 * (1 - (1 - rr**2 / A**2) ** 1.5) / (3 * E * rr)
    np.testing.assert_allclose(u[1:, 0], ur, rtol=1e-3)


@pytest.mark.parametrize("nu", [0.3, 0.49])
def test_thick_layer_is_cerruti_half_space(nu):
    """Tangential load along x on a half-space.  Hertz-shaped q0 sqrt(1 - r^2/a^2):
    u_x = pi q0 (4 (2 - nu) a^2 - (4 - 3 nu) x^2 - (4 - nu) y^2) / (32 G a) (Johnson 1985,
    eq. 3.92); uniform q: u_x = (2 - nu) q a / (2 G) at the centre (Cerruti's point solution
    (1 - nu) / rho + nu x^2 / rho^3 integrated over the disc). The normal displacement is
    the reciprocal of the radial one under pressure (Betti): u_z(x) = u_r(r) x / r."""
    h = 1e4 * A
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    ft = 0.1
    xy = np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [0.3, 0.6], [-0.6, -0.3]]) * A
    pts = np.concatenate([xy, np.full((len(xy), 1), h)], axis=-1)
    u = layer_displacement(pts, layer=layer, load=_load("hertz", ft=(ft, 0.0)))
    q0 = 3.0 * ft / (2.0 * np.pi * A**2)
    x, y = xy.T
    ux = np.pi * q0 * (4 * (2 - nu) * A**2 - (4 - 3 * nu) * x**2 - (4 - nu) * y**2) / (32 * MU * A)
    np.testing.assert_allclose(u[:, 0], ux, rtol=2e-4)
    E = 2.0 * MU * (1.0 + nu)
    r = np.hypot(x[1:], y[1:])
    ur = -(1 - 2 * nu) * (1 + nu) * A**2 * q0 * (1 - (1 - r**2 / A**2) ** 1.5) / (3 * E * r)
    np.testing.assert_allclose(u[1:, 2], ur * x[1:] / r, rtol=1e-3, atol=1e-6 * ux[0])
    uniform = layer_displacement(pts[0], layer=layer, load=_load("uniform", ft=(ft, 0.0)))
    np.testing.assert_allclose(uniform[0], (2 - nu) * ft / (np.pi * A) / (2 * MU), rtol=1e-4)
    # a load along y is the load along x turned by 90 degrees
    turned = layer_displacement(pts[:, [1, 0, 2]] * np.array([-1, 1, 1]), layer=layer, load=_load("hertz", ft=(0, ft)))
    np.testing.assert_allclose(turned, u[:, [1, 0, 2]] * np.array([-1, 1, 1]), rtol=1e-12, atol=1e-12 * ux[0])


# ----------------------------------------------------------------------------------------
# Independent finite-element model of the layer (Fourier harmonic n of an axisymmetric body)

_GAUSS3 = np.polynomial.legendre.leggauss(3)


def _q9(xi, eta):
    """Shape functions of the 9-node quadrilateral and their derivatives at (xi, eta)."""

    def one(t):
        return np.array([t * (t - 1) / 2, 1 - t * t, t * (t + 1) / 2]), np.array([t - 0.5, -2 * t, t + 0.5])

    nx, dx = one(xi)
    ny, dy = one(eta)
    return np.outer(nx, ny).ravel(), np.outer(dx, ny).ravel(), np.outer(nx, dy).ravel()


def _axisymmetric_fe(h, nu, a, profile, harmonic, r_edges, z_edges):
    """Displacement amplitudes (U, V, W) (m) on the node grid of a layer bonded at z = 0 and
    free at r = R, under a unit normal force pressing down (harmonic 0) or a unit tangential
    force along x (harmonic 1): u_r = U cos(n theta), u_theta = V sin(n theta),
    u_z = W cos(n theta). Returns (r nodes (nr,), z nodes (nz,), U, V, W each (nz, nr))."""
    mids = 0.5 * (r_edges[:-1] + r_edges[1:])
    r_nodes = np.append(np.stack([r_edges[:-1], mids], 1).ravel(), r_edges[-1])
    z_nodes = np.append(np.stack([z_edges[:-1], 0.5 * (z_edges[:-1] + z_edges[1:])], 1).ravel(), z_edges[-1])
    nz = len(z_edges) - 1
    nr_n, nz_n = len(r_nodes), len(z_nodes)
    ndof = 3 * nr_n * nz_n
    D = np.diag([0.0, 0.0, 0.0, MU, MU, MU])
    D[:3, :3] = 2 * MU * nu / (1 - 2 * nu) * np.ones((3, 3)) + 2 * MU * np.eye(3)
    n = harmonic
    rows, cols, vals = [], [], []
    xg, wg = _GAUSS3
    for ie in range(len(r_edges) - 1):
        for je in range(nz):
            ir, jz = 2 * ie + np.arange(3), 2 * je + np.arange(3)
            nodes = (jz[None, :] * nr_n + ir[:, None]).ravel()  # local index 3 i_r + j_z, as in _q9
            jr, jzz = (r_nodes[ir[2]] - r_nodes[ir[0]]) / 2, (z_nodes[jz[2]] - z_nodes[jz[0]]) / 2
            ke = np.zeros((27, 27))
            for gi, wi in zip(xg, wg):
                for gj, wj in zip(xg, wg):
                    N, dNx, dNy = _q9(gi, gj)
                    r = N @ np.repeat(r_nodes[ir], 3)
                    Nr, Nz = dNx / jr, dNy / jzz
                    B = np.zeros((6, 27))  # strains e_r, e_z, e_theta, g_rz, g_rtheta, g_ztheta
                    B[0, 0::3] = Nr
                    B[1, 2::3] = Nz
                    B[2, 0::3], B[2, 1::3] = N / r, n * N / r
                    B[3, 0::3], B[3, 2::3] = Nz, Nr
                    B[4, 0::3], B[4, 1::3] = -n * N / r, Nr - N / r
                    B[5, 1::3], B[5, 2::3] = Nz, -n * N / r
                    ke += B.T @ D @ B * r * jr * jzz * wi * wj
            dofs = (3 * nodes[:, None] + np.arange(3)).ravel()
            rows.append(np.repeat(dofs, 27))
            cols.append(np.tile(dofs, 27))
            vals.append(ke.ravel())
    # the theta integral of cos^2 (n theta): 2 pi for n = 0, pi for n >= 1
    K = sps.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(ndof, ndof))
    K = K * (2 * np.pi if n == 0 else np.pi)
    # the load on the top edge, 8-point Gauss per element edge (an element edge sits at r = a)
    f = np.zeros(ndof)
    xl, wl = np.polynomial.legendre.leggauss(8)
    top = (nz_n - 1) * nr_n
    for ie in np.flatnonzero(r_edges[:-1] < a):
        r0, r1 = r_edges[ie], r_edges[ie + 1]
        r, w = 0.5 * (r1 - r0) * xl + 0.5 * (r1 + r0), 0.5 * (r1 - r0) * wl
        if profile == "uniform":
            q = np.full_like(r, 1 / (np.pi * a**2))
        else:
            q = np.sqrt(1 - r**2 / a**2) * 3 / (2 * np.pi * a**2)
        N = np.stack([xl * (xl - 1) / 2, 1 - xl * xl, xl * (xl + 1) / 2])  # (3, 8)
        nodal = N @ (q * r * w)  # int q N r dr
        node = top + 2 * ie + np.arange(3)
        if n == 0:
            f[3 * node + 2] -= 2 * np.pi * nodal  # pressure pushes down
        else:
            f[3 * node] += np.pi * nodal  # t_r = q cos(theta)
            f[3 * node + 1] -= np.pi * nodal  # t_theta = -q sin(theta)
    # constraints: u = 0 on the base; on the axis U = 0 (n = 0) or W = 0, V = -U (n = 1)
    node_r = np.tile(np.arange(nr_n), nz_n)
    node_z = np.repeat(np.arange(nz_n), nr_n)
    keep = np.ones(ndof, bool)
    keep[np.flatnonzero(np.repeat(node_z == 0, 3))] = False
    axis = np.flatnonzero((node_r == 0) & (node_z > 0))
    if n == 0:
        keep[3 * axis] = False
        keep[1::3] = False
    else:
        keep[3 * axis + 2] = False
        keep[3 * axis + 1] = False
    columns = -np.ones(ndof, int)
    columns[keep] = np.arange(keep.sum())
    T_rows, T_cols, T_vals = list(np.flatnonzero(keep)), list(columns[keep]), [1.0] * int(keep.sum())
    if n == 1:
        T_rows += list(3 * axis + 1)
        T_cols += list(columns[3 * axis])
        T_vals += [-1.0] * len(axis)
    T = sps.csr_matrix((T_vals, (T_rows, T_cols)), shape=(ndof, int(keep.sum())))
    u = T @ spsl.spsolve((T.T @ K @ T).tocsc(), T.T @ f)
    U, V, W = (u[i::3].reshape(nz_n, nr_n) for i in range(3))
    return r_nodes, z_nodes, U, V, W


def _fe_mesh(a, h):
    """Element edges in r and z. In r: a / 16 or h / 16 (the smaller) up to 1.5 a, an edge
    at r = a, then growing by 1.15 per element to a + 8 h (a bonded layer's displacement
    decays over about h). In z: the same fine size at the loaded top, growing by 1.3 per
    element towards the base."""
    fine = min(a, h) / 16
    inner = np.unique(np.concatenate([np.arange(0, a, fine), [a], np.arange(a, 1.5 * a, fine)]))
    edges, step = list(inner), fine
    while edges[-1] < a + 8 * h:
        step *= 1.15
        edges.append(edges[-1] + step)
    depth, step = [0.0], fine
    while depth[-1] + step < h:
        depth.append(depth[-1] + step)
        step *= 1.3
    return np.array(edges), h - np.append(depth, h)[::-1]


@pytest.mark.parametrize(
    ("a_over_h", "profile", "nu"),
    [(0.5, "hertz", 0.3), (2.0, "hertz", 0.3), (2.0, "uniform", 0.3), (1.0, "hertz", 0.45)],
)
@pytest.mark.slow
def test_pressure_matches_axisymmetric_fe(a_over_h, profile, nu):
    """Normal load on layers of a / h = 0.5, 1 and 2 against the harmonic-0 finite elements.

    The tolerance, 0.2 % of the largest displacement, is the finite-element model's own error
    (halving its elements changes its values by less than 0.05 % at nu = 0.3; the nu = 0.45
    model, which locks slightly, moves more)."""
    h = 1e-3
    a = a_over_h * h
    r, z, U, _, W = _axisymmetric_fe(h, nu, a, profile, 0, *_fe_mesh(a, h))
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    cols = np.flatnonzero(r <= 3 * a)[::4]
    if profile == "uniform":
        cols = cols[r[cols] != a]
    for row in (-1, np.argmin(np.abs(z - h / 2))):  # the top surface and mid-depth
        pts = np.stack([r[cols], np.zeros(len(cols)), np.full(len(cols), z[row])], -1)
        u = layer_displacement(pts, layer=layer, load=_load(profile, fn=1.0, radius=a))
        scale = np.max(np.abs(W[-1]))
        np.testing.assert_allclose(u[:, 2], W[row, cols], atol=2e-3 * scale)
        np.testing.assert_allclose(u[:, 0], U[row, cols], atol=2e-3 * scale)
        np.testing.assert_allclose(u[:, 1], 0.0, atol=1e-15)


@pytest.mark.parametrize(("a_over_h", "profile"), [(1.0, "hertz"), (2.0, "uniform")])
def test_shear_matches_fourier_fe(a_over_h, profile):
    """Tangential load along x against the harmonic-1 finite elements: u_x = U, u_z = W on the
    x axis (theta = 0) and u_x = -V on the y axis (theta = 90 degrees). Tolerance and the
    node at r = a under the uniform disc as in the pressure test above."""
    h, nu = 1e-3, 0.3
    a = a_over_h * h
    r, z, U, V, W = _axisymmetric_fe(h, nu, a, profile, 1, *_fe_mesh(a, h))
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    cols = np.flatnonzero(r <= 3 * a)[::4]
    if profile == "uniform":
        cols = cols[r[cols] != a]
    load = _load(profile, ft=(1.0, 0.0), radius=a)
    scale = np.max(np.abs(U[-1]))
    for row in (-1, np.argmin(np.abs(z - h / 2))):
        zz = np.full(len(cols), z[row])
        on_x = layer_displacement(np.stack([r[cols], 0 * zz, zz], -1), layer=layer, load=load)
        on_y = layer_displacement(np.stack([0 * zz, r[cols], zz], -1), layer=layer, load=load)
        np.testing.assert_allclose(on_x[:, 0], U[row, cols], atol=2e-3 * scale)
        np.testing.assert_allclose(on_x[:, 2], W[row, cols], atol=2e-3 * scale)
        np.testing.assert_allclose(on_y[:, 0], -V[row, cols], atol=2e-3 * scale)
        np.testing.assert_allclose(on_y[:, 1:], 0.0, atol=1e-12 * scale)


def test_fe_mesh_convergence_behind_the_tolerance():
    """The finite-element model's discretisation error, which sets the tolerance above."""
    h, a = 1e-3, 2e-3
    meshes = [_fe_mesh(a, h)]
    meshes.append([np.sort(np.concatenate([e, 0.5 * (e[:-1] + e[1:])])) for e in meshes[0]])
    (r, _, U0, _, W0), (r1, _, U1, _, W1) = (_axisymmetric_fe(h, 0.3, a, "hertz", 0, *m) for m in meshes)
    scale = np.max(np.abs(W1))
    assert np.max(np.abs(np.interp(r, r1, W1[-1]) - W0[-1])) < 5e-4 * scale
    assert np.max(np.abs(np.interp(r, r1, U1[-1]) - U0[-1])) < 5e-4 * scale


@pytest.mark.parametrize("a_over_h", [20.0, 40.0, 160.0])
def test_thin_incompressible_layer_is_lubrication_limit(a_over_h):
    """A thin incompressible layer bonded below and shear-free on top squeezes out like a
    lubricating film: w = h^3 lap(p) / (3 mu) (the half-Poiseuille flow u_r = p' (z^2/2 - h z)
    / mu carried through the thickness). Under Hertz's pressure lap(p) = -2 p0 / a^2 at the
    centre, so w(0) = -2 p0 h^3 / (3 mu a^2); the next term is of relative order (h / a)^2:
    the tolerance 10 (h / a)^2 falls from 2.5 % to 4e-4 over these layers (the computed
    excess is 8.0, 7.4 and 7.2 (h / a)^2)."""
    a, fn = 2e-3, 0.5
    h = a / a_over_h
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=0.5)
    w = layer_displacement(jnp.array([0.0, 0.0, h]), layer=layer, load=_load("hertz", fn=fn, radius=a))[2]
    p0 = 3 * fn / (2 * np.pi * a**2)
    np.testing.assert_allclose(w, -2 * p0 * h**3 / (3 * MU * a**2), rtol=10 / a_over_h**2)


def test_incompressible_is_the_limit_and_bulk_strain_vanishes():
    h, a = 2e-3, 1.5e-3
    pts = jnp.array([[0.3e-3, -0.2e-3, 1.8e-3], [1.0e-3, 0.5e-3, 1.2e-3], [2.5e-3, 0.0, 0.4e-3]])
    load = _load("hertz", fn=0.3, ft=(0.1, -0.05), radius=a)

    def u(nu, p=pts):
        return layer_displacement(p, layer=ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu), load=load)

    # displacements are smooth through nu = 0.5: the step from 0.4999 is of order 1e-4 of them
    np.testing.assert_allclose(u(0.4999), u(0.5), atol=1e-3 * np.max(np.abs(u(0.5))))
    # incompressible: div u = 0 inside the layer (central differences, step 1e-6 m)
    d = 1e-6
    div = sum((u(0.5, pts + d * e)[:, i] - u(0.5, pts - d * e)[:, i]) / (2 * d) for i, e in enumerate(np.eye(3)))
    grad_scale = np.max(np.abs(u(0.5))) / h
    np.testing.assert_allclose(div, 0.0, atol=1e-6 * grad_scale)


def test_shapes_jit_vmap():
    layer = ElasticLayer(thickness=2e-3, shear_modulus=MU, poisson_ratio=0.49)
    load = _load("uniform", fn=0.2, ft=(0.05, 0.02), centre=(1e-3, -0.5e-3))
    pts = jnp.stack(jnp.meshgrid(jnp.linspace(-3e-3, 3e-3, 4), jnp.linspace(-2e-3, 2e-3, 5), indexing="ij"), -1)
    pts = jnp.concatenate([pts, jnp.full(pts.shape[:-1] + (1,), 1.5e-3)], -1)  # (4, 5, 3)
    u = layer_displacement(pts, layer=layer, load=load)
    assert u.shape == (4, 5, 3)
    np.testing.assert_allclose(jax.jit(lambda p: layer_displacement(p, layer=layer, load=load))(pts), u, rtol=1e-12)
    np.testing.assert_allclose(layer_displacement(pts[1, 2], layer=layer, load=load), u[1, 2], rtol=1e-12)
    # linear in the forces: the parts add up
    parts = [
        _load("uniform", fn=0.2, centre=(1e-3, -0.5e-3)),
        _load("uniform", ft=(0.05, 0.0), centre=(1e-3, -0.5e-3)),
        _load("uniform", ft=(0.0, 0.02), centre=(1e-3, -0.5e-3)),
    ]
    total = sum(layer_displacement(pts, layer=layer, load=part) for part in parts)
    np.testing.assert_allclose(total, u, rtol=1e-12, atol=1e-15)
    # the base does not move
    base = layer_displacement(pts.at[..., 2].set(0.0), layer=layer, load=load)
    np.testing.assert_allclose(base, 0.0, atol=1e-12 * np.max(np.abs(u)))


@pytest.mark.slow
def test_derivatives_match_finite_differences():
    """Differentiable in h, mu, nu, a, the forces and the load centre: jax.grad against
    central differences (relative step 1e-6; the quadrature nodes move with a, so the
    derivative is that of the discrete sum, smooth). Also on the load's axis, where the
    Bessel functions are evaluated through r^2 and the derivative stays finite."""

    def f(params, point):
        h, mu, nu, a, fn, ft, cx = params
        layer = ElasticLayer(thickness=h, shear_modulus=mu, poisson_ratio=nu)
        load = SurfaceLoad(
            centre=jnp.stack([cx, 0.0]), radius=a, normal_force=fn, shear_force=jnp.stack([ft, 0.0]), profile="hertz"
        )
        u = layer_displacement(point, layer=layer, load=load)
        return u[0] + 2.0 * u[1] + u[2]

    x0 = jnp.array([2e-3, MU, 0.45, 1e-3, 0.3, 0.1, 0.2e-3])
    grad, f = jax.jit(jax.grad(f)), jax.jit(f)
    for point in (jnp.array([0.8e-3, 0.3e-3, 1.7e-3]), jnp.array([0.2e-3, 0.0, 1.7e-3])):  # the second on the axis
        g = grad(x0, point)
        assert np.all(np.isfinite(g))
        for i in range(len(x0)):
            step = 1e-6 * x0[i]
            e = jnp.zeros_like(x0).at[i].set(step)
            fd = (f(x0 + e, point) - f(x0 - e, point)) / (2 * step)
            np.testing.assert_allclose(g[i], fd, rtol=2e-5, err_msg=f"parameter {i}")


def test_hertz_contact_fits_the_sphere_on_a_thick_layer():
    """Hertz's contact radius, checked through the displacement field: on a thick layer
    (a / h = 0.01) the surface under the contact follows the sphere,
    u_z(r) = -(delta - r^2 / (2 R)); the base takes about a / h off the depth."""
    h, R, fn = 0.1, 5e-3, 0.2
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=0.49)
    contact = hertz_contact(normal_force=fn, sphere_radius=R, layer=layer)
    a = contact.radius
    np.testing.assert_allclose(contact.peak_pressure * 2 * np.pi * a**2 / 3, fn, rtol=1e-14)
    r = np.array([0.0, 0.4, 0.8]) * a
    pts = jnp.stack([r, 0 * r, jnp.full(3, h)], -1)
    u = layer_displacement(pts, layer=layer, load=_load("hertz", fn=fn, radius=a))
    # a / h = 0.01 leaves a base effect of that order on the rigid-body part delta
    shape = u[:, 2] - u[0, 2]
    np.testing.assert_allclose(shape, r**2 / (2 * R), rtol=1e-3)
    np.testing.assert_allclose(-u[0, 2], contact.depth, rtol=2e-2)


@pytest.mark.slow
def test_far_points_and_quadrature_convergence():
    """Beyond a few thicknesses the bonded layer hardly moves; the default nodes agree with
    four times as many (a window twice as wide, panels half as wide) up to r / a = 39, to 1e-5
    of the largest displacement; at the load's edge r = a, which each window smooths over its
    own width (module docstring), to 1e-3."""
    from magdesign.mechanics.skin_layer import make_quadrature

    h, a = 2e-3, 1e-3
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=0.49)
    load = _load("hertz", fn=0.3, ft=(0.1, 0.0), radius=a)
    r = np.array([0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 39.0]) * a
    pts = np.stack([r * 0.6, r * 0.8, np.full_like(r, h)], -1)
    u = layer_displacement(pts, layer=layer, load=load)
    fine = layer_displacement(
        pts, layer=layer, load=load, quadrature=make_quadrature(s_taper=200.0, taper_width=50.0, width=0.25)
    )
    scale = np.max(np.abs(u))
    edge = r == a
    np.testing.assert_allclose(u[~edge], fine[~edge], atol=1e-5 * scale)
    np.testing.assert_allclose(u[edge], fine[edge], atol=1e-3 * scale)
    assert np.max(np.abs(u[-1])) < 1e-3 * scale  # 20 thicknesses away


@pytest.mark.parametrize("h", [25e-6, 6.25e-6])
def test_thin_layer_contact_fits_the_sphere(h):
    """The thin-layer contact (derived from the lubrication limit) checked through the
    transform solution: under the ``"thin"`` pressure the surface follows the sphere,
    u_z(r) - u_z(0) = r^2 / (2 R) for r <= a / 2 (tolerance 2 (h / a)^2) and u_z(0) = -delta
    (tolerance 20 (h / a)^2; computed 14 (h / a)^2). a / h = 21 and 42 here."""
    R, fn = 5e-3, 0.5
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=0.5)
    contact = thin_layer_contact(normal_force=fn, sphere_radius=R, layer=layer)
    a = contact.radius
    assert a / h > 20
    np.testing.assert_allclose(contact.peak_pressure * np.pi * a**2 / 3, fn, rtol=1e-14)  # int p dA = Fn
    r = np.array([0.0, 0.25, 0.5]) * a
    u = layer_displacement(jnp.stack([r, 0 * r, jnp.full(3, h)], -1), layer=layer, load=_load("thin", fn=fn, radius=a))
    tol = (h / a) ** 2
    np.testing.assert_allclose(u[1:, 2] - u[0, 2], r[1:] ** 2 / (2 * R), rtol=2 * tol)
    np.testing.assert_allclose(-u[0, 2], contact.depth, rtol=20 * tol)
    assert hertz_contact(normal_force=fn, sphere_radius=R, layer=layer).radius > 2 * a  # the layer is stiffer


def test_construction_and_validation():
    from magdesign.mechanics import LinearElastic

    layer = ElasticLayer.from_material(thickness=2e-3, material=LinearElastic(E=83e3, nu=0.49))
    np.testing.assert_allclose([layer.shear_modulus, layer.poisson_ratio], [83e3 / 2.98, 0.49], rtol=1e-15)
    with pytest.raises(ValueError, match="poisson_ratio"):
        ElasticLayer(thickness=2e-3, shear_modulus=MU, poisson_ratio=0.51)
    with pytest.raises(ValueError, match="thickness"):
        ElasticLayer(thickness=-1e-3, shear_modulus=MU, poisson_ratio=0.4)
    with pytest.raises(ValueError, match="profile"):
        _load("parabolic", fn=1.0)
    with pytest.raises(ValueError, match="radius"):
        _load("hertz", fn=1.0, radius=0.0)


def _curl_by_differences(points, layer, load, step=1e-6):
    """curl(u) / 2 of the Hankel quadrature's field by central differences of step (m)."""
    columns = []
    for axis in range(3):
        shift = np.zeros(3)
        shift[axis] = step
        plus = np.asarray(layer_displacement(points + shift, layer=layer, load=load))
        minus = np.asarray(layer_displacement(points - shift, layer=layer, load=load))
        columns.append((plus - minus) / (2 * step))
    g = np.stack(columns, axis=-1)  # (N, component, derivative)
    return 0.5 * np.stack([g[:, 2, 1] - g[:, 1, 2], g[:, 0, 2] - g[:, 2, 0], g[:, 1, 0] - g[:, 0, 1]], axis=-1)


@pytest.mark.parametrize(
    ("radius", "nu", "profile"),
    [(1.7e-3, 0.49, "hertz"), (0.5e-3, 0.49, "hertz"), (1.0e-3, 0.3, "uniform")],
)
@pytest.mark.slow
def test_grid_evaluation_matches_the_hankel_quadrature(radius, nu, profile):
    """The cells' Fourier sums (layer_displacement_grid) against the Hankel quadrature
    (layer_displacement, itself checked above against half-space and finite-element
    solutions) at every level of a 2 mm layer cut 16 x 16 x 8 (h / a = 1.2, 4 and 2), an
    off-centre load with shear along both axes; the rotation against central differences of
    the quadrature's displacement. Tolerance 1e-3 of the peak: the lattice's reach
    (SPECTRAL_REACH) and period (SPECTRAL_PADDING) leave about 1e-4 of the displacement's peak
    and 5e-4 of the rotation's."""
    size, h, cells = np.array([20e-3, 20e-3]), 2e-3, (16, 16, 8)
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=nu)
    load = _load(profile, fn=0.3, ft=(0.1, 0.05), centre=(1.3e-3, -2.1e-3), radius=radius)
    grid = spectral_grid(size=size, thickness=h, cells=cells)
    u, rotation = layer_displacement_grid(layer=layer, load=load, size=size, cells=cells, grid=grid)
    assert u.shape == rotation.shape == (16, 16, 8, 3)
    centres, _ = layer_cells(size=size, thickness=h, cells=cells)
    # every third column of cells, all levels: 6 x 6 x 8 points, near the load and far
    pick = (slice(None, None, 3), slice(None, None, 3))
    points = np.asarray(centres).reshape(16, 16, 8, 3)[pick].reshape(-1, 3)
    expected = np.asarray(layer_displacement(points, layer=layer, load=load))
    turned = _curl_by_differences(points, layer, load)
    got_u, got_rotation = np.asarray(u)[pick].reshape(-1, 3), np.asarray(rotation)[pick].reshape(-1, 3)
    np.testing.assert_allclose(got_u, expected, atol=1e-3 * np.max(np.abs(expected)))
    np.testing.assert_allclose(got_rotation, turned, atol=1e-3 * np.max(np.abs(turned)))


@pytest.mark.slow
def test_grid_evaluation_differentiates():
    """jax's derivatives of the grid's displacement and rotation along the load's position,
    forces and radius and the layer's thickness, modulus and Poisson ratio, against central
    differences of the same function (a coarse 8 x 8 x 2 layer)."""
    size, cells = jnp.array([16e-3, 12e-3]), (8, 6, 2)
    grid = spectral_grid(size=size, thickness=2e-3, cells=cells)

    @jax.jit
    def fields(q):
        layer = ElasticLayer(thickness=q[6], shear_modulus=q[7], poisson_ratio=q[8])
        load = SurfaceLoad(centre=q[:2], radius=q[5], normal_force=q[2], shear_force=q[3:5])
        u, rotation = layer_displacement_grid(layer=layer, load=load, size=size, cells=cells, grid=grid)
        return jnp.concatenate([u.ravel(), rotation.ravel()])

    q = np.array([1e-3, -0.5e-3, 0.5, 0.2, -0.1, 1.5e-3, 2e-3, MU, 0.45])
    steps = np.abs(q) * 1e-5
    jacobian = np.asarray(jax.jit(jax.jacfwd(fields))(jnp.asarray(q)))
    for i, step in enumerate(steps):
        e = np.zeros_like(q)
        e[i] = step
        difference = (np.asarray(fields(q + e)) - np.asarray(fields(q - e))) / (2 * step)
        np.testing.assert_allclose(jacobian[:, i], difference, rtol=1e-5, atol=1e-6 * np.max(np.abs(difference)))


def test_spectral_grid_follows_the_layer():
    """Periods span the layer plus SPECTRAL_PADDING thicknesses; the lattice of each level,
    its centre d below the top, reaches k d >= SPECTRAL_REACH (by hand for 20 x 10 mm,
    h = 2 mm, 16 x 8 x 4 cells: sides 1.25 mm, levels 0.25 to 1.75 mm deep)."""
    grid = spectral_grid(size=(20e-3, 10e-3), thickness=2e-3, cells=(16, 8, 4))
    assert grid.periods == (16 + 16, 8 + 16)
    # r = ceil(7 * 1.25 / (pi d)) at d = 1.75, 1.25, 0.75, 0.25 mm, bottom to top
    assert grid.refine == ((2, 2), (3, 3), (4, 4), (12, 12))
    with pytest.raises(ValueError, match="concrete"):
        jax.jit(lambda h: spectral_grid(size=(20e-3, 10e-3), thickness=h, cells=(16, 8, 4)).periods[0])(2e-3)


def _batch_case():
    """A 12 x 10 mm, 2 mm layer cut 8 x 6 in-plane, an off-centre Hertz press with shear."""
    size, h = np.array([12e-3, 10e-3]), 2e-3
    layer = ElasticLayer(thickness=h, shear_modulus=MU, poisson_ratio=0.49)
    load = _load("hertz", fn=0.2, ft=(0.05, -0.02), centre=(1e-3, 0.5e-3), radius=0.7e-3)
    return size, h, layer, load


@pytest.mark.slow  # the batch and each level run op by op: 9 to 11 s of CPU
def test_the_levels_of_one_lattice_are_one_batch():
    """Levels that share a lattice (consecutive equal refine: every level of the skin's linear
    field) are computed as one batch of heights: each level's displacement and rotation are
    those of that level alone, on a grid that mixes lattices."""
    size, h, layer, load = _batch_case()
    cells = (8, 6, 4)
    refine, levels = ((1, 1), (1, 1), (2, 3), (1, 1)), (0.1, 0.4, 0.6, 0.9)
    grid = dataclasses.replace(spectral_grid(size=size, thickness=h, cells=cells), refine=refine)
    u, rotation = layer_displacement_grid(layer=layer, load=load, size=size, cells=cells, grid=grid, levels=levels)
    for i, (level, lattice) in enumerate(zip(levels, refine)):
        alone = layer_displacement_grid(
            layer=layer,
            load=load,
            size=size,
            cells=(*cells[:2], 1),
            grid=dataclasses.replace(grid, refine=(lattice,)),
            levels=(level,),
        )
        np.testing.assert_allclose(u[:, :, i], alone[0][:, :, 0], rtol=1e-12, atol=1e-12 * np.max(np.abs(alone[0])))
        np.testing.assert_allclose(
            rotation[:, :, i], alone[1][:, :, 0], rtol=1e-12, atol=1e-12 * np.max(np.abs(alone[1]))
        )


def test_a_batch_of_levels_is_one_program_whatever_their_count():
    """The traced program of 8 levels on one lattice has as many operations as that of 2:
    its compile time does not grow with the skin's Gauss nodes."""
    size, h, layer, _ = _batch_case()

    def operations(nodes):
        """The count of operations in the program of ``nodes`` levels on one lattice."""
        grid = dataclasses.replace(spectral_grid(size=size, thickness=h, cells=(8, 6, nodes)), refine=((1, 1),) * nodes)
        heights = tuple((np.arange(nodes) + 0.5) / nodes)

        def fields(force):
            pressed = _load("hertz", fn=force, ft=(0.05, -0.02), centre=(1e-3, 0.5e-3), radius=0.7e-3)
            return layer_displacement_grid(
                layer=layer, load=pressed, size=size, cells=(8, 6, nodes), grid=grid, levels=heights
            )

        return len(jax.make_jaxpr(fields)(0.2).eqns)

    assert operations(8) == operations(2)
