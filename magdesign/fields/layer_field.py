"""The field of a magnetised layer under a small displacement field, to first order in the
displacement.

The layer (sides L_x x L_y centred on x = y = 0, 0 <= z <= h) carries a polarization J(r)
that is uniform, J0, or the sinusoidal film's Halbach pattern along x (:func:`pattern`,
period T, k = 2 pi / T),

    J(x) = J0 R_y(k x) d,

the direction d at x = 0 turned about y by the angle k x (d = (0, 0, -1) is the film's
pattern of :mod:`magdesign.fields.film` in a frame whose z axis points up, J0 (-sin kx, 0,
-cos kx), strong side down; another d in the x-z plane shifts its phase). A finite layer
carries the pattern as cut by its sides: x is measured from the layer's centre, whatever the
number of periods across it, and the pattern is uniform along y.

The layer is a continuum of particles, each keeping its moment J(r') dV / mu0 while the
material moves it by u and turns it by omega = curl(u) / 2 (the limit of the rigid cells of
:mod:`magdesign.fields.cells` as they shrink). To first order in u the field is

    B(r) = B_0(r) + dB(r),
    dB(r) = int_layer [ -(u(r') . grad_r) N(r - r') J(r') + N(r - r') (omega(r') x J(r')) ] dV',

with N(d) = (3 d^ d^T - I) / (4 pi |d|^3) the dipole tensor (field per unit J dV). A
particle's strain leaves its moment unchanged, so no div u term enters. B_0, the undeformed
layer's field, is one cuboid's for a uniform layer (:func:`magdesign.fields.cuboid.cuboid`,
exact); for the pattern it is :func:`pattern_field`'s sum of slabs (its error stated there).

Numerics. Through the thickness, Gauss-Legendre nodes on [0, h]: the integrand is smooth in
z' (the rigid cells' midpoint levels are what converge slowly, as n_z^-2). In the plane, the
midpoint rule on an n_x x n_y grid over the layer, with u and omega from the layer's Fourier
sum on that grid (:func:`magdesign.mechanics.skin_layer.layer_displacement_grid`) cut at the
grid's own wavenumbers (no refinement of the lattice): the integral is the inner product of u
with the kernel N(r - r'), which is smooth on the scale of its distance from the chip (at
least the chips' depth below the layer), so u's modes beyond the grid's reach meet only
the kernel's negligible ones, and the sum over the grid of the band-limited u is exact for
every mode both resolve. The error then falls with the grid spacing over the chips' depth,
not over the contact radius, and with the Gauss nodes faster than any power. A pattern's J(x')
shifts u's wavenumbers by k, which the grid resolves where it holds several nodes per period
(the skin scene puts 8 or more).

The discretisation error is estimated from two resolutions (:func:`finer`): the in-plane
grid doubled and four more Gauss nodes; the difference of the two fields is the coarser
one's error, nearly (the finer one's is far smaller).
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import float_array
from magdesign._validation import check_last_axis
from magdesign.fields.cells import cells_field, kernel_batches, layer_cells
from magdesign.fields.cuboid import cuboid

# (n_x, n_y, Gauss nodes through the thickness): the coarser of the two resolutions the
# estimate compares goes up by these.
FINER_FACTOR = 2
FINER_NODES = 4
# Slabs of the patterned layer's B_0 per in-plane node spacing (pattern_field): at the scene's
# default resolution (nodes half the chips' depth apart) slabs an eighth of the depth wide.
SLABS_PER_NODE = 4
# Per source point the sum holds about this many float64 temporaries (the dipole field, its
# derivative along u, the turned polarization): the batches over points stay within
# fields.cells.KERNEL_BATCH_BYTES.
_BYTES_PER_SOURCE = 8 * 48


def gauss_levels(nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1] (``nodes`` of them, static): heights as
    fractions of the thickness, bottom to top, and weights summing to 1."""
    if int(nodes) != nodes or nodes < 1:
        raise ValueError(f"nodes must be a positive integer, got {nodes!r}")
    x, w = np.polynomial.legendre.leggauss(int(nodes))
    return 0.5 * (x + 1.0), 0.5 * w


def finer(resolution: tuple[int, int, int]) -> tuple[int, int, int]:
    """The resolution the estimate compares ``resolution`` (n_x, n_y, Gauss nodes) with."""
    nx, ny, nodes = resolution
    return (FINER_FACTOR * nx, FINER_FACTOR * ny, nodes + FINER_NODES)


