"""The field of a uniformly magnetised layer under a small displacement field, to first
order in the displacement.

The layer (sides L_x x L_y centred on x = y = 0, 0 <= z <= h, polarization J0 uniform)
is a continuum of particles, each keeping its moment J0 dV / mu0 while the material moves
it by u and turns it by omega = curl(u) / 2 (the limit of the rigid cells of
:mod:`magdesign.fields.cells` as they shrink). To first order in u the field is

    B(r) = B_block(r) + dB(r),
    dB(r) = int_layer [ -(u(r') . grad_r) N(r - r') J0 + N(r - r') (omega(r') x J0) ] dV',

with B_block the undeformed block's field (one cuboid, :func:`magdesign.fields.cuboid.cuboid`,
exact) and N(d) = (3 d^ d^T - I) / (4 pi |d|^3) the dipole tensor (field per unit J dV). A
particle's strain leaves its moment unchanged, so no div u term enters.

Numerics. Through the thickness, Gauss-Legendre nodes on [0, h]: the integrand is smooth in
z' (the rigid cells' midpoint levels are what converge slowly, as n_z^-2). In the plane, the
midpoint rule on an n_x x n_y grid over the layer, with u and omega from the layer's Fourier
sum on that grid (:func:`magdesign.mechanics.skin_layer.layer_displacement_grid`) cut at the
grid's own wavenumbers (no refinement of the lattice): the integral is the inner product of u
with the kernel N(r - r'), which is smooth on the scale of its distance from the chip (at
least the chips' depth below the layer), so u's modes beyond the grid's reach meet only
the kernel's negligible ones, and the sum over the grid of the band-limited u is exact for
every mode both resolve. The error then falls with the grid spacing over the chips' depth,
not over the contact radius, and with the Gauss nodes faster than any power.

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
from magdesign.fields.cells import kernel_batches, layer_cells
from magdesign.fields.cuboid import cuboid

# (n_x, n_y, Gauss nodes through the thickness): the coarser of the two resolutions the
# estimate compares goes up by these.
FINER_FACTOR = 2
FINER_NODES = 4
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
) -> Float[Array, "... 3"]:
    """Flux density B (T) at ``points`` (m, (..., 3), outside the layer) of the layer moved by
    a small displacement, to first order in it (module docstring).

    Args:
        points: where the field is wanted (m), shape (..., 3), not inside the layer.
        size: the layer's sides (L_x, L_y) (m), shape (2,), centred on x = y = 0.
        thickness: h (m): the layer fills 0 <= z <= h.
        polarization: J0 (T), shape (3,), uniform.
        displacement: u (m) at the nodes, shape (n_x, n_y, n_z, 3): the in-plane centres of
            an n_x x n_y grid over the layer (:func:`magdesign.fields.cells.layer_cells`) at
            the heights :func:`gauss_levels` (n_z) h.
        rotation: curl(u) / 2 (rad) at the same nodes, shape (n_x, n_y, n_z, 3).

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
    moved = u.reshape(-1, 3) * volume
    turned = jnp.cross(omega.reshape(-1, 3), polarization) * volume

    def change(point):
        offsets = point - sources
        # -(u . grad) N J0: the dipole field's derivative along -u, plus N (omega x J0)
        _, slope = jax.jvp(lambda d: _dipole(d, polarization), (offsets,), (-moved,))
        return jnp.sum(slope + _dipole(offsets, turned), axis=0)

    flat = points.reshape(-1, 3)
    dB = kernel_batches(change, flat, sources.shape[0], _BYTES_PER_SOURCE)
    block = cuboid(
        flat - jnp.stack([0.0, 0.0, 0.5 * h]),
        dimension=jnp.concatenate([size, h[None]]),
        polarization=polarization,
    )
    return (block + dB).reshape(points.shape)
