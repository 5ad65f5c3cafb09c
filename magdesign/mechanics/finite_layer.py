"""A neo-Hookean (or Mooney-Rivlin) layer bonded to a rigid base and pressed by a rigid
sphere: the finite-strain counterpart of :mod:`magdesign.mechanics.skin_layer`'s linear
layer under a normal load (SI: m, N, Pa).

The layer (thickness h, any :class:`~magdesign.mechanics.materials.AbstractHyperelastic`,
nearly incompressible as elastomers are) fills 0 <= z <= h with u = 0 on the base z = 0
and a free top surface, pressed on the axis r = 0 by a frictionless rigid sphere of
radius R with the normal force Fn (force control). It is the dome's axisymmetric
finite-strain model (:mod:`magdesign.mechanics._axisymmetric`: Q9/P3 mixed elements,
exact tangent, Newton, implicit derivatives) on a rectangular meridian mesh
(:mod:`magdesign.mechanics._axisymmetric.layer_mesh`): out to R = 6 h, where the
displacement is held at 0 (a bonded layer's displacement decays like e^(-0.85 r / h)
beyond the contact; moving that rim to 10 h changes the answer well below the
discretisation error), the contact resolved by elements of about h / 20 at the axis.

The load is applied in LAYER_LOAD_STEPS equal force steps, each a Newton solve from the
last; the equilibrium is then differentiated implicitly, so the depth and the
displacements are differentiable in the force, h, R and the material's constants, in
forward and reverse mode, whatever the iterations did.

Reach: any depth that the elements resolve and Newton reaches (below); at a / h = 0.2 and 0.5 (a the contact
radius) the default mesh is within 1 % of the peak displacement of a mesh twice as fine
in each direction (:data:`LAYER_MESH_ERROR`), and at small loads (a / R = 0.025) within
1 % of the linear layer's displacements under Hertz's pressure (at a / h = 0.5 away from
the contact: there Hertz's pressure is not the layer's, tests/mechanics/test_finite_layer.py).
At a skin's loads it departs from the linearised layer: under examples/skin.toml's press
(a 2 mm layer of 100 kPa, a 2 mm sphere, 0.2 N, a / R about 0.46) the centre goes 3.4 %
deeper. At a large press (K = 10 mu, depth / R = 0.2, a / h = 0.49) its depth is within
0.05 % and its displacements within 0.25 % of the peak of an independent model (8-node
serendipity elements, tests/mechanics/test_finite_layer_reference.py). Its Newton solves
do not always converge in LAYER_LOAD_STEPS steps at deeper presses (measured, a 2 mm layer
under a 2 mm sphere: 0.3 N converges with K = 10 mu, 1 N does not with K = 100 mu, does with
K = 1000 mu): :func:`press_layer`
then raises (or, with throw=False, reports it in its result), and a scene flags the load
point (:func:`press_converged`). Cost: one solve compiles in 10-15 s and runs in 0.1-0.5 s
on one core (41 x 13 nodes, 1066 unknowns). A flat punch is not modelled here.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
from jax import lax
from jaxtyping import Array, ArrayLike, Bool, Float

from magdesign._numerics import safe_div
from magdesign._validation import check_positive
from magdesign.mechanics import _axisymmetric
from magdesign.mechanics._axisymmetric import equilibrium
from magdesign.mechanics._axisymmetric.layer_mesh import LayerMesh
from magdesign.mechanics.materials import AbstractHyperelastic

# The layer mesh (elements along r over r <= h, along r beyond it to 6 h, through the
# thickness): the contact's elements are about h / 20 at the axis, and the depth and the
# displacements are within LAYER_MESH_ERROR of the (24, 16, 12) mesh's at a / h = 0.2 and 0.5.
DEFAULT_LAYER_MESH = (12, 8, 6)
# Relative difference of the default mesh's depth and displacements from a mesh twice as fine
# in each direction, measured at a / h = 0.2 and 0.5 (tests/mechanics/test_finite_layer.py).
LAYER_MESH_ERROR = 0.01
# Equal force steps from the unloaded layer: at the largest loads a skin meets (a / R
# about 0.5) each step's Newton solve from the last converges in about 10 iterations.
LAYER_LOAD_STEPS = 4


class PressResult(eqx.Enumeration):
    """Outcome of a finite-strain layer solve."""

    successful = "converged"
    not_converged = (
        "the finite-strain layer did not converge: Newton left an out-of-balance force above "
        "its tolerance (DOME_RESIDUAL_TOL mu h^2) after one of its load steps"
    )


class LayerPress(eqx.Module):
    """The equilibrium of a layer pressed by a sphere (:func:`press_layer`).

    Attributes:
        depth: the sphere's travel from first touch (m): the indentation depth (the
            penalty contact's own penetration, about p h / (1000 mu), included).
        displacements: (rows, cols, 2) nodal (u_r, u_z) (m) of the mesh; read them
            anywhere with :func:`press_displacement`.
        thickness: h (m).
        result: a :class:`PressResult`.
        mesh: the mesh's shape (static).
    """

    depth: Float[Array, ""]
    displacements: Float[Array, "rows cols 2"]
    thickness: Float[Array, ""]
    result: PressResult
    mesh: tuple = eqx.field(static=True)


@functools.cache
def layer_mesh(shape: tuple) -> LayerMesh:
    """The :class:`LayerMesh` of a shape (n_inner, n_outer, n_depth[, inner, extent]), one
    object per shape, so that its programs are traced once."""
    return LayerMesh(*shape)


@eqx.filter_jit
def _press(sphere_radius, thickness, material, force, shape):
    mesh = layer_mesh(shape)
    params = (sphere_radius, thickness, material)
    fixed = lax.stop_gradient(params)
    mask, held = mesh.mask(True), jnp.zeros(mesh.size)
    step = lax.stop_gradient(force) / LAYER_LOAD_STEPS
    R, h, mat = fixed
    # first guess of the first step's depth: Hertz's incompressible half-space, at most h / 4
    a = (3.0 * step * R / (16.0 * mat.shear_modulus)) ** (1.0 / 3.0)
    y0 = held.at[-1].set(jnp.minimum(a * a / R, h / 4))

    def one_step(carry, k):
        y, ok = carry
        y, converged, _, _, _, _ = equilibrium.newton(mesh, mask, held, step * k, fixed, y, equilibrium.NEWTON_MAX_ITER)
        return (y, ok & converged), None

    (y, ok), _ = lax.scan(one_step, (y0, jnp.asarray(True)), jnp.arange(1, LAYER_LOAD_STEPS + 1.0))
    y = _axisymmetric.implicit(mesh, "force", params, force[None], y[None])[0]
    result = PressResult.where(ok, PressResult.successful, PressResult.not_converged)
    return y, result


def press_layer(
    *,
    normal_force: Float[ArrayLike, ""],
    sphere_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractHyperelastic,
    mesh: tuple = DEFAULT_LAYER_MESH,
    throw: bool = True,
) -> LayerPress:
    """The finite-strain layer of ``thickness`` h (m) and ``material`` pressed by a rigid
    frictionless sphere of radius R (m) with ``normal_force`` Fn (N, > 0) (module docstring).

    Differentiable in Fn, R, h and the material's constants. ``throw``: raise where Newton
    did not converge (else the :class:`LayerPress` carries the result).
    """
    check_positive(normal_force=normal_force, unit="N")
    check_positive(sphere_radius=sphere_radius, thickness=thickness, unit="m")
    if not isinstance(material, AbstractHyperelastic):
        raise TypeError(f"material must be a hyperelastic material (NeoHookean, MooneyRivlin), got {material!r}")
    args = jax.tree.map(lambda x: jnp.asarray(x, dtype=float), (sphere_radius, thickness, material, normal_force))
    y, result = _press(*args, tuple(mesh))
    m = layer_mesh(tuple(mesh))
    displacements = (y[:-1] * m.free_u).reshape(m.rows, m.cols, 2)
    depth = y[-1]
    if throw:
        depth = result.error_if(depth, result != PressResult.successful)
    return LayerPress(depth=depth, displacements=displacements, thickness=args[1], result=result, mesh=tuple(mesh))


def _quadratic(x):
    """Quadratic Lagrange basis at nodes -1, 0, 1: (..., 3)."""
    return jnp.stack([x * (x - 1) / 2, 1 - x * x, x * (x + 1) / 2], axis=-1)


def press_displacement(press: LayerPress, points: Float[ArrayLike, "... 2"]) -> Float[Array, "... 2"]:
    """(u_r, u_z) (m), shape (..., 2), at ``points`` (..., 2) = (r, z) (m) of the reference
    layer (r from the sphere's axis, 0 <= z <= h from the base), interpolated with the
    elements' shape functions; 0 beyond the mesh's rim (r > 6 h). Differentiable in the
    points and in everything the press is."""
    mesh = layer_mesh(press.mesh)
    points = jnp.asarray(points, dtype=float)
    h = press.thickness
    r, z = points[..., 0] / h, jnp.clip(points[..., 1] / h, 0.0, 1.0)
    r_corners, z_corners = jnp.asarray(mesh.rho[0::2]), jnp.asarray(mesh.zeta[0::2])
    i = jnp.clip(jnp.searchsorted(r_corners, r, side="right") - 1, 0, r_corners.size - 2)
    j = jnp.clip(jnp.searchsorted(z_corners, z, side="right") - 1, 0, z_corners.size - 2)
    xi = 2.0 * (r - r_corners[i]) / (r_corners[i + 1] - r_corners[i]) - 1.0
    eta = 2.0 * (z - z_corners[j]) / (z_corners[j + 1] - z_corners[j]) - 1.0
    rows = 2 * i[..., None] + jnp.arange(3)  # (..., 3)
    cols = 2 * j[..., None] + jnp.arange(3)
    nodal = press.displacements[rows[..., :, None], cols[..., None, :]]  # (..., 3, 3, 2)
    u = jnp.einsum("...a,...b,...abk->...k", _quadratic(xi), _quadratic(eta), nodal)
    return jnp.where((r <= r_corners[-1])[..., None], u, 0.0)


def press_converged(
    normal_force: Float[ArrayLike, "..."],
    *,
    sphere_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractHyperelastic,
    force_floor: float,
    mesh: tuple = DEFAULT_LAYER_MESH,
) -> Bool[Array, "..."]:
    """Whether the finite-strain layer's Newton solves converged under each ``normal_force``
    Fn (N, (...,)), shape (...,): the solve :func:`press_field` makes at max(Fn,
    ``force_floor``) (N). Traceable at any Fn >= 0 (no check of its inputs); the solve
    depends on the force alone, not on where the sphere presses."""
    force = jnp.asarray(normal_force, dtype=float)
    args = jax.tree.map(lambda x: jnp.asarray(x, dtype=float), (sphere_radius, thickness, material))

    def one(applied):
        _, result = _press(*args, applied, tuple(mesh))
        return result == PressResult.successful

    flat = jnp.maximum(force, force_floor).reshape(-1)
    return jax.vmap(one)(flat).reshape(force.shape)


def press_field(
    points: Float[ArrayLike, "... 3"],
    *,
    centre: Float[ArrayLike, "2"],
    normal_force: Float[ArrayLike, ""],
    sphere_radius: Float[ArrayLike, ""],
    thickness: Float[ArrayLike, ""],
    material: AbstractHyperelastic,
    force_floor: float,
    mesh: tuple = DEFAULT_LAYER_MESH,
) -> tuple[Float[Array, "... 3"], Float[Array, "... 3"], Float[Array, ""]]:
    """The press of a sphere centred at ``centre`` (x, y) (m) on the finite-strain layer, as
    a 3-D field: (displacement u (m), rotation curl(u) / 2 (rad), each (..., 3), at
    ``points`` (..., 3) = (x, y, z) of the reference layer (m, z from the base); converged,
    a bool). For a force below ``force_floor`` (N, > 0) the layer is solved at the floor and
    the field scaled by Fn / floor (linear in Fn there, 0 at rest), so that it can be traced
    (no check of its inputs) at any Fn >= 0. The rotation about the load's axis is
    (du_r / dz - du_z / dr) / 2 along e_theta, 0 on the axis (symmetry)."""
    force = jnp.asarray(normal_force, dtype=float)
    applied = jnp.maximum(force, force_floor)
    args = jax.tree.map(lambda x: jnp.asarray(x, dtype=float), (sphere_radius, thickness, material))
    y, result = _press(*args, applied, tuple(mesh))
    m = layer_mesh(tuple(mesh))
    press = LayerPress(
        depth=y[-1],
        displacements=(y[:-1] * m.free_u).reshape(m.rows, m.cols, 2),
        thickness=args[1],
        result=result,
        mesh=tuple(mesh),
    )
    points = jnp.asarray(points, dtype=float)
    relative = points[..., :2] - jnp.asarray(centre, dtype=float)
    r = jnp.sqrt(jnp.sum(relative * relative, axis=-1))
    rz = jnp.stack([r, points[..., 2]], axis=-1).reshape(-1, 2)
    meridian = jax.vmap(lambda p: press_displacement(press, p))
    u_rz = meridian(rz)
    gradient = jax.vmap(jax.jacfwd(lambda p: press_displacement(press, p)))(rz)  # (n, 2 (u_r, u_z), 2 (r, z))
    swirl = 0.5 * (gradient[:, 0, 1] - gradient[:, 1, 0])
    scale = force / applied
    u_rz, swirl = (scale * u_rz).reshape(r.shape + (2,)), (scale * swirl).reshape(r.shape)
    cos, sin = safe_div(relative[..., 0], r), safe_div(relative[..., 1], r)
    u = jnp.stack([u_rz[..., 0] * cos, u_rz[..., 0] * sin, u_rz[..., 1]], axis=-1)
    rotation = jnp.stack([-swirl * sin, swirl * cos, jnp.zeros_like(swirl)], axis=-1)
    return u, rotation, result == PressResult.successful