def pattern(x: Float[ArrayLike, "..."], period, vector: Float[ArrayLike, "3"]) -> Float[Array, "... 3"]:
    """The pattern R_y(k x) v ((..., 3), the unit of ``vector``) at ``x`` (m): ``vector`` v
    ((3,), its value at x = 0, e.g. J0 d in T) turned about y by k x = 2 pi x / ``period``
    (m) (module docstring)."""
    angle = 2.0 * jnp.pi * jnp.asarray(x, dtype=float) / period
    cos, sin = jnp.cos(angle)[..., None], jnp.sin(angle)[..., None]
    v = float_array(vector)
    return jnp.concatenate(
        [cos * v[0:1] + sin * v[2:3], jnp.broadcast_to(v[1:2], cos.shape), cos * v[2:3] - sin * v[0:1]], axis=-1
    )


def pattern_field(
    points: Float[ArrayLike, "... 3"],
    *,
    size: Float[ArrayLike, "2"],
    thickness: Float[ArrayLike, ""],
    polarization: Float[ArrayLike, "3"],
    period: Float[ArrayLike, ""],
    slabs: int,
) -> Float[Array, "... 3"]:
    """B_0 (T) at ``points`` (m, (..., 3), outside the layer) of the undeformed layer carrying
    the pattern (module docstring) whose direction at x = 0 is ``polarization`` (J0 d, (3,), T).

    The layer is cut across x into uniformly magnetised slabs, each one cuboid's exact field
    (the pattern is uniform in y and z): ``slabs`` - 1 slabs of width D = L_x / ``slabs``
    centred on x_j = -L_x / 2 + j D, carrying J(x_j) / sinc(k D / 2), and a slab D / 2 wide at
    each side, carrying J at that side. The side slabs give the sides' charges J_x(+-L_x / 2)
    exactly; the 1 / sinc(k D / 2) makes the slabs' Fourier amplitude at k the pattern's, so
    that on an infinite layer what remains are the aliases at wavenumbers k - 2 pi / D and
    beyond, of relative amplitude (k D / 2) / pi: at a distance d from the layer their field is
    about J0 (k D / 2 pi) e^{-(2 pi / D - k) d}. Near the sides the slabs' jumps stand for the
    volume charge -dJ_x/dx by a midpoint rule, off by O(D^2) there. Measured against
    magpylib's cuboids refined to convergence (a 20 x 16 x 2 mm layer, T = 4 mm, along a line
    1 mm below it across both sides; tests/fields/test_layer_pattern.py): the largest error,
    under a side, is 1.6e-3, 4.2e-4 and 1.1e-4 of J0 at D = d / 2, d / 4 and d / 8, falling
    as D^2; 10 mm from the sides it is 5e-5, 1e-5 and 2e-6 of J0.

    Args:
        points: where the field is wanted (m), shape (..., 3), not inside the layer.
        size: the layer's sides (L_x, L_y) (m), shape (2,), centred on x = y = 0.
        thickness: h (m): the layer fills 0 <= z <= h.
        polarization: J0 d (T), shape (3,): the pattern's polarization at x = 0.
        period: T (m), > 0.
        slabs: the count of slab widths D across L_x (static), >= 1.

    Returns:
        B (T), the shape of ``points``.
    """
    check_last_axis("points", points, 3)
    points, polarization = float_array(points), float_array(polarization)
    size, h = float_array(size), float_array(thickness)
    width = size[0] / slabs
    inner = (jnp.arange(1, slabs) - 0.5 * slabs) * width
    x = jnp.concatenate([inner, jnp.stack([-0.5 * size[0] + 0.25 * width, 0.5 * size[0] - 0.25 * width])])
    ends = jnp.stack([-0.5 * size[0], 0.5 * size[0]])
    sinc = jnp.sinc(width / period)  # sin(k D / 2) / (k D / 2)
    strengths = jnp.concatenate([jnp.broadcast_to(1.0 / sinc, inner.shape), jnp.ones(2)])
    turned = strengths[:, None] * pattern(jnp.concatenate([inner, ends]), period, polarization)
    widths = jnp.concatenate([jnp.broadcast_to(width, inner.shape), jnp.broadcast_to(0.5 * width, (2,))])
    centres = jnp.stack([x, jnp.zeros_like(x), jnp.broadcast_to(0.5 * h, x.shape)], axis=-1)
    dimension = jnp.stack([widths, jnp.broadcast_to(size[1], x.shape), jnp.broadcast_to(h, x.shape)], axis=-1)
    return cells_field(points, centres=centres, dimension=dimension, polarization=turned)


