"""The finite-strain layer (magdesign.mechanics.finite_layer) at a large press, against an
independent finite-element model written here.

The reference shares nothing with the package's element code: 8-node serendipity
quadrilaterals (displacement only, 3 x 3 Gauss points) in the meridian section of the
axisymmetric layer, the same strain energy W = mu / 2 (J^(-2/3) I1 - 3) + K / 2 (J - 1)^2
written out from F (hoop stretch 1 + u_r / r), the rigid frictionless sphere as a penalty
(kappa / 2) max(g, 0)^2 on the depth g of the top surface's points inside the sphere (six
Gauss points per edge, its depth d a further unknown, force control: the potential
energy minus Fn d), and Newton's method on element Hessians (jax.hessian) assembled in a
scipy sparse matrix, in equal force steps with a backtracking line search on the energy.
The layer is the package's: bonded at z = 0, u_r = 0 on the axis, u = 0 at the rim r = 6 h
(moving the rim to 10 h changes the package's answer by < 0.1 % of the peak:
test_finite_layer.py). The bulk modulus is K = 10 mu (nu = 0.45), so that displacement-only
quadratic elements do not lock; the penalty stiffness is the package's, kappa = 1000 mu / h,
so that both depths contain the same penalty penetration (about p h / (1000 mu); with a
penalty ten times stiffer the reference's depth is 0.42 % smaller and its centre's u_z
0.29 % of the peak, measured once: a part of the model both share, not an error here).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from magdesign.mechanics import NeoHookean
from magdesign.mechanics.finite_layer import LAYER_MESH_ERROR, press_displacement, press_layer

MU, H, SPHERE = 100e3, 2e-3, 2e-3  # Pa, m, m
K = 10 * MU  # Pa: nu = 0.45, compressible enough for displacement-only elements
KAPPA = 1000 * MU / H  # Pa / m: the package's penalty (CONTACT_PENALTY mu / h), restated
FORCE = 0.3  # N: depth / R = 0.198, contact radius a / h = 0.49 (measured)
RIM = 6.0  # the mesh's rim, in h
NEWTON_RTOL = 1e-7  # largest nodal out-of-balance force over Fn at which Newton stops
COARSE, FINE = (16, 10, 6), (32, 20, 12)  # (elements over r <= 1.5 h, beyond it, through h)

_CORNERS = ((-1, -1), (1, -1), (1, 1), (-1, 1))
_MIDSIDES = ((0, -1), (1, 0), (0, 1), (-1, 0))


def q8_shape(xi, eta):
    """Serendipity shape functions (8,) at (xi, eta) and their derivatives (8, 2): corners
    (counter-clockwise), then the mid-sides (bottom, right, top, left). numpy, so that
    collecting this module computes nothing with JAX."""
    n, dn = [], []
    for a, b in _CORNERS:
        n.append(0.25 * (1 + xi * a) * (1 + eta * b) * (xi * a + eta * b - 1))
        dn.append([0.25 * a * (1 + eta * b) * (2 * xi * a + eta * b), 0.25 * b * (1 + xi * a) * (xi * a + 2 * eta * b)])
    for a, b in _MIDSIDES:
        if a == 0:
            n.append(0.5 * (1 - xi**2) * (1 + eta * b))
            dn.append([-xi * (1 + eta * b), 0.5 * b * (1 - xi**2)])
        else:
            n.append(0.5 * (1 + xi * a) * (1 - eta**2))
            dn.append([0.5 * a * (1 - eta**2), -eta * (1 + xi * a)])
    return np.array(n), np.array(dn)


_g3, _w3 = np.polynomial.legendre.leggauss(3)
GAUSS = np.array([[a, b] for a in _g3 for b in _g3])
GAUSS_W = np.outer(_w3, _w3).ravel()
N_G = np.stack([q8_shape(*p)[0] for p in GAUSS])  # (9, 8)
DN_G = np.stack([q8_shape(*p)[1] for p in GAUSS])  # (9, 8, 2)
_g6, EDGE_W = np.polynomial.legendre.leggauss(6)
EDGE_N = np.stack([0.5 * _g6 * (_g6 - 1), 1 - _g6**2, 0.5 * _g6 * (_g6 + 1)], -1)  # (6, 3): nodes at -1, 0, 1
EDGE_DN = np.stack([_g6 - 0.5, -2 * _g6, _g6 + 0.5], -1)


def q8_mesh(n_inner, n_outer, n_z, inner=1.5):
    """(nodes (n, 2) reference (r, z) (m), elements (e, 8), top edges (t, 3)): n_inner equal
    elements over r <= inner h, n_outer growing geometrically out to RIM h, n_z through h."""
    first, span = inner * H / n_inner, (RIM - inner) * H
    q = 1.1
    for _ in range(200):  # growth ratio whose n_outer steps, the first about `first`, fill the span
        q = (span / first * (q - 1) + 1) ** (1 / n_outer)
    steps = first * q ** np.arange(1, n_outer + 1)
    r_corner = np.concatenate(
        [np.linspace(0, inner * H, n_inner + 1), inner * H + np.cumsum(steps * span / steps.sum())]
    )
    z_corner = np.linspace(0, H, n_z + 1)

    def with_midpoints(c):
        out = np.empty(2 * c.size - 1)
        out[0::2], out[1::2] = c, 0.5 * (c[1:] + c[:-1])
        return out

    r_all, z_all = with_midpoints(r_corner), with_midpoints(z_corner)
    index = -np.ones((r_all.size, z_all.size), int)
    nodes = []
    for i in range(r_all.size):
        for j in range(z_all.size):
            if not (i % 2 and j % 2):  # serendipity: no centre node
                index[i, j] = len(nodes)
                nodes.append((r_all[i], z_all[j]))
    elements, top = [], []
    for e in range(r_corner.size - 1):
        for f in range(z_corner.size - 1):
            i, j = 2 * e, 2 * f
            ij = [
                (i, j),
                (i + 2, j),
                (i + 2, j + 2),
                (i, j + 2),
                (i + 1, j),
                (i + 2, j + 1),
                (i + 1, j + 2),
                (i, j + 1),
            ]
            elements.append([index[a, b] for a, b in ij])
        top.append([index[2 * e, -1], index[2 * e + 1, -1], index[2 * e + 2, -1]])
    return np.array(nodes), np.array(elements), np.array(top)


def element_energy(X, u, mu, bulk):
    """Strain energy (J) of one ring element: X (8, 2) reference (r, z) (m), u (8, 2) (u_r, u_z) (m)."""
    jac = jnp.einsum("gak,ai->gik", DN_G, X)
    dn = jnp.einsum("gak,gki->gai", DN_G, jnp.linalg.inv(jac))
    f = jnp.eye(2) + jnp.einsum("ai,gaj->gij", u, dn)
    r = N_G @ X[:, 0]
    hoop = 1 + (N_G @ u[:, 0]) / r
    j = (f[:, 0, 0] * f[:, 1, 1] - f[:, 0, 1] * f[:, 1, 0]) * hoop
    i1 = jnp.sum(f * f, axis=(1, 2)) + hoop**2
    w = 0.5 * mu * (j ** (-2.0 / 3.0) * i1 - 3) + 0.5 * bulk * (j - 1) ** 2
    return jnp.sum(GAUSS_W * jnp.linalg.det(jac) * 2 * jnp.pi * r * w)


def edge_energy(X, ud):
    """Penalty energy (J) of one top edge: X (3, 2) its nodes' (r, z) (m), ud their (u_r, u_z)
    (6,) and the sphere's depth d (m), its lowest point at z = h - d."""
    x = EDGE_N @ (X + ud[:6].reshape(3, 2))
    inside = SPHERE - jnp.sqrt(x[:, 0] ** 2 + (H + SPHERE - ud[6] - x[:, 1]) ** 2)
    ring = 2 * jnp.pi * (EDGE_N @ X[:, 0]) * jnp.abs(EDGE_DN @ X[:, 0])
    return jnp.sum(EDGE_W * ring * 0.5 * KAPPA * jnp.maximum(inside, 0.0) ** 2)


