"""A picture of a sensor: its axial plane (y = 0) with the magnet, the dome or layer (or a
skin and its indenter), the chips, the field magnitude and the field lines, at rest and at
the largest load.

    magdesign show SPEC --plot FILE
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure
from matplotlib.patches import Arc, Circle, Polygon, Rectangle

from magdesign._files import replaced
from magdesign.scene.film_scene import FilmScene
from magdesign.scene.magnet_scene import MagnetScene
from magdesign.scene.mechanics import Dome
from magdesign.scene.pole_scene import PoleScene
from magdesign.scene.pose import rotation
from magdesign.scene.skin_scene import SkinScene

GRID_POINTS = 181
# A soft body's field costs one exact cuboid kernel per cell at every grid point (the
# magnetic-suspension rod: 336 cells, ~2.5 ms per point): its pictures use a coarser grid.
SOFT_GRID_POINTS = 61
MM = 1e3  # the picture is drawn in millimetres

OUTLINE = dict(fill=False, edgecolor="k", linewidth=1.2)


# One jitted function for every panel: a lambda made per call would be a new function to
# jit, and the scene's field (for a soft body its solve) compiled again for each panel.
_source_field = eqx.filter_jit(lambda scene, points, u: scene.source_field(points, u))


def _largest_load(loads):
    """Index of the load point with the largest force."""
    magnitude = np.abs(np.asarray(loads.normal)) + np.linalg.norm(np.asarray(loads.shear), axis=-1)
    return int(np.argmax(magnitude))


def _cylinder_corners(centre, angles, radius, height):
    """Corners (4, 2) (x, z) of a cylinder's section by its own y = 0 plane, in the scene."""
    local = np.array(
        [[-radius, 0, -height / 2], [radius, 0, -height / 2], [radius, 0, height / 2], [-radius, 0, height / 2]]
    )
    matrix = np.eye(3) if angles is None else np.asarray(rotation(angles))
    points = local @ matrix + np.asarray(centre)  # M^T p for each row
    return points[:, [0, 2]]


def _extent(scene):
    """(x_min, x_max, z_min, z_max) (m) of the picture."""
    if isinstance(scene, MagnetScene):
        positions = np.asarray(scene.sensor_positions)
        top = float(scene.gap + scene.height)
        half = max(4.0 * float(scene.radius), np.max(np.abs(positions[:, 0])) + 2.0 * float(scene.radius))
        if isinstance(scene.mechanics, Dome):
            half = max(half, 1.15 * float(scene.mechanics.outer_radius))
            top = max(top, float(scene.mechanics.outer_radius))
        low = min(0.0, float(np.min(positions[:, 2])))
        for extra in scene.extra:  # further magnets: their enclosing spheres in the picture
            size = float(np.hypot(extra.radius, extra.height / 2))
            centre = np.asarray(extra.centre)
            half = max(half, abs(float(centre[0])) + 1.5 * size)
            top, low = max(top, float(centre[2]) + size), min(low, float(centre[2]) - size)
        margin = 0.25 * (top - low)
        return -half, half, low - margin, top + margin
    if isinstance(scene, FilmScene):
        period = float(scene.period)
        half = max(1.5 * period, (scene.grid[1] / 2 + 0.5) * float(scene.pitch))
        if scene.periods is not None:
            half = max(half, 0.6 * scene.periods * period)
        top = float(scene.layer.thickness + scene.film_thickness)
        return -half, half, -0.3 * top, 1.3 * top
    if isinstance(scene, SkinScene):
        half, top = 0.6 * float(scene.size[0]), float(scene.thickness + 2 * scene.sphere_radius)
        return -half, half, -2.0 * float(scene.depth), 1.2 * top
    half = 2.2 * float(scene.ball_radius)
    top = float(scene.gap + 2 * scene.ball_radius)
    return -half, half, -1.5 * float(scene.plate_thickness), 1.1 * top


