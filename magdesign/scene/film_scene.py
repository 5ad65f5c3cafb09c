"""The film-Hall sensor (Yan et al., Sci. Robot. 2021): a sinusoidally magnetised film on an elastomer layer over Hall taxels.

Scene frame: z points up, from the taxels towards the film. The film (period T,
thickness d, polarization amplitude J0; :mod:`magdesign.fields.film`) lies on an
elastomer layer of thickness h: its bottom face at z = h, its pattern
J = J0 (-sin kx, 0, -cos kx) in this frame (the film frame's depth axis points down),
strong side down. The taxels sit on the layer's bottom face (z = 0) on a square grid
centred on the origin. Below an infinite film the field in this frame is

    B = J0 (1 - e^{-kd}) e^{-k (h - z)} (sin kx, 0, -cos kx)

a valid field here (div B = curl B = 0, tested), so effects given in the scene frame
(a background field) add to it with their true relative sign. ``periods = N`` makes
the film a strip N periods wide (exact field, :func:`magdesign.fields.film`), centred
over the grid; None is the infinite film.

A load moves the whole film: normal force Fz by -Fz / k_n along z (towards the
taxels), shear (Fx, Fy) by F / k_s, with the layer stiffness k_n, k_s of
:func:`magdesign.mechanics.layer_stiffness` for the contact area S. The film is
uniform along y, so only the x shear changes the field.

Outputs (:meth:`FilmScene.outputs`), at the central taxel (the middle of the grid; one
of the middle four of an even grid), through the scene's chain with its field effects
(see docs/outputs.md):
    field_fraction      |B| at the taxel at rest (zero load) over |B| of the film alone (with
                        its source effects) at its face (-); e^{-k h} for the infinite film
    normal_sensitivity  d|B| / dFz there at rest (T/N); k |B| / k_n for the infinite film
    shear_phase_max     k times the largest |u_x| of the sweep (rad)
    normal_compliance   1 / k_n (m/N);  shear_compliance  1 / k_s (m/N)
    saturation_ratio    the largest |reading| over every taxel, axis and load point over the
                        chips' range (the saturation effect's limit, else the preset's full
                        scale) (-); above 1 the chips clip
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from magdesign.fields import film
from magdesign.scene.core import STATIC_WITHOUT, AbstractScene, apply_source_effects, chain
from magdesign.scene.effects import AbstractEffect, judged_saturation
from magdesign.scene.loads import Loads
from magdesign.scene.mechanics import Layer
from magdesign.scene.pose import grid_positions
from magdesign.transducers import Hall3D


class FilmScene(AbstractScene):
    """The film-Hall sensor (see the module docstring); all lengths (m), J0 (T), area (m^2).

    ``periods`` (static): None for an infinite film, N for a strip N periods wide.
    """

    period: Float[Array, ""]
    film_thickness: Float[Array, ""]
    magnetization: Float[Array, ""]
    layer: Layer
    pitch: Float[Array, ""]
    hall: Hall3D
    effects: tuple[AbstractEffect, ...]
    grid: tuple[int, int] = eqx.field(static=True)
    periods: int | None = eqx.field(static=True, default=None)

    SOURCE_KEY: ClassVar = "magnet.magnetization"
    reading_labels: ClassVar = ("Bx", "By", "Bz")
    reading_unit: ClassVar = "T"
    OUTPUT_UNITS: ClassVar[dict[str, str]] = {
        "field_fraction": "1",
        "normal_sensitivity": "T/N",
        "shear_phase_max": "rad",
        "normal_compliance": "m/N",
        "shear_compliance": "m/N",
    }

    @property
    def output_units(self):
        return {**self.OUTPUT_UNITS, "saturation_ratio": "1"}

    def chip_range(self):
        """The listed saturation effect, else the Hall chips' own range (the preset's full
        scale per axis)."""
        return judged_saturation(self.effects, self.hall.full_scale)

    @property
    def parameter_paths(self):
        paths = {
            "magnet.period": lambda s: s.period,
            "magnet.thickness": lambda s: s.film_thickness,
            "magnet.magnetization": lambda s: s.magnetization,
            "sensor.pitch": lambda s: s.pitch,
        }
        for name, get in self.layer.parameter_paths.items():
            paths[name] = lambda s, get=get: get(s.layer)
        return paths

    def sensor_poses(self):
        positions = grid_positions(self.grid, self.pitch)
        return positions, jnp.broadcast_to(jnp.eye(3), (positions.shape[0], 3, 3))

    def displacement(self, loads):
        return self.layer.displacement(loads)

    def source_field(self, points, displacement):
        # film frame: x from the film's centre, z the depth below its bottom face (down)
        depth = self.layer.thickness + displacement[2] - points[..., 2]
        bx, b_depth = film(
            points[..., 0] - displacement[0],
            depth,
            period=self.period,
            thickness=self.film_thickness,
            polarization=self.magnetization,
            periods=self.periods,
        )
        # back to the scene frame: its z axis is the film frame's depth axis reversed
        return jnp.stack([bx, jnp.zeros_like(bx), -b_depth], axis=-1)

    def transduce(self, field):
        return field

    def outputs(self, result):
        k = 2.0 * jnp.pi / self.period
        stiffness = self.layer.stiffness
        rows, cols = self.grid
        centre = (rows // 2) * cols + cols // 2

        def magnitude(force):
            """|B| (T) at the central taxel under a static normal ``force`` (N)."""
            displacement = self.displacement(Loads(force[None]))[0]
            return jnp.linalg.norm(chain(self, displacement, without=STATIC_WITHOUT).field[0, centre])

        at_taxel, slope = jax.jvp(magnitude, (jnp.zeros(()),), (jnp.ones(()),))
        film = apply_source_effects(self, self.effects)  # a drifted film is weaker at its face too
        at_face = jnp.linalg.norm(film.source_field(jnp.array([0.0, 0.0, 1.0]) * self.layer.thickness, jnp.zeros(3)))
        return {
            "field_fraction": at_taxel / at_face,
            "normal_sensitivity": slope,
            "shear_phase_max": k * jnp.max(jnp.abs(result.displacement[:, 0])),
            "normal_compliance": 1.0 / stiffness.normal,
            "shear_compliance": 1.0 / stiffness.shear,
            "saturation_ratio": self.chip_range().ratio(self.transduce(result.chip_field)),
        }
