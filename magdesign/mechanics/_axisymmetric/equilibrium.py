"""The equilibrium of the axisymmetric dome under one load: its energy, tangent, Newton
solve and implicit derivatives (the mesh: :mod:`.mesh`).

Bodies. Every function here takes the mesh, which says what it meshes: its element and edge
arrays of a state (``mesh.parts(params, y)``), its contact's energy per edge
(``mesh.edge_energy(X_edge, edge_values, *mesh.contact_args(params))``) and its fixed
unknowns (``mesh.free_u``). The dome's :class:`.mesh.Mesh` is a wall under a flat plate;
:class:`.layer_mesh.LayerMesh` a layer on a rigid base under a sphere, which the same
elements, tangent, Newton solve and implicit derivatives serve (params = (a length, the
thickness, material) for both: the tolerance and the penalty read params[1] and params[2]).

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
assembled straight into the blocks of its factor (:mod:`magdesign.mechanics._blocks`).

Solution. Newton's method (the loop of :mod:`magdesign._newton`, which the saturating soft
body's solve shares) on the total potential with the exact tangent, factored as a
block tridiagonal matrix bordered by the plate travel (:mod:`magdesign.mechanics._blocks`), a Levenberg
shift only where the tangent is not positive definite, and a backtracking line search on
the potential (skipped where the decrease it would test is below the potential's rounding,
DOME_ENERGY_RESOLUTION); converged when the largest out-of-balance force is below DOME_RESIDUAL_TOL
mu t^2 (or, where float64's rounding of the forces stops Newton short of that, below
DOME_ROUNDING_SLACK times it). Two controls: the plate travel held (the natural control: it passes limit points
where the force falls) or the force held (d an unknown, Pi - F d minimised). The path
(:mod:`.path`) makes one such solve per step. Its equilibria are differentiated implicitly
(:func:`implicit`: a custom JVP solving with the same tangent, whose own derivative,
the second order that a design's Hessians take, is a rule of its own: the JVP of
:func:`state_tangent`), so derivatives with respect to geometry, material, travel and
force are exact whatever the iterations did, in forward and reverse mode and to any order.
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import lax

from magdesign import _newton
from magdesign._tracing import traced_once
from magdesign.mechanics import _blocks
from magdesign.mechanics._axisymmetric.mesh import _DN, _EDGE_N, _N, _P, _W
from magdesign.mechanics.materials import isochoric_excess

# Solver thresholds of the axisymmetric dome.
# A state is in equilibrium when its largest out-of-balance nodal force is below this
# fraction of mu t^2 (the wall's own force scale, 2.4 N for the dome-Hall sensor's dome): Newton
# converges quadratically there, so the state it leaves is exact to float64 rounding, and
# the tolerance stays above the rounding of the contact forces (the penalty times ~1e-18 m)
# and, for walls thicker than ~0.2 mm of the dome-Hall sensor's resin, of the wall's forces (see
# DOME_ROUNDING_SLACK for thinner ones).
DOME_RESIDUAL_TOL = 1e-10
# Float64 rounding of the wall's nodal forces leaves a floor of about eps K R_o^2 theta^2
# (K the bulk modulus, theta the wall's rotation: the volume change J - 1 is a small
# difference of rotation terms), measured 2e-12 N at rotations of order one whatever the
# wall, which is the tolerance itself for a 0.2 mm wall of the dome-Hall sensor's resin. A state within
# this many tolerances, whose Newton step no longer halves its out-of-balance force,
# sits on that floor and counts as converged.
DOME_ROUNDING_SLACK = 100.0
# Newton takes its full step, untested by the line search, when the decrease it predicts
# is below this fraction of the potential's magnitude: there the potential's float64
# rounding (measured up to 3e-11 relative, a thin wall's bending energy being a small
# difference of rotations) hides the decrease, and a test on the potential would refuse
# good steps (a t/R = 0.005 dome at a travel of 0.002 t stalls 20x above its tolerance).
# Near equilibrium Newton's step is exact to second order, so nothing is lost.
DOME_ENERGY_RESOLUTION = 1e-9
# First Levenberg shift (tried only when the tangent matrix is not positive definite,
# e.g. while a load step passes through a buckling-like intermediate state), as a
# fraction of each unknown's own diagonal entry (floored at this fraction of the largest);
# it grows tenfold until a Cholesky succeeds.
DOME_LEVENBERG_START = 1e-6


# Newton iterations of one solve at most: a force-held solve or a path's first step, and
# any later step of a path (a step that needs more is retried at a quarter of its length).
NEWTON_MAX_ITER = 40
# The Armijo fraction of the predicted decrease that a step must achieve (of the
# potential's decrease, where the soft body's 1e-4 is of |residual|^2: a different merit).
ARMIJO = 0.25
# Index of the largest Levenberg shift tried (each ten times the previous one; see _factor).
LEVENBERG_MAX = 12


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


def potential(mesh, y, params, force=0.0):
    """Total potential (J) of state y: elastic + contact energy - force d.

    params = (outer_radius (m), thickness (m), material); force (N).
    """
    X_elem, u_elem, X_edge, z_edge = mesh.parts(params, y)
    elastic = jax.vmap(_element_energy, (0, 0, None))(X_elem, u_elem, params[2])
    args = mesh.contact_args(params)
    contact = jax.vmap(mesh.edge_energy, (0, 0) + (None,) * len(args))(X_edge, z_edge, *args)
    return jnp.sum(elastic) + jnp.sum(contact) - force * y[-1]


@traced_once
def derivatives(mesh, y, params, with_hessian=True):
    """Gradient (size,) and Hessian (:class:`_blocks.Blocks`; None unless
    ``with_hessian``) of :func:`potential` (force 0) in y, fixed displacements held out
    (their rows and columns 0).

    The last gradient entry, dPi / dd, is the plate force (N)."""
    X_elem, u_elem, X_edge, z_edge = mesh.parts(params, y)
    element = functools.partial(_element_derivatives, with_hessian=with_hessian)
    g_elem, H_elem = jax.vmap(element, (0, 0, None))(X_elem, u_elem, params[2])
    contact = (X_edge, z_edge) + mesh.contact_args(params)
    in_axes = (0, 0) + (None,) * (len(contact) - 2)
    g_edge = jax.vmap(jax.grad(mesh.edge_energy, argnums=1), in_axes)(*contact)
    g = _blocks.gather_sum(mesh.gradient_tables, jnp.concatenate([g_elem.ravel(), g_edge.ravel()]))
    g = g.at[-1].set(jnp.sum(g_edge[:, -1]))
    if not with_hessian:
        return g, None
    H_edge = jax.vmap(jax.hessian(mesh.edge_energy, argnums=1), in_axes)(*contact)
    flat = _blocks.gather_sum(mesh.hessian_tables, jnp.concatenate([H_elem.ravel(), H_edge.ravel()]))
    return g, _blocks.Blocks.from_flat(mesh.layout, flat, jnp.sum(H_edge[:, -1, -1]))


def plate_force(mesh, y, params):
    """The plate force (N) at state y: the reaction dPi / dd."""
    return jax.grad(lambda d: potential(mesh, y.at[-1].set(d), params))(y[-1])


def contact_radius(mesh, y, params):
    """Largest current radius (m) of an outer-surface Gauss point pressed into the plate
    (0 if none): where the contact ends. Not differentiable (held constant)."""
    y, params = lax.stop_gradient((y, params))
    _, _, X_edge, z_edge = mesh.parts(params, y)
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
    longer halves it (float64's floor, see DOME_ROUNDING_SLACK)."""
    tol = _tolerance(params)
    y0 = mask * y0 + (1 - mask) * held
    unit = _unit_last(mesh)

    def energy(y):
        value = potential(mesh, y, params, force)
        return jnp.where(jnp.isfinite(value), value, jnp.inf)

    def on_floor(size, previous):
        return (size > previous / 2) & (size <= DOME_ROUNDING_SLACK * tol)

    # Each turn linearises at y (one evaluation of the derivatives in the compiled loop),
    # then steps unless y is where the solve ends; the potential at y is carried from the
    # line search that reached y (at y0 the first search evaluates it: unknown).
    def linearise(y, pi0, gave_up, state):
        previous, it, shift, _, _, _ = state
        g, H = derivatives(mesh, y, params)
        reaction = g[-1]
        g = mask * (g - force * unit)
        size = jnp.max(jnp.abs(g))
        stopped = gave_up | on_floor(size, previous)
        done = ~(size > tol) | (it >= max_iter) | stopped  # a NaN residual stops it too
        return done, (g, H), (size, it + jnp.where(done, 0, 1), shift, stopped, H, reaction)

    def direction(y, linear, state):
        """(Newton's step, the line search's Armijo test on the potential, skipped where
        the decrease it would test is below the potential's rounding, the state with the
        shift hint: the shift a factor last needed (one that found none keeps it))."""
        g, H = linear
        shift = state[2]
        F, used = _factor(mesh, H.restricted(mesh.layout, mask), jnp.maximum(shift - 1, 1))
        dy = _blocks.solve(mesh.layout, F, g)
        slope = jnp.dot(g, dy)

        def too_long(alpha, trial, pi0):
            resolved = slope > DOME_ENERGY_RESOLUTION * jnp.abs(pi0)
            return resolved & (trial > pi0 - ARMIJO * alpha * slope)

        hint = jnp.where((used > 0) & F.finite(), used, shift)
        return -dy, too_long, (*state[:2], hint, *state[3:])

    state = (jnp.inf, 0, jnp.asarray(shift), False, _blocks.Blocks.zeros(mesh.layout), jnp.zeros(()))
    y, _, state, _ = _newton.newton(linearise, direction, energy, y0, jnp.nan, state, known=False)
    size, iterations, shift, stopped, H, reaction = state
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

    # linearize, not jvp: reverse mode transposes this body (state_tangent's) equation by
    # equation, and a jvp of the jitted gradient is one jitted call with the primal and the
    # tangent among its results, which jax 0.12's transposition takes as linear whole (a
    # product of two linear values: an error); linearize keeps the tangent's call apart
    g_dot = jax.linearize(lambda p: _gradient(mesh, y, p), params)[1](params_dot)
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