def _with_derivatives(energy):
    return jax.jit(jax.vmap(lambda X, u: (energy(X, u), jax.grad(energy, 1)(X, u), jax.hessian(energy, 1)(X, u))))


_ELEMENTS = _with_derivatives(lambda X, u: element_energy(X, u, MU, K))
_EDGES = _with_derivatives(edge_energy)


def q8_press(force, shape, steps=6):
    """(nodes (n, 2), displacements (n, 2) (m), depth d (m), elements) of the reference layer
    pressed with ``force`` (N), in ``steps`` equal force steps."""
    X, el, top = q8_mesh(*shape)
    n = len(X)
    held = np.zeros((n, 2), bool)
    held[np.isclose(X[:, 1], 0)] = True
    held[np.isclose(X[:, 0], RIM * H)] = True
    held[np.isclose(X[:, 0], 0), 0] = True
    unknown = np.concatenate([np.flatnonzero(~held.ravel()), [2 * n]])  # the free dofs and d
    e_dofs = (2 * el[:, :, None] + np.arange(2)).reshape(len(el), 16)
    c_dofs = np.concatenate(
        [(2 * top[:, :, None] + np.arange(2)).reshape(len(top), 6), np.full((len(top), 1), 2 * n)], 1
    )
    X_el, X_top = jnp.asarray(X[el]), jnp.asarray(X[top])

    def evaluate(y, f):
        """(energy, gradient, sparse Hessian) of the potential energy at y under f."""
        ee, ge, he = _ELEMENTS(X_el, jnp.asarray(y[e_dofs].reshape(-1, 8, 2)))
        ec, gc, hc = _EDGES(X_top, jnp.asarray(y[c_dofs]))
        gradient = np.zeros(2 * n + 1)
        np.add.at(gradient, e_dofs, np.asarray(ge).reshape(-1, 16))
        np.add.at(gradient, c_dofs, np.asarray(gc))
        gradient[-1] -= f
        rows = np.concatenate([np.repeat(e_dofs, 16, 1).ravel(), np.repeat(c_dofs, 7, 1).ravel()])
        cols = np.concatenate([np.tile(e_dofs, 16).ravel(), np.tile(c_dofs, 7).ravel()])
        hessian = sp.csr_matrix((np.concatenate([np.ravel(he), np.ravel(hc)]), (rows, cols)), (2 * n + 1,) * 2)
        return float(jnp.sum(ee) + jnp.sum(ec)) - f * y[-1], gradient, hessian

    y = np.zeros(2 * n + 1)
    nu = (3 * K - 2 * MU) / (2 * (3 * K + MU))
    a = (3 * force / steps * SPHERE * (1 - nu) / (8 * MU)) ** (1 / 3)
    y[-1] = a * a / SPHERE  # Hertz's depth of the first step: a first contact
    for k in range(1, steps + 1):
        f = force * k / steps
        for _ in range(60):
            energy, gradient, hessian = evaluate(y, f)
            residual = gradient[unknown]
            if np.max(np.abs(residual)) < NEWTON_RTOL * f:
                break
            step = -spla.spsolve(hessian[unknown][:, unknown].tocsc(), residual)
            t = 1.0
            while t > 1e-4:  # backtracking until the energy falls (Armijo)
                trial = y.copy()
                trial[unknown] += t * step
                if evaluate(trial, f)[0] <= energy + 1e-4 * t * (residual @ step):
                    break
                t /= 2
            y = trial
        else:
            raise AssertionError(f"the reference's Newton did not converge at {f} N")
    return X, y[:-1].reshape(n, 2), y[-1], el


