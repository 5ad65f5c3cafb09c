"""Sets of uniformly magnetised cuboid cells placed anywhere: a magnetised elastomer layer
cut into cells, and the same cells carried by the layer's displacement field.

A layer loaded with magnetised particles (a magnetic skin) is a continuous magnetisation
J(x) = mu0 M(x). Cut into cells, each cell a uniformly magnetised cuboid, its field is the
sum of the cells' exact cuboid fields (:func:`magdesign.fields.cuboid.cuboid_tensor`); an
undeformed layer of uniform J is then exactly the one block it fills (the cells' shared
faces carry no charge).

Under a displacement field u(x) the particles move with the material: each cell's centre
moves to c + u(c), and its particles turn with the material's local rotation, the
infinitesimal rotation vector omega = curl(u) / 2 at the centre (small-strain elasticity),
applied as the rotation by |omega| about omega. A cell keeps its moment (its particles)
and its reference shape: its polarization turns, its cuboid moves. What this leaves out is
the cell's strain (its shape and volume change, which leave its moment unchanged), whose
effect on the field at a distance d is of order strain (cell / d)^2 relative to the
cell's own contribution: finer cells make it vanish.
"""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import float_array
from magdesign._validation import check_last_axis, check_positive
from magdesign.fields.cuboid import FAR_NODES, cuboid_tensor
from magdesign.frames import rotate_by_vector

# The cell kernel's far form holds FAR_NODES^3 point dipoles per (point, cell) pair until
# XLA sums them: the tensors are evaluated in batches of at most this many bytes of them.
KERNEL_BATCH_BYTES = 1 << 28
_BYTES_PER_TENSOR = 8 * 9 * FAR_NODES**3


