"""The magnetic-suspension sensor (T. R. binti Sajat, "Basic study on tactile sensor by using
magnetic suspension", master's thesis, Wakayama University, 2008): a soft-magnetic pole in
a ball over a magnet plate.

A plastic ball of radius r_b carries a Ni-Fe rod (diameter d_p) along a diameter, from the
ball's bottom up for its length (``pole.length``, default the whole diameter 2 r_b); its
bottom sits ``gap`` above a permanent-magnet plate (a disc of radius R, thickness t,
remanence Br = mu0 Hc, top face at z = 0). Tilting the ball by theta about y moves
the rod's lower tip to c + r_b (sin theta, 0, -cos theta), c the ball's centre.

Reduced (magnetic-charge) model, the cheap fidelity level: the rod
is magnetised along its axis by the plate's field at its lower tip, mu0 M = B_axial /
N_d (a high-permeability rod with demagnetising factor N_d), which puts the magnetic
charges -/+ Q = mu0 M A_p (T m^2) on its lower / upper end. A charge Q at p adds
B = Q (r - p) / (4 pi |r - p|^3). The plate is taken as non-permeable (mu_r ~ 1 for a
sintered magnet), so there is no image charge; the rod's field on itself is left out.

A shear (tangential) force F_x at the ball tilts it by theta = F_x / k_spring, with
k_spring the published spring coefficient (N/rad; 12.57 uN at 10 deg). A GMR element
(sensitive along x) sits ``sensor_height`` above the plate at x = ``sensor_offset``.

Against the thesis (checked, no unit or factor error found: charges in T m^2, field of a
charge Q r / (4 pi r^3), force Q B / mu0, generalised force per ball radius in N/rad):
with the example's geometry the model gives a spring coefficient of 7.0e-3 N/rad against
the thesis's 7.2e-5 N/rad (12.57 uN at 10 deg, its first design), and a GMR (in-plane)
sensitivity of 4.5 mT/deg; the thesis's 0.3 mT/deg (magnet soleplate) is a different
quantity, the difference of two Hall sensors' B_z, which studies/magnetic_suspension.py
computes like for like. Both scale with the rod's induced magnetisation
(tip field / N_d), which is where the reduced model is weakest: N_d = 0.1 is a guess for
the rod's aspect ratio, the plate's field falls along the 4 mm rod while the model takes
it at the tip, and the thesis's FEM has a non-linear B-H curve (its Table 3.1 also lost
its units). Treat absolute forces of this level as upper bounds; use it for trends.

Method-of-moments level (``pole.fidelity = "moments"``): the
rod is a soft body of relative permeability mu_r (``pole.permeability``; linear, or
saturating at ``pole.saturation`` (T) by :mod:`magdesign.fields.soft`'s law) split
into cuboid cells (:mod:`magdesign.fields.soft`, ``pole.cells`` along its length), its
magnetisation solved self-consistently in the plate's field at every tilt, its own field
added at the sensors, and the forces taken as derivatives of the magnetic co-energy
W'(theta) with respect to the tilt and to a vertical shift (no demagnetising factor, no
charge model). The plate is still taken as non-permeable (mu_r = 1, as the thesis's FEM
sets it).

Outputs (:meth:`PoleScene.outputs`), at theta = 0:
    field_sensitivity   dB_a / dtheta at the GMR (T/rad), through the scene's chain with
                        its field effects (B_a along the chip's sensitive axis)
    spring_coefficient  the model's own restoring stiffness -dF_t / dtheta, F_t the
                        generalised force along theta of the plate's pull on the
                        rod (its charges; at the moments level dW'/dtheta), per ball
                        radius (N/rad); > 0 is restoring
    attraction          the plate's vertical pull on the rod (N, > 0 downwards)
and, where the scene lists the saturation effect, over the load sweep:
    saturation_ratio    the largest |reading| over its limit (-); above 1 the read-out clips
At the moments level the two tilt derivatives are five-point central differences of
exact values over TILT_DIFFERENCE_STEP (their error O(step^4), below 1e-6 relative, far
below the cells' discretisation error), and the attraction is -dW'/dz.
"""