def q8_displacement(X, el, U, points):
    """(u_r, u_z) (m) at ``points`` (m, 2) (r, z) of the reference mesh (rectangular elements,
    mid-side nodes at the middles: an affine map to (xi, eta))."""
    out = []
    for p in points:
        for e in el:
            low, high = X[e].min(axis=0), X[e].max(axis=0)
            if np.all(low <= p) and np.all(p <= high):
                xi, eta = 2 * (p - low) / (high - low) - 1
                out.append(q8_shape(xi, eta)[0] @ U[e])
                break
    return np.array(out)


def test_the_reference_element_integrates_a_homogeneous_stretch_exactly():
    """The reference's own check: u = (e_r r, e_z z) in a ring element (r from 1 to 2 mm, z
    from 0 to 1 mm) is F = diag(1 + e_r, 1 + e_z, 1 + e_r) everywhere, so its energy is
    W(F) times the ring's volume pi (r2^2 - r1^2) dz, W written out by hand here; and the
    shape functions' derivatives are their central differences."""
    corners = np.array([[1e-3, 0], [2e-3, 0], [2e-3, 1e-3], [1e-3, 1e-3]])
    X = np.concatenate([corners, 0.5 * (corners + np.roll(corners, -1, axis=0))])
    e_r, e_z = 0.1, -0.3
    u = np.stack([e_r * X[:, 0], e_z * X[:, 1]], -1)
    j = (1 + e_r) ** 2 * (1 + e_z)
    w = 0.5 * MU * (j ** (-2 / 3) * (2 * (1 + e_r) ** 2 + (1 + e_z) ** 2) - 3) + 0.5 * K * (j - 1) ** 2
    volume = np.pi * ((2e-3) ** 2 - (1e-3) ** 2) * 1e-3
    np.testing.assert_allclose(float(element_energy(jnp.asarray(X), jnp.asarray(u), MU, K)), w * volume, rtol=1e-13)
    # the shape functions' derivatives, written by hand, are their central differences (N is
    # quadratic along each axis, so the difference is exact but for rounding)
    step = 1e-3
    for xi, eta in [(0.3, -0.7), (-0.9, 0.1)]:
        _, dn = q8_shape(xi, eta)
        d_xi = (q8_shape(xi + step, eta)[0] - q8_shape(xi - step, eta)[0]) / (2 * step)
        d_eta = (q8_shape(xi, eta + step)[0] - q8_shape(xi, eta - step)[0]) / (2 * step)
        np.testing.assert_allclose(dn, np.stack([d_xi, d_eta], -1), atol=1e-10)


