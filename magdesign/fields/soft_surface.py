"""Linear soft bodies by a surface formulation: an accurate mean magnetisation with its
error estimate.

A homogeneous linear body (relative permeability mu_r, chi = mu_r - 1) in the field of
outside sources carries no volume charge (div M = chi div H = 0 inside); its own field is
that of the surface charge sigma = M . n (A/m). The normal field just inside the surface
is H_ext . n + K' sigma - sigma / 2 (K' the adjoint double-layer operator, the normal
field of the charge elsewhere on the surface), and sigma = chi H . n there, so

    (1 / chi + 1 / 2) sigma - K' sigma = H_ext . n        on the surface.

The surface is split into flat triangles with their corners on the exact surface (a
sphere from a cube's faces, equal angles; a cylinder by angle, height and radius; a
cuboid by its faces), the cylinder's and the cuboid's panels graded towards the edges,
where sigma is singular. sigma is uniform on each triangle and the equation holds at
the centroids (collocation). K'_ij is the centroid rule far away and a 36-point rule on
the triangle's subdivision for neighbours (within NEAR_PANELS panel sizes). A flat
panel's own K'_ii would be zero; the curved surface's share is set instead by Gauss's
law, sum_i A_i K'_ij = A_j / 2 (the flux of a charge on a closed surface half inside),
which makes the answer converge like the panel size squared on smooth surfaces instead
of like the panel size.

The mean magnetisation is the moment over the body's exact volume,
M = sum_j sigma_j A_j x_j / V. Two panel sizes h_1 > h_2 (ladder levels l - 1 and l)
give M_1, M_2; the answer is Richardson's extrapolation M = M_2 + (M_2 - M_1) / (r^2 - 1),
r = h_1 / h_2, and its error estimate |M - M_2| / |M|. The extrapolation assumes the
order 2 of smooth surfaces; at a cylinder's or a cuboid's edges the error falls like
h^1.5-h^2, where the extrapolated answer's remaining error is below the estimate (the
estimate is the whole step, the remainder at most its ~0.4). Measured: see
tests/fields/test_soft_accuracy.py.

Cost: one dense (P, P) solve for P panels per level (SPHERE_PANELS etc. below); the
panels' matrix depends on the shape's proportions and the level only and is kept
(``functools.lru_cache``), so a repeated solve at other permeabilities or fields costs the
LU alone.

Not modelled here: saturation (the law is nonlinear: :mod:`magdesign.fields.soft`), the
field of the body at outside points and its co-energy (:mod:`magdesign.fields.soft`'s cells
give both).
"""

import functools
from collections.abc import Callable
from typing import Literal

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign._numerics import float_array
from magdesign._validation import check_positive
from magdesign.units import MU0

# The ladder: panels along a quarter turn (sphere: per cube face edge) per level 0, 1, ...
LADDER = (4, 6, 8, 10, 12, 16)
# Neighbours (the finer rule) within this many panel sizes of a collocation point.
NEAR_PANELS = 3.0
# Subdivisions per triangle side of the near rule (SUBDIVISIONS^2 points).
SUBDIVISIONS = 6


class SurfaceAnswer(eqx.Module):
    """A soft body's mean magnetisation from the surface formulation.

    Fields:
        magnetization: the mean magnetisation M (A/m), shape (3,), body frame.
        error: its estimated relative error |M - M_fine| / |M| (dimensionless).
        level: (static) the ladder level used (LADDER[level] panels per quarter turn).
        panels: (static) the panels of that level.
        converged: whether ``error`` meets the asked ``rtol`` (True when none was asked).
    """

    magnetization: Float[Array, "3"]
    error: Float[Array, ""]
    level: int = eqx.field(static=True)
    panels: int = eqx.field(static=True)
    converged: Float[Array, ""]


def _graded(n):
    """n + 1 points on [0, 1], dense at both ends (cosine spacing)."""
    return 0.5 - 0.5 * np.cos(np.pi * np.arange(n + 1) / n)


def _triangles(grid):
    """The two triangles of each quad of a (a, b, 3) grid of corners, (2 (a-1)(b-1), 3, 3)."""
    quads = np.stack([grid[:-1, :-1], grid[1:, :-1], grid[1:, 1:], grid[:-1, 1:]], axis=-2).reshape(-1, 4, 3)
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _sphere(m):
    """A unit-radius sphere: each cube face m x m quads of equal angles, projected."""
    a = np.tan(np.linspace(-np.pi / 4, np.pi / 4, m + 1))
    u, v = np.meshgrid(a, a, indexing="ij")
    faces = []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            grid = np.zeros(u.shape + (3,))
            grid[..., axis], grid[..., (axis + 1) % 3], grid[..., (axis + 2) % 3] = sign, u, v
            grid = grid / np.linalg.norm(grid, axis=-1, keepdims=True)
            faces.append(_triangles(grid if sign > 0 else grid[::-1]))
    return np.concatenate(faces)