from typing import ClassVar

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float

from magdesign.fields import cylinder, soft
from magdesign.scene.core import STATIC_WITHOUT, AbstractScene, chain
from magdesign.scene.effects import AbstractEffect
from magdesign.scene.magnet_scene import SpinValveReadout
from magdesign.scene.pose import SoftPart, rotation, soft_parts_field, soft_parts_frames
from magdesign.units import MU0

# The magnetic-suspension pole's moments level: the tilt step (rad) of its five-point central differences (the
# spring coefficient and the field sensitivity at theta = 0). Truncation ~ step^4 times a
# fifth / sixth tilt derivative: the GMR's field, 0.58 mm from the rod's tip, varies
# fastest; at 0.02 rad its sensitivity is 1.7e-4 off, at 0.005 rad below 1e-6 (against
# 0.0025 rad); rounding ~1e-15 / step^2 ~ 4e-11 for the spring coefficient.
TILT_DIFFERENCE_STEP = 0.005
# The five tilts (rad) of those central differences and their weights for the first and
# the second derivative: f' = TILT_FIRST_DIFFERENCE . f(TILT_DIFFERENCE_ANGLES), alike f''.
TILT_DIFFERENCE_ANGLES = tuple(TILT_DIFFERENCE_STEP * k for k in (-2.0, -1.0, 0.0, 1.0, 2.0))
TILT_FIRST_DIFFERENCE = tuple(w / (12.0 * TILT_DIFFERENCE_STEP) for w in (1.0, -8.0, 0.0, 8.0, -1.0))
TILT_SECOND_DIFFERENCE = tuple(w / (12.0 * TILT_DIFFERENCE_STEP**2) for w in (-1.0, 16.0, -30.0, 16.0, -1.0))


def _charge_field(points, position, charge):
    r = points - position
    return charge * r / (4.0 * jnp.pi * jnp.sum(r * r, axis=-1, keepdims=True) ** 1.5)