@pytest.mark.slow
def test_a_large_press_matches_the_independent_reference():
    """Expected before running: the two models agree to their discretisation errors, the
    package's LAYER_MESH_ERROR (1 % of the peak displacement; measured below 0.5 %) and
    the reference's (its coarse mesh against its fine one, twice as many elements along r
    and z; the fine one's are h / 21 along r under the contact). Measured (0.3 N, K = 10 mu): depths 395.58 um (package),
    395.40 um (reference, coarse), 395.75 um (fine): 0.045 % apart; the displacements at
    the points below agree to 0.25 % of the peak with the fine mesh (0.68 % with the coarse
    one), the largest at the contact's edge (r = h / 2, a / h = 0.49); the reference's
    coarse and fine meshes differ by 0.44 % of the peak."""
    material = NeoHookean(mu=MU, bulk=K)
    press = press_layer(normal_force=FORCE, sphere_radius=SPHERE, thickness=H, material=material)
    points = np.array([[r * H, H] for r in (0, 0.25, 0.5, 0.75, 1, 2)] + [[0, H / 2], [H / 2, H / 2], [H, H / 2]])
    package = np.asarray(press_displacement(press, points))
    (X, U, coarse_depth, el), (Xf, Uf, fine_depth, elf) = (q8_press(FORCE, shape) for shape in (COARSE, FINE))
    coarse, fine = q8_displacement(X, el, U, points), q8_displacement(Xf, elf, Uf, points)
    peak = np.max(np.abs(fine))
    assert 0.19 < fine_depth / SPHERE  # a large press: depth / R about 0.2
    reference_error = np.max(np.abs(coarse - fine)) / peak
    assert reference_error < 0.01  # measured 0.0044
    assert abs(float(press.depth) - fine_depth) < 0.005 * fine_depth  # measured 0.045 %
    assert np.max(np.abs(package - fine)) < LAYER_MESH_ERROR * peak  # measured 0.25 % of the peak
