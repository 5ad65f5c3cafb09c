"""Poses: magnets and soft parts placed and turned in the scene, and the sensor grid.

Orientations are three angles (alpha, beta, gamma) (rad), v_body = Rx(alpha) Ry(beta)
Rz(gamma) v: :mod:`magdesign.frames` holds the rotation (:func:`rotation`, re-exported
here for the scene's modules) and the maps into and out of a body's frame.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from magdesign.fields import cylinder, soft
from magdesign.frames import from_body, rotation, to_body


def posed_cylinder(
    points: Float[ArrayLike, "... 3"],
    *,
    centre: Float[ArrayLike, "3"],
    angles: Float[ArrayLike, "3"] | None,
    radius,
    height,
    polarization,
    fidelity: str = "exact",
) -> Float[Array, "... 3"]:
    """Flux density (T, scene frame) at ``points`` (m, scene frame) of a cylinder whose
    centre is at ``centre`` (m) and whose orientation is ``angles`` (rad, None: its axis
    along the scene's z); ``polarization`` (T) a scalar along its axis or a vector in its
    own frame (:func:`magdesign.fields.cylinder`)."""
    local = jnp.asarray(points) - centre
    if angles is None:
        return cylinder(local, radius=radius, height=height, polarization=polarization, fidelity=fidelity)
    matrix = rotation(angles)
    field = cylinder(to_body(matrix, local), radius=radius, height=height, polarization=polarization, fidelity=fidelity)
    return from_body(matrix, field)


class Magnet(eqx.Module):
    """A further cylinder magnet of a scene: radius, height (m), polarization (3,) (T, in
    its own frame), centre (3,) (m, scene frame, at rest), angles (3,) (rad; its
    orientation, as a chip's); ``moves`` (static): carried with the main magnet by the
    load, or fixed in the scene."""

    radius: Float[Array, ""]
    height: Float[Array, ""]
    polarization: Float[Array, "3"]
    centre: Float[Array, "3"]
    angles: Float[Array, "3"]
    moves: bool = eqx.field(static=True, default=True)

    def field(self, points, displacement, fidelity="exact"):
        """Flux density (T, scene frame) at ``points`` with the load's ``displacement`` (m)."""
        centre = self.centre + displacement if self.moves else self.centre
        return posed_cylinder(
            points,
            centre=centre,
            angles=self.angles,
            radius=self.radius,
            height=self.height,
            polarization=self.polarization,
            fidelity=fidelity,
        )


class SoftPart(eqx.Module):
    """A soft-magnetic part of a scene (``[[soft]]``; :mod:`magdesign.fields.soft`): its
    ``shape`` (static) and ``size`` (lengths, m, as :func:`~magdesign.fields.soft.soft_body`),
    relative ``permeability``, ``centre`` (x, y, z) (m, scene frame, at rest), ``angles`` (3,)
    (rad, as a magnet's), ``grid`` (static) its cells along x, y, z; ``moves`` (static):
    carried by the load with the magnet, or fixed in the scene; ``saturation`` (T, J_s) or
    None for a linear part. Sizes and centre are scalars each, so a design can set one free
    (the grid stays: a design that grows a part stretches its cells)."""

    size: tuple[Float[Array, ""], ...]
    permeability: Float[Array, ""]
    centre: tuple[Float[Array, ""], Float[Array, ""], Float[Array, ""]]
    angles: Float[Array, "3"]
    shape: str = eqx.field(static=True)
    grid: tuple[int, int, int] = eqx.field(static=True)
    moves: bool = eqx.field(static=True, default=False)
    saturation: Float[Array, ""] | None = None

    @property
    def body(self) -> soft.SoftBody:
        return soft.soft_body(
            self.shape,
            **soft.size_keywords(self.shape, jnp.stack(self.size)),
            cells=self.grid,
            permeability=self.permeability,
            saturation=self.saturation,
        )

    def position(self, displacement):
        """The part's centre (3,) (m, scene frame) with the load's ``displacement`` (m)."""
        centre = jnp.stack(self.centre)
        return centre + displacement if self.moves else centre


def soft_parameter_paths(parts, get_parts) -> dict:
    """The design parameters of the soft ``parts`` by spec key (``soft[i].permeability``,
    ``.saturation`` where given, ``.position[k]``, ``.size[k]``), each a getter of the scene;
    ``get_parts`` gets the parts from the scene."""
    paths = {}
    for i, part in enumerate(parts):
        paths[f"soft[{i}].permeability"] = lambda s, i=i: get_parts(s)[i].permeability
        if part.saturation is not None:
            paths[f"soft[{i}].saturation"] = lambda s, i=i: get_parts(s)[i].saturation
        for k in range(3):
            paths[f"soft[{i}].position[{k}]"] = lambda s, i=i, k=k: get_parts(s)[i].centre[k]
        for k in range(len(part.size)):
            paths[f"soft[{i}].size[{k}]"] = lambda s, i=i, k=k: get_parts(s)[i].size[k]
    return paths


def soft_parts_frames(parts, displacement, magnets):
    """Each part's body, centre (3,) (m, scene frame), rotation (3, 3) (v_body = matrix
    v_scene) and the permanent magnets' B (T) at its cells in its own frame, (N_b, 3);
    ``displacement`` (m) the load's, ``magnets`` as in :func:`soft_parts_field` (called
    once, on every part's cells)."""
    bodies = [part.body for part in parts]
    centres = [part.position(displacement) for part in parts]
    matrices = [rotation(part.angles) for part in parts]
    cells = [centre + body.centres @ matrix for body, centre, matrix in zip(bodies, centres, matrices)]
    at_cells = jnp.split(magnets(jnp.concatenate(cells)), np.cumsum([len(c) for c in cells])[:-1])
    return bodies, centres, matrices, [to_body(matrix, field) for matrix, field in zip(matrices, at_cells)]


def soft_parts_field(parts, points, displacement, magnets):
    """The soft ``parts``' own flux density (T, scene frame) at ``points`` (m, scene frame),
    with the load's ``displacement`` (m), magnetised by ``magnets`` (a function from points
    (..., 3) (m, scene frame) to the permanent magnets' B (T) there) and by one another."""
    bodies, centres, matrices, externals = soft_parts_frames(parts, displacement, magnets)
    magnetizations = soft.coupled_magnetization(bodies, centres, matrices, externals)
    points = jnp.asarray(points)
    return sum(
        from_body(matrix, soft.field(body, magnetization, to_body(matrix, points - centre)))
        for body, magnetization, centre, matrix in zip(bodies, magnetizations, centres, matrices)
    )


def grid_positions(shape: tuple[int, int], pitch) -> Float[Array, "s 3"]:
    """Centres (S, 3) (m) of a rows x cols grid at ``pitch`` (m) in z = 0, centred on the origin."""
    rows, cols = shape
    x = (jnp.arange(cols) - (cols - 1) / 2) * pitch
    y = (jnp.arange(rows) - (rows - 1) / 2) * pitch
    xx, yy = jnp.meshgrid(x, y)
    return jnp.stack([xx.ravel(), yy.ravel(), jnp.zeros(xx.size)], axis=-1)