class PoleScene(AbstractScene):
    """The magnetic-suspension sensor (see the module docstring); SI throughout.

    ``fidelity`` (static) is "reduced" (charges, ``demagnetizing_factor``) or "moments"
    (the rod a soft body of ``permeability``, ``rod_cells`` = its grid (n_x, n_y, n_z),
    ``saturation`` its J_s (T) or None: linear).
    """

    plate_radius: Float[Array, ""]
    plate_thickness: Float[Array, ""]
    remanence: Float[Array, ""]
    gap: Float[Array, ""]
    ball_radius: Float[Array, ""]
    pole_diameter: Float[Array, ""]
    pole_length: Float[Array, ""]
    demagnetizing_factor: Float[Array, ""] | None
    permeability: Float[Array, ""] | None
    spring: Float[Array, ""]
    sensor_offset: Float[Array, ""]
    sensor_height: Float[Array, ""]
    transducer: SpinValveReadout
    effects: tuple[AbstractEffect, ...]
    fidelity: str = eqx.field(static=True, default="reduced")
    rod_cells: tuple[int, int, int] | None = eqx.field(static=True, default=None)
    saturation: Float[Array, ""] | None = None

    SOURCE_KEY = "magnet.remanence"
    reading_labels = ("V",)
    reading_unit = "V"
    OUTPUT_UNITS: ClassVar[dict[str, str]] = {
        "field_sensitivity": "T/rad",
        "spring_coefficient": "N/rad",
        "attraction": "N",
    }

    @property
    def output_units(self):
        return {**self.OUTPUT_UNITS, **({} if self.chip_range() is None else {"saturation_ratio": "1"})}

    @property
    def parameter_paths(self):
        return {
            "magnet.radius": lambda s: s.plate_radius,
            "magnet.height": lambda s: s.plate_thickness,
            "magnet.remanence": lambda s: s.remanence,
            "geometry.gap": lambda s: s.gap,
            "pole.ball_radius": lambda s: s.ball_radius,
            "pole.diameter": lambda s: s.pole_diameter,
            "pole.length": lambda s: s.pole_length,
            **(
                {"pole.demagnetizing_factor": lambda s: s.demagnetizing_factor}
                if self.fidelity == "reduced"
                else {"pole.permeability": lambda s: s.permeability}
            ),
            **({"pole.saturation": lambda s: s.saturation} if self.saturation is not None else {}),
            "mechanics.spring": lambda s: s.spring,
            "sensor.offset": lambda s: s.sensor_offset,
            "sensor.height": lambda s: s.sensor_height,
        }

    @property
    def centre(self):
        return jnp.array([0.0, 0.0, 1.0]) * (self.gap + self.ball_radius)

    def tip(self, theta):
        """The rod's lower tip (3,) (m) at tilt ``theta`` (rad)."""
        return self.centre + self.ball_radius * jnp.stack([jnp.sin(theta), 0.0 * theta, -jnp.cos(theta)])

    def tilt(self, displacement):
        """The tilt (rad) that moves the rod's lower tip by ``displacement`` (3,) (m)."""
        tip = self.tip(0.0) + displacement - self.centre
        return jnp.arctan2(tip[0], -tip[2])

    @property
    def rod(self):
        """The rod as a :class:`~magdesign.fields.soft.SoftBody` (moments level), in its
        own frame: centre at the origin, axis along z."""
        return self._rod_part(0.0, jnp.zeros(3)).body

    def _rod_part(self, theta, shift):
        """The rod at tilt ``theta`` (rad), moved by ``shift`` (3,) (m), as a scene's soft
        part: turned about y by theta, its axis (-sin theta, 0, cos theta) from the tip."""
        if self.fidelity != "moments":
            raise ValueError("the rod is a soft body at the moments level only (pole.fidelity = 'moments')")
        angles = jnp.stack([0.0 * theta, theta, 0.0 * theta])
        centre = self.tip(theta) + shift + 0.5 * self.pole_length * rotation(angles)[2]
        return SoftPart(
            size=(self.pole_diameter, self.pole_length),
            permeability=self.permeability,
            centre=tuple(centre),
            angles=angles,
            shape="cylinder",
            grid=self.rod_cells,
            saturation=self.saturation,
        )

    def _rod_pose(self, theta, shift):
        """The rod's centre (3,) (m) and turn (3, 3) (v_scene = turn v_body) at tilt
        ``theta`` (rad), moved by ``shift`` (3,) (m)."""
        part = self._rod_part(theta, shift)
        return jnp.stack(part.centre), rotation(part.angles).T

    def _rod_external(self, theta, shift):
        """The plate's field at the rod's cells in the rod's frame (N, 3) (T)."""
        return soft_parts_frames((self._rod_part(theta, shift),), jnp.zeros(3), self.plate_field)[3][0]

    def coenergy(self, theta, shift=None):
        """The rod's magnetic co-energy W' (J) in the plate's field at tilt ``theta`` (rad),
        moved by ``shift`` (3,) (m) (moments level)."""
        shift = jnp.zeros(3) if shift is None else shift
        return soft.coenergy(self.rod, self._rod_external(theta, shift))

    def plate_field(self, points):
        centre = jnp.array([0.0, 0.0, -0.5]) * self.plate_thickness
        return cylinder(
            points - centre, radius=self.plate_radius, height=self.plate_thickness, polarization=self.remanence
        )

    def charges(self, displacement):
        """Positions (2, 3) (m) and charges (2,) (T m^2) of the rod's lower and upper ends."""
        tip = self.tip(0.0) + displacement
        return self._rod(tip, self.plate_field(tip))

    def _rod(self, tip, tip_field):
        """The rod's charges given its lower tip (3,) (m) and the plate's field there (T):
        the rod runs from the tip towards the ball's centre for ``pole_length``."""
        axis = (self.centre - tip) / self.ball_radius
        top = tip + self.pole_length * axis
        area = jnp.pi * self.pole_diameter**2 / 4
        charge = area * jnp.dot(tip_field, axis) / self.demagnetizing_factor
        return jnp.stack([tip, top]), jnp.stack([-charge, charge])

    def sensor_poses(self):
        position = jnp.stack([self.sensor_offset, 0.0 * self.sensor_offset, self.sensor_height])
        return position[None, :], jnp.eye(3)[None]

    def displacement(self, loads):
        theta = loads.shear[:, 0] / self.spring
        return jax.vmap(self.tip)(theta) - self.tip(0.0), jnp.ones(theta.shape, bool)

    def source_field(self, points, displacement):
        if self.fidelity == "moments":
            rod = self._rod_part(self.tilt(displacement), jnp.zeros(3))
            return self.plate_field(points) + soft_parts_field((rod,), points, jnp.zeros(3), self.plate_field)
        # one plate-field evaluation for the points and the rod's tip (one compiled kernel)
        tip = self.tip(0.0) + displacement
        flat = points.reshape(-1, 3)
        both = self.plate_field(jnp.concatenate([flat, tip[None]]))
        positions, charges = self._rod(tip, both[-1])
        field = both[:-1].reshape(points.shape)
        for position, charge in zip(positions, charges):
            field = field + _charge_field(points, position, charge)
        return field

    def transduce(self, field):
        return self.transducer(field)[..., None]

    def tangential_force(self, theta):
        """The plate's pull on the rod's charges at tilt ``theta`` (rad) as a generalised
        force along theta, per ball radius (N): sum F_i . dp_i/dtheta / r_b (the torque
        about the ball's centre over r_b); at the moments level dW'/dtheta / r_b. Negative
        for theta > 0 where it restores."""
        if self.fidelity == "moments":
            return jax.grad(self.coenergy)(theta) / self.ball_radius

        def ends(angle):
            return self.charges(self.tip(angle) - self.tip(0.0))[0]

        positions, velocities = jax.jvp(ends, (theta,), (jnp.ones_like(theta),))
        charges = self.charges(self.tip(theta) - self.tip(0.0))[1]
        forces = charges[:, None] * self.plate_field(positions) / MU0
        return jnp.sum(forces * velocities) / self.ball_radius

    def outputs(self, result):
        def field_a(theta):
            displacement = (self.tip(theta) - self.tip(0.0))[None]
            return chain(self, displacement, without=STATIC_WITHOUT).chip_field[0, 0, 0]

        if self.fidelity == "moments":
            # Five-point central differences over the tilt of exact values (the co-energy
            # and the field): the exact second derivative of the plate's cylinder kernel
            # costs ~95 s to compile; these need its values only. Truncation O(step^4).
            angles = jnp.array(TILT_DIFFERENCE_ANGLES)
            energy, field = jax.vmap(self.coenergy)(angles), jax.vmap(field_a)(angles)
            first, second = jnp.array(TILT_FIRST_DIFFERENCE), jnp.array(TILT_SECOND_DIFFERENCE)
            return {
                "field_sensitivity": first @ field,
                "spring_coefficient": -(second @ energy) / self.ball_radius,
                "attraction": self.attraction(),
                **self._range_outputs(result),
            }
        return {
            "field_sensitivity": jax.grad(field_a)(0.0),
            "spring_coefficient": -jax.grad(self.tangential_force)(0.0),
            "attraction": self.attraction(),
            **self._range_outputs(result),
        }

    def _range_outputs(self, result):
        """{"saturation_ratio": the largest |reading| over the sweep / the saturation
        effect's limit} where the scene lists the effect (the GMR's read-out range), else {}."""
        judged = self.chip_range()
        return {} if judged is None else {"saturation_ratio": judged.ratio(self.transduce(result.chip_field))}

    def attraction(self):
        """The plate's vertical pull on the rod at rest (N, > 0 downwards)."""
        if self.fidelity == "moments":
            return jax.grad(lambda dz: self.coenergy(0.0, jnp.array([0.0, 0.0, -1.0]) * dz))(0.0)
        positions, charges = self.charges(jnp.zeros(3))
        return -jnp.sum(charges * self.plate_field(positions)[:, 2]) / MU0