def _draw_bodies(axis, scene, displacement):
    """Outlines of the magnet(s), mechanics and chips (mm)."""
    u = np.asarray(displacement)
    if isinstance(scene, MagnetScene):
        corners = _cylinder_corners(
            np.asarray(scene.magnet_centre()) + u, scene.angles, float(scene.radius), float(scene.height)
        )
        axis.add_patch(Polygon(corners * MM, closed=True, facecolor="0.85", edgecolor="k", label="magnet"))
        for extra in scene.extra:
            centre = np.asarray(extra.centre) + (u if extra.moves else 0.0)
            corners = _cylinder_corners(centre, extra.angles, float(extra.radius), float(extra.height))
            axis.add_patch(Polygon(corners * MM, closed=True, facecolor="0.85", edgecolor="k"))
        mechanics = scene.mechanics
        if isinstance(mechanics, Dome):
            for radius in (float(mechanics.outer_radius), float(mechanics.outer_radius - mechanics.thickness)):
                axis.add_patch(
                    Arc((0.0, 0.0), 2 * radius * MM, 2 * radius * MM, theta1=0, theta2=180, linestyle="--", color="k")
                )
            axis.plot([], [], "k--", label="dome (undeformed)")
        else:
            # the layer's top face moves with the magnet it carries (pressed by -uz)
            thickness = float(mechanics.thickness + u[2])
            axis.add_patch(
                Rectangle(
                    (-1e3, 0.0), 2e3, thickness * MM, facecolor="none", edgecolor="k", linestyle="--", label="layer"
                )
            )
        chips = np.asarray(scene.sensor_positions)
    elif isinstance(scene, FilmScene):
        h, d = float(scene.layer.thickness + u[2]), float(scene.film_thickness)
        half = 1e3 if scene.periods is None else scene.periods * float(scene.period) / 2
        axis.add_patch(
            Rectangle(((u[0] - half) * MM, h * MM), 2 * half * MM, d * MM, facecolor="0.7", edgecolor="k", label="film")
        )
        axis.add_patch(
            Rectangle((-1e3, 0.0), 2e3, h * MM, facecolor="none", edgecolor="k", linestyle="--", label="layer")
        )
        chips = np.asarray(scene.sensor_poses()[0])
    elif isinstance(scene, SkinScene):
        # the skin undeformed (its displacements are small against h), the sphere at the contact
        side, h = float(scene.size[0]), float(scene.thickness)
        axis.add_patch(
            Rectangle((-side / 2 * MM, 0.0), side * MM, h * MM, facecolor="none", edgecolor="k", label="skin")
        )
        if scene.magnets is not None:
            # the discrete magnets at rest, projected on y = 0: filled where the plane cuts them
            centres, sizes = np.asarray(scene.magnets.centres), np.asarray(scene.magnets.sizes)
            for index, (centre, size) in enumerate(zip(centres, sizes)):
                cut = abs(centre[1]) <= size[1] / 2
                axis.add_patch(
                    Rectangle(
                        ((centre[0] - size[0] / 2) * MM, (centre[2] - size[2] / 2) * MM),
                        size[0] * MM,
                        size[2] * MM,
                        facecolor="0.85" if cut else "none",
                        edgecolor="k",
                        linestyle="-" if cut else ":",
                        label="magnets (dotted: off the plane)" if index == 0 else None,
                    )
                )
        if u[2] > 0.0:  # the indenter at the contact's x (its y projected on y = 0)
            radius = float(scene.sphere_radius)
            if scene.indenter == "flat":
                punch = Rectangle(
                    ((u[0] - radius) * MM, h * MM), 2 * radius * MM, radius * MM, **OUTLINE, label="punch"
                )
                axis.add_patch(punch)
            else:
                axis.add_patch(Circle((u[0] * MM, (h + radius) * MM), radius * MM, **OUTLINE, label="indenter"))
        chips = np.asarray(scene.sensor_poses()[0])
    else:
        radius, thickness = float(scene.plate_radius), float(scene.plate_thickness)
        axis.add_patch(
            Rectangle(
                (-radius * MM, -thickness * MM),
                2 * radius * MM,
                thickness * MM,
                facecolor="0.85",
                edgecolor="k",
                label="magnet plate",
            )
        )
        centre = np.asarray(scene.centre)
        axis.add_patch(Circle((centre[0] * MM, centre[2] * MM), float(scene.ball_radius) * MM, **OUTLINE))
        tip = np.asarray(scene.tip(0.0)) + u
        top = 2 * centre - tip
        axis.plot([tip[0] * MM, top[0] * MM], [tip[2] * MM, top[2] * MM], color="k", linewidth=3, label="pole")
        chips = np.asarray(scene.sensor_poses()[0])
    projected = " (projected on y = 0)" if np.any(chips[:, 1] != 0.0) else ""
    axis.plot(chips[:, 0] * MM, chips[:, 2] * MM, "s", color="C3", markersize=5, label=f"chips{projected}")