def kernel_batches(fn, rows, tensors_per_row, bytes_per_tensor=_BYTES_PER_TENSOR):
    """``fn`` over ``rows`` (leading axis), in batches whose kernel temporaries, for
    ``tensors_per_row`` kernels per row of ``bytes_per_tensor`` each (by default a cuboid
    tensor's far form), stay within KERNEL_BATCH_BYTES."""
    size = max(1, min(rows.shape[0], KERNEL_BATCH_BYTES // (bytes_per_tensor * tensors_per_row)))
    return jax.lax.map(fn, rows, batch_size=size)


def layer_cells(
    *,
    size: Float[ArrayLike, "2"],
    thickness: Float[ArrayLike, ""],
    cells: tuple[int, int, int],
    bottom: Float[ArrayLike, ""] = 0.0,
) -> tuple[Float[Array, "n 3"], Float[Array, "3"]]:
    """The cells of a rectangular layer on a regular grid.

    Args:
        size: the layer's sides (L_x, L_y) (m), shape (2,), each > 0; centred on x = y = 0.
        thickness: h (m), > 0: the layer fills bottom <= z <= bottom + h.
        cells: (n_x, n_y, n_z), positive integers (static).
        bottom: the height (m) of the layer's lower face.

    Returns:
        (centres (N, 3) (m), N = n_x n_y n_z in C order over (x, y, z); dimension (3,) (m),
        the cells' sides).
    """
    grid = tuple(int(n) for n in cells)
    if len(grid) != 3 or min(grid) < 1 or any(int(n) != n for n in cells):
        raise ValueError(f"cells must be three positive integers (n_x, n_y, n_z), got {cells!r}")
    check_last_axis("size", size, 2)
    check_positive(size=size, thickness=thickness, unit="m")
    sides = jnp.concatenate([float_array(size), float_array(thickness)[None]])
    dimension = sides / jnp.asarray(grid, dtype=sides.dtype)
    # centres in units of the cell: -(n - 1)/2 .. (n - 1)/2 across x and y, 0.5 .. n_z - 0.5 up z
    index = np.indices(grid).reshape(3, -1).T.astype(float)
    offset = index - np.array([(grid[0] - 1) / 2.0, (grid[1] - 1) / 2.0, -0.5])
    centres = jnp.asarray(offset) * dimension + jnp.array([0.0, 0.0, 1.0]) * float_array(bottom)
    return centres, dimension


def cells_field(
    points: Float[ArrayLike, "... 3"],
    *,
    centres: Float[ArrayLike, "n 3"],
    dimension: Float[ArrayLike, "3"] | Float[ArrayLike, "n 3"],
    polarization: Float[ArrayLike, "n 3"],
) -> Float[Array, "... 3"]:
    """Flux density B (T) at ``points`` (m, shape (..., 3)) of N axis-aligned cuboid cells of
    sides ``dimension`` (m, (3,) for all, or (N, 3) for each: discrete magnets of their own
    sizes) centred at ``centres`` (m, (N, 3)), each of uniform
    polarization J = mu0 M (T, (N, 3)). Exact for each cell (:func:`~magdesign.fields.cuboid.cuboid`'s
    accuracy), differentiable in every argument; evaluated in batches of points so that
    memory stays bounded for many points times many cells."""
    check_last_axis("points", points, 3)
    check_last_axis("centres", centres, 3)
    check_last_axis("polarization", polarization, 3)
    points = float_array(points)
    centres, polarization = float_array(centres), float_array(polarization)
    if polarization.shape != centres.shape:
        raise ValueError(f"polarization must have the shape of centres {centres.shape}, got {polarization.shape}")

    def at(point):
        return jnp.einsum("nij,nj->i", cuboid_tensor(point - centres, dimension=dimension), polarization)

    return kernel_batches(at, points.reshape(-1, 3), centres.shape[0]).reshape(points.shape)


def moved_cells(
    centres: Float[ArrayLike, "n 3"],
    polarization: Float[ArrayLike, "n 3"],
    displacement,
) -> tuple[Float[Array, "n 3"], Float[Array, "n 3"]]:
    """The cells carried by a displacement field (module docstring).

    Args:
        centres: the cells' centres (m), shape (N, 3), undeformed.
        polarization: their polarization J (T), shape (N, 3), undeformed.
        displacement: a pointwise function of points (m, (N, 3)) returning u (m, (N, 3)),
            differentiable (e.g. :func:`magdesign.mechanics.skin_layer.layer_displacement`
            with its layer and load bound).

    Returns:
        (moved centres c + u(c) (m, (N, 3)), polarization turned by the local rotation
        curl(u) / 2 (T, (N, 3))).
    """
    centres, polarization = float_array(centres), float_array(polarization)

    def along(direction):
        return jax.jvp(displacement, (centres,), (jnp.broadcast_to(direction, centres.shape),))

    # u is pointwise: a tangent along axis j at every centre gives du/dx_j at each of them
    u, columns = jax.vmap(along, out_axes=(None, -1))(jnp.eye(3, dtype=centres.dtype))  # (N, 3), (N, 3, 3)
    curl = jnp.stack(
        [
            columns[:, 2, 1] - columns[:, 1, 2],
            columns[:, 0, 2] - columns[:, 2, 0],
            columns[:, 1, 0] - columns[:, 0, 1],
        ],
        axis=-1,
    )
    return carried_cells(centres, polarization, u, 0.5 * curl)


def carried_cells(
    centres: Float[ArrayLike, "n 3"],
    polarization: Float[ArrayLike, "n 3"],
    displacement: Float[ArrayLike, "n 3"],
    rotation: Float[ArrayLike, "n 3"],
) -> tuple[Float[Array, "n 3"], Float[Array, "n 3"]]:
    """The cells carried by given displacements and rotations at their centres (module
    docstring): what :func:`moved_cells` does with a displacement field's values.

    Args:
        centres: the cells' centres (m), shape (N, 3), undeformed.
        polarization: their polarization J (T), shape (N, 3), undeformed.
        displacement: u at each centre (m), shape (N, 3).
        rotation: the rotation vector curl(u) / 2 at each centre (rad), shape (N, 3).

    Returns:
        (moved centres c + u (m, (N, 3)), polarization turned by the rotation (T, (N, 3))).
    """
    centres, polarization = float_array(centres), float_array(polarization)
    return centres + float_array(displacement), rotate_by_vector(polarization, float_array(rotation))