def _dipole(d, moment):
    """N(d) moment (T per unit J dV): the dipole field at offsets d (..., 3)."""
    r2 = jnp.sum(d * d, axis=-1, keepdims=True)
    r = jnp.sqrt(r2)
    return (3.0 * d * jnp.sum(d * moment, axis=-1, keepdims=True) / r2 - moment) / (4.0 * jnp.pi * r2 * r)


def layer_field(
    points: Float[ArrayLike, "... 3"],
    *,
    size: Float[ArrayLike, "2"],
    thickness: Float[ArrayLike, ""],
    polarization: Float[ArrayLike, "3"],
    displacement: Float[ArrayLike, "nx ny nz 3"],
    rotation: Float[ArrayLike, "nx ny nz 3"],
    period: Float[ArrayLike, ""] | None = None,
) -> Float[Array, "... 3"]:
    """Flux density B (T) at ``points`` (m, (..., 3), outside the layer) of the layer moved by
    a small displacement, to first order in it (module docstring).

    Args:
        points: where the field is wanted (m), shape (..., 3), not inside the layer.
        size: the layer's sides (L_x, L_y) (m), shape (2,), centred on x = y = 0.
        thickness: h (m): the layer fills 0 <= z <= h.
        polarization: J0 (T), shape (3,): uniform, or the pattern's at x = 0.
        displacement: u (m) at the nodes, shape (n_x, n_y, n_z, 3): the in-plane centres of
            an n_x x n_y grid over the layer (:func:`magdesign.fields.cells.layer_cells`) at
            the heights :func:`gauss_levels` (n_z) h.
        rotation: curl(u) / 2 (rad) at the same nodes, shape (n_x, n_y, n_z, 3).
        period: None for a uniform layer; else the pattern's period T (m), > 0, whose B_0
            is :func:`pattern_field`'s with SLABS_PER_NODE n_x slabs.

    Returns:
        B (T), the shape of ``points``.
    """
    check_last_axis("points", points, 3)
    points, polarization = float_array(points), float_array(polarization)
    u, omega = float_array(displacement), float_array(rotation)
    nx, ny, nz = u.shape[:3]
    size, h = float_array(size), float_array(thickness)
    plane, _ = layer_cells(size=size, thickness=h, cells=(nx, ny, 1))
    heights, weights = gauss_levels(nz)
    sources = jnp.concatenate(
        [
            jnp.broadcast_to(plane.reshape(nx, ny, 1, 3)[..., :2], (nx, ny, nz, 2)),
            jnp.broadcast_to((jnp.asarray(heights) * h)[None, None, :, None], (nx, ny, nz, 1)),
        ],
        axis=-1,
    ).reshape(-1, 3)
    volume = (size[0] * size[1] * h / (nx * ny)) * jnp.tile(jnp.asarray(weights), nx * ny)[:, None]
    # each particle's own polarization J(r'): J0, or the pattern's at its x
    carried = polarization if period is None else pattern(sources[:, 0], period, polarization)
    moved = u.reshape(-1, 3) * volume
    turned = jnp.cross(omega.reshape(-1, 3), carried) * volume

    def change(point):
        offsets = point - sources
        # -(u . grad) N J: the dipole field's derivative along -u, plus N (omega x J)
        _, slope = jax.jvp(lambda d: _dipole(d, carried), (offsets,), (-moved,))
        return jnp.sum(slope + _dipole(offsets, turned), axis=0)

    flat = points.reshape(-1, 3)
    dB = kernel_batches(change, flat, sources.shape[0], _BYTES_PER_SOURCE)
    if period is None:
        block = cuboid(
            flat - jnp.stack([0.0, 0.0, 0.5 * h]),
            dimension=jnp.concatenate([size, h[None]]),
            polarization=polarization,
        )
    else:
        block = pattern_field(
            flat, size=size, thickness=h, polarization=polarization, period=period, slabs=SLABS_PER_NODE * nx
        )
    return (block + dB).reshape(points.shape)