def _plane_field(scene, displacement, x, z):
    """|B| and (Bx, Bz) (T) on the (x, z) grid in y = 0; NaN above a film and inside a
    magnetised skin (no field model there)."""
    xx, zz = np.meshgrid(x, z)
    points = jnp.asarray(np.stack([xx, 0 * xx, zz], axis=-1))
    field = np.asarray(_source_field(scene, points, jnp.asarray(displacement)))
    if isinstance(scene, FilmScene):
        below = zz < float(scene.layer.thickness + displacement[2])
        field = np.where(below[..., None], field, np.nan)
    if isinstance(scene, SkinScene) and scene.magnets is None:
        # inside a magnetised skin the moved rigid cells leave gaps and overlaps (a cell face
        # lies in y = 0): their field there is not the continuum's, and is left out; an
        # unmagnetised layer's discrete magnets have their exact field everywhere
        inside = (zz >= 0.0) & (zz <= float(scene.thickness)) & (np.abs(xx) <= float(scene.size[0]) / 2)
        field = np.where(inside[..., None], np.nan, field)
    return np.linalg.norm(field, axis=-1), field[..., 0], field[..., 2]


def plot_scene(scene, loads, path, *, title=""):
    """Write a PNG of the scene's axial plane at rest and at the largest load of ``loads``
    to ``path``, and return its matplotlib Figure: two panels (x, z in mm) of |B| (T, log
    colour scale, computed on a GRID_POINTS x GRID_POINTS grid over the axes' limits,
    SOFT_GRID_POINTS for a scene with soft-magnetic bodies) with
    the field lines of (Bx, Bz), and the outlines of the bodies and the chips.

    The field drawn is the exact one: a scene whose magnet uses the on-axis fidelity
    ("axis", exact on the axis only) is drawn with fidelity "exact".
    """
    if isinstance(scene, MagnetScene) and scene.fidelity == "axis":
        scene = dataclasses.replace(scene, fidelity="exact")
    displacements, converged = (np.asarray(a) for a in scene.displacement(loads))
    index = _largest_load(loads)
    x_min, x_max, z_min, z_max = _extent(scene)
    soft = (isinstance(scene, PoleScene) and scene.fidelity == "moments") or bool(getattr(scene, "soft", ()))
    grid = SOFT_GRID_POINTS if soft else GRID_POINTS
    x, z = np.linspace(x_min, x_max, grid), np.linspace(z_min, z_max, grid)
    panels = [("at rest", np.zeros_like(displacements[index]))]  # a skin's: no force
    force = f"Fz {float(loads.normal[index]):.3g} N, Fx {float(loads.shear[index, 0]):.3g} N"
    warning = "" if converged[index] else ", mechanics did not converge"
    panels.append((f"at the largest load ({force}{warning})", displacements[index]))
    fields = [_plane_field(scene, u, x, z) for _, u in panels]
    magnitudes = np.concatenate([m[np.isfinite(m)] for m, _, _ in fields])
    norm = LogNorm(vmin=max(np.percentile(magnitudes, 1), 1e-9), vmax=np.percentile(magnitudes, 99.5))
    # two panels side by side at equal scale, plus room for titles and the colour bar
    height = 12.0 * (z_max - z_min) / (2.0 * (x_max - x_min)) + 1.4
    figure = Figure(figsize=(12, min(max(height, 3.0), 7.0)), layout="constrained")
    axes = figure.subplots(1, 2, sharey=True)
    for axis, (label, u), (magnitude, bx, bz) in zip(axes, panels, fields):
        mesh = axis.pcolormesh(x * MM, z * MM, magnitude, norm=norm, cmap="viridis", shading="auto")
        axis.streamplot(
            x * MM, z * MM, np.nan_to_num(bx), np.nan_to_num(bz), color="w", linewidth=0.6, density=1.3, arrowsize=0.6
        )
        _draw_bodies(axis, scene, u)
        axis.set_xlim(x_min * MM, x_max * MM)
        axis.set_ylim(z_min * MM, z_max * MM)
        axis.set_aspect("equal")
        axis.set_xlabel("x (mm)")
        axis.set_title(label, fontsize=10)
    axes[0].set_ylabel("z (mm)")
    axes[0].legend(loc="upper left", fontsize=7, framealpha=0.8)
    figure.colorbar(mesh, ax=list(axes), label="|B| (T)", shrink=0.9)
    figure.suptitle(title or f"{type(scene).__name__}: field magnitude and field lines in the plane y = 0")
    with replaced(path) as temporary:
        figure.savefig(temporary, dpi=110)
    return figure