def _cylinder(m, ratio):
    """A cylinder of unit radius and length 2 ratio (axis z): 4 m panels around, graded
    heights and radii (the end discs' centre rings triangles)."""
    turns = np.linspace(0.0, 2.0 * np.pi, 4 * m + 1)
    heights = ratio * (2.0 * _graded(max(2, int(round(m * np.sqrt(ratio)))) + 2) - 1.0)
    t, z = np.meshgrid(turns, heights, indexing="ij")
    parts = [_triangles(np.stack([np.cos(t), np.sin(t), z], axis=-1))]
    radii = np.sin(0.5 * np.pi * np.arange(max(2, m // 2) + 1) / max(2, m // 2))
    r, t = np.meshgrid(radii, turns, indexing="ij")
    for sign in (-1.0, 1.0):
        grid = np.stack([r * np.cos(t), r * np.sin(t), np.full_like(r, sign * ratio)], axis=-1)
        grid = grid if sign > 0 else grid[:, ::-1]
        rings = _triangles(grid)
        half = len(rings) // 2
        inner = np.arange(half) < len(turns) - 1  # the quads at r = 0: one triangle each
        parts.append(np.concatenate([rings[:half], rings[half:][~inner]]))
    return np.concatenate(parts)


def _cuboid(m, sides):
    """A cuboid of the given full sides (longest 2): each face's panels graded, m along the
    longest side (12 m^2 panels for a cube, as for a sphere)."""
    counts = [max(2, int(round(m * s / max(sides)))) for s in sides]
    faces = []
    for axis in range(3):
        b, c = (axis + 1) % 3, (axis + 2) % 3
        u, v = np.meshgrid(sides[b] * (_graded(counts[b]) - 0.5), sides[c] * (_graded(counts[c]) - 0.5), indexing="ij")
        for sign in (-1.0, 1.0):
            grid = np.zeros(u.shape + (3,))
            grid[..., axis], grid[..., b], grid[..., c] = sign * sides[axis] / 2, u, v
            faces.append(_triangles(grid if sign > 0 else grid[::-1]))
    return np.concatenate(faces)


def _subdivision(k):
    """Barycentric centroids of the k^2 equal subtriangles of a triangle, (k^2, 3)."""
    points = []
    for i in range(k):
        for j in range(k - i):
            points.append(((i + 1 / 3) / k, (j + 1 / 3) / k))
            if i + j < k - 1:
                points.append(((i + 2 / 3) / k, (j + 2 / 3) / k))
    b = np.asarray(points)
    return np.column_stack([1.0 - b.sum(axis=1), b])


@functools.lru_cache(maxsize=32)
def _panels(shape, proportions, m):
    """The panels of a ``shape`` of unit size (sphere and cylinder: unit radius; cuboid:
    longest side 2) at m per quarter turn: centroids (P, 3), unit normals (P, 3), areas
    (P,) and K' (P, P) with its Gauss-law diagonal."""
    triangles = {"sphere": lambda: _sphere(m), "cylinder": lambda: _cylinder(m, proportions[0])}.get(
        shape, lambda: _cuboid(m, np.asarray(proportions))
    )()
    centres = triangles.mean(axis=1)
    cross = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / (2.0 * area[:, None])
    apart = centres[:, None, :] - centres[None, :, :]
    distance = np.linalg.norm(apart, axis=-1)
    np.fill_diagonal(distance, 1.0)
    kernel = np.einsum("ijk,ik->ij", apart, normal) * area[None, :] / (4.0 * np.pi * distance**3)
    size = np.sqrt(2.0 * area)
    rows, cols = np.nonzero(distance < NEAR_PANELS * np.maximum(size[:, None], size[None, :]))
    rows, cols = rows[rows != cols], cols[rows != cols]
    points = np.einsum("qa,jac->jqc", _subdivision(SUBDIVISIONS), triangles[cols])
    step = centres[rows][:, None, :] - points
    near = np.einsum("pqc,pc->pq", step, normal[rows]) / (4.0 * np.pi * np.linalg.norm(step, axis=-1) ** 3)
    kernel[rows, cols] = near.mean(axis=1) * area[cols]
    kernel[np.diag_indices(len(area))] = 0.0
    kernel[np.diag_indices(len(area))] = 0.5 - (area @ kernel) / area  # Gauss's law, column by column
    return centres, normal, area, kernel


def _unit(shape, radius, height, dimension):
    """(scale (m), proportions, exact volume (m^3)) of the shape's unit panels."""
    if shape == "sphere":
        check_positive(radius=radius, unit="m")
        r = float(radius)
        return r, (), 4.0 / 3.0 * np.pi * r**3
    if shape == "cylinder":
        check_positive(radius=radius, height=height, unit="m")
        r, h = float(radius), float(height)
        return r, (round(h / (2.0 * r), 12),), np.pi * r * r * h
    if shape == "cuboid":
        sides = np.asarray(dimension, dtype=float).reshape(3)
        check_positive(dimension=sides, unit="m")
        scale = sides.max() / 2.0
        return scale, tuple(round(s, 12) for s in sides / scale), float(np.prod(sides))
    raise ValueError(f"shape must be 'cuboid', 'cylinder' or 'sphere', got {shape!r}")


def _mean(shape, scale, proportions, volume, permeability, external, m):
    centres, normal, area, kernel = _panels(shape, proportions, m)
    points = centres * scale
    field = external(points) if callable(external) else jnp.broadcast_to(float_array(external), points.shape)
    chi = jnp.asarray(permeability) - 1.0
    system = (1.0 / chi + 0.5) * jnp.eye(len(area)) - kernel
    charge = jnp.linalg.solve(system, jnp.sum(field * normal, axis=-1) / MU0)  # sigma (A/m)
    return (charge * area * scale**2) @ points / volume, len(area)


def mean_magnetization(
    shape: Literal["cuboid", "cylinder", "sphere"],
    *,
    permeability: float | Float[ArrayLike, ""],
    external: Float[ArrayLike, "3"] | Callable[[Float[Array, "p 3"]], Float[Array, "p 3"]],
    radius: float | None = None,
    height: float | None = None,
    dimension: Float[ArrayLike, "3"] | None = None,
    level: int = 2,
    rtol: float | None = None,
    throw: bool = True,
) -> SurfaceAnswer:
    """The mean magnetisation of a linear soft body (sized as :func:`magdesign.fields.soft.soft_body`
    sizes it, its own frame) with its estimated error, by the surface formulation (module
    docstring).

    Args:
        shape: "sphere" (``radius=``), "cylinder" (``radius=``, ``height=``; axis z) or
            "cuboid" (``dimension=``: full sides).
        permeability: relative permeability mu_r (> 1). May be traced.
        external: the flux density of the outside sources, B_ext = mu0 H_ext (T): a
            uniform (3,) vector, or a function of points (P, 3) (m, body frame) returning
            (P, 3) (the sources lie outside the body).
        radius, height, dimension: the sizes (m), concrete numbers.
        level: the ladder level (1 .. len(LADDER) - 1): the answer extrapolates levels
            ``level - 1`` and ``level``. Measured (tests/fields/test_soft_accuracy.py):
            level 2 (432 + 768 panels on a sphere), error below 0.2 % on the sphere for
            mu_r 10..1000; cylinders of length/diameter 0.5..5 below the estimate.
        rtol: if given, the levels from 1 up until the estimate meets it (``level`` is
            then the last level tried).
        throw: with ``rtol``, raise when no level meets it; else return the finest answer
            with ``converged`` False.

    Returns:
        The :class:`SurfaceAnswer`.

    Raises:
        RuntimeError: ``rtol`` given, ``throw`` True and no level up to ``level`` meets it
            (the message names the best estimate).
    """
    if not 1 <= level < len(LADDER):
        raise ValueError(f"level must be 1 .. {len(LADDER) - 1}, got {level!r}")
    check_positive(**{"permeability - 1 (a soft body needs mu_r > 1)": jnp.asarray(permeability) - 1.0})
    scale, proportions, volume = _unit(shape, radius, height, dimension)
    coarse, _ = _mean(shape, scale, proportions, volume, permeability, external, LADDER[(1 if rtol else level) - 1])
    for at in range(1 if rtol else level, level + 1):
        fine, panels = _mean(shape, scale, proportions, volume, permeability, external, LADDER[at])
        ratio2 = (LADDER[at] / LADDER[at - 1]) ** 2
        answer = fine + (fine - coarse) / (ratio2 - 1.0)
        error = jnp.linalg.norm(answer - fine) / jnp.linalg.norm(answer)
        if rtol is not None and float(error) <= rtol:
            break
        coarse = fine
    converged = jnp.asarray(True) if rtol is None else error <= rtol
    if rtol is not None and throw and not bool(converged):
        raise RuntimeError(
            f"soft body (surface formulation): no level up to {level} meets rtol={rtol:g}; "
            f"the finest estimate is {float(error):.3g} (ask a higher level or a looser rtol)"
        )
    return SurfaceAnswer(magnetization=answer, error=error, level=at, panels=panels, converged=converged)


def demagnetizing_factor(
    shape: Literal["cuboid", "cylinder", "sphere"], *, permeability: float, axis: int = 2, **kwargs
) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """The magnetometric demagnetising factor N_m along ``axis`` (0, 1, 2) of a linear body of
    ``permeability`` (mu_r > 1), M_mean = chi H_0 / (1 + chi N_m) in a uniform field H_0 along
    that axis, and its estimated absolute error (dimensionless). ``kwargs``: the sizes and
    ``level`` / ``rtol`` / ``throw`` of :func:`mean_magnetization`."""
    chi = permeability - 1.0
    answer = mean_magnetization(shape, permeability=permeability, external=MU0 * np.eye(3)[axis], **kwargs)
    ratio = answer.magnetization[axis]  # M / H_0
    factor = 1.0 / ratio - 1.0 / chi
    return factor, answer.error / ratio
