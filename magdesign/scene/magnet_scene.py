"""The dome-Hall, spin-valve matrix and GMR-inductor sensors: an axially magnetised cylinder
moved by a dome or a layer.

Scene frame: the reference sensor plane is z = 0; at rest the magnet's near (bottom)
face is ``gap`` above it, its axis along z through the origin, magnetised along +z
(:func:`magdesign.fields.cylinder`, exact fidelity unless the spec says otherwise).
Where the spec asks for it, the magnet's polarization has another ``direction`` (a unit
vector in its own frame: axial plus diametral parts), its pose an ``offset`` (m) from that
centre and a rotation ``angles`` (rad, as a chip's, :mod:`magdesign.scene.pose`), and
further magnets (``extra``, :class:`magdesign.scene.pose.Magnet`), carried with it or
fixed, add their fields. Soft-magnetic parts (``soft``, :class:`magdesign.scene.pose.SoftPart`,
the method of moments) are magnetised by the magnets and by one another (one system of all
their cells), and add their own fields.
Sensors sit at given positions (a reference sensor at the origin for the dome-Hall
sensor; a 4 x 2 matrix for the spin-valve matrix; four GMR at several depths for the
GMR-inductor sensor). A press moves the magnet by -z towards them (the spin-valve chips move towards a fixed magnet: the
same relative displacement).

Outputs (:meth:`MagnetScene.outputs`), read from a simulation of the load sweep (see
docs/outputs.md): "rest" is the sweep's first point, "closest" its largest normal force
F, dF the force between them; fields are in each chip's frame (a, b, c) after the
scene's field effects, before its reading effects.
    compliance         (uz(rest) - uz(closest)) / dF (m/N)
    closest_gap        gap + the lowest uz of the sweep (m)
    field_rest         B_c at sensor 0 at rest (T)
    field_closest      B_c at sensor 0 at closest (T)
    sensitivity        (field_closest - field_rest) / dF (T/N)
    field_max          largest |B| component over every sensor, axis and load point (T)
    inplane_field_max  largest |B_a| (the chip's sensitive in-plane axis) over every
                       sensor and load point (T)
    inplane_field_min  the smallest (most negative) B_a over the same (T)
    embed              how deep the magnet's near face lies below the top of the part that
                       carries it at rest (the layer's top face, the dome's outer apex):
                       top - gap (m); below 0 the magnet floats above its part
    reach              how far the magnet's far face reaches above the lowest point of the
                       part that holds it (a dome's inner apex, a layer's base): gap + height
                       - bottom (m); below 0 the magnet hangs in the dome's cavity
    outer_radius       the dome's outer radius (m), for dome scenes only
    travel_fraction    the largest travel towards the sensors over the room the part allows
                       (a dome's inner height R_o - t, a layer's thickness) (-)
    mechanics_converged  1 if the mechanics converged at every load point, else 0 (-)
and, when the scene lists the effect (:func:`magdesign.scene.effects.effect_outputs`):
    saturation_ratio   largest |reading| / saturation limit, per channel (-); above 1 clips
                       (also without the effect for a Hall chip, against its preset's range:
                       :meth:`MagnetScene.chip_range`)
    resolution         one LSB of sensor 0's last channel over its reading sensitivity (N)
    noise_equivalent_force  one sigma of that channel over the same (N)
"""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from magdesign.scene.core import MECHANICS_CONVERGED, AbstractScene
from magdesign.scene.effects import AbstractEffect, effect_output_units, effect_outputs, judged_saturation
from magdesign.scene.mechanics import AbstractMechanics
from magdesign.scene.pose import Magnet, SoftPart, posed_cylinder, rotation, soft_parameter_paths, soft_parts_field
from magdesign.transducers import Hall3D, SpinValve, add_noise, emf, slip_flags


class SpinValveReadout(eqx.Module):
    """A spin valve's output voltage, optionally amplified as a bridge difference.

    reading = amplification * (V(B) - V(0)) if ``differential`` else amplification * V(B),
    V = I R0 (1 + s f(B_a)) (:class:`magdesign.transducers.SpinValve`).
    """

    valve: SpinValve
    amplification: Float[Array, ""]
    differential: bool = eqx.field(static=True)

    def __call__(self, field):
        voltage = self.valve.voltage(field)
        if self.differential:
            voltage = voltage - self.valve.bias_current * self.valve.resistance
        return self.amplification * voltage


class Inductors(eqx.Module):
    """The GMR-inductor sensor's chip inductors: EMF = -N d(Bz A)/dt, amplified, and the slip flags.

    ``positions`` (I, 3) (m), ``area`` the coil's mean turn area (m^2), ``turns`` N,
    ``amplification`` (-), ``noise`` the output's Gaussian noise (V rms, drawn when a
    simulation has a key); ``window`` samples of history for the 3-sigma slip test, which
    judges the noisy output (on a noiseless one any rounding leaves a constant history's
    zero-width band).
    """

    positions: Float[Array, "i 3"]
    area: Float[Array, ""]
    turns: Float[Array, ""]
    amplification: Float[Array, ""]
    noise: Float[Array, ""]
    window: int = eqx.field(static=True)


class MagnetScene(AbstractScene):
    """A cylinder magnet over sensors (see the module docstring); SI throughout."""

    radius: Float[Array, ""]
    height: Float[Array, ""]
    remanence: Float[Array, ""]
    gap: Float[Array, ""]
    mechanics: AbstractMechanics
    sensor_positions: Float[Array, "s 3"]
    sensor_angles: Float[Array, "s 3"]
    transducer: Hall3D | SpinValveReadout
    effects: tuple[AbstractEffect, ...]
    inductors: Inductors | None = None
    fidelity: str = eqx.field(static=True, default="exact")
    direction: Float[Array, "3"] | None = None
    offset: Float[Array, "3"] | None = None
    angles: Float[Array, "3"] | None = None
    extra: tuple[Magnet, ...] = ()
    soft: tuple[SoftPart, ...] = ()

    SOURCE_KEY = "magnet.remanence"
    OUTPUT_UNITS: ClassVar[dict[str, str]] = {
        "compliance": "m/N",
        "closest_gap": "m",
        "field_rest": "T",
        "field_closest": "T",
        "sensitivity": "T/N",
        "field_max": "T",
        "inplane_field_max": "T",
        "inplane_field_min": "T",
        "embed": "m",
        "reach": "m",
        MECHANICS_CONVERGED: "1",
    }

    @property
    def output_units(self):
        judged = {} if self.chip_range() is None else {"saturation_ratio": "1"}
        return {**self.OUTPUT_UNITS, **self.mechanics.output_units, **effect_output_units(self.effects), **judged}

    def chip_range(self):
        """The listed saturation effect, else a Hall chip's own range (its preset's full
        scale per axis); a spin valve's range is its read-out's, known only from the effect."""
        full_scale = self.transducer.full_scale if isinstance(self.transducer, Hall3D) else None
        return judged_saturation(self.effects, full_scale)

    @property
    def parameter_paths(self):
        paths = {
            "geometry.gap": lambda s: s.gap,
            "magnet.radius": lambda s: s.radius,
            "magnet.height": lambda s: s.height,
            "magnet.remanence": lambda s: s.remanence,
        }
        for name, get in self.mechanics.parameter_paths.items():
            paths[name] = lambda s, get=get: get(s.mechanics)
        return paths | soft_parameter_paths(self.soft, lambda s: s.soft)

    @property
    def reading_labels(self):
        return ("Bx", "By", "Bz") if isinstance(self.transducer, Hall3D) else ("V",)

    @property
    def reading_unit(self):
        return "T" if isinstance(self.transducer, Hall3D) else "V"

    def sensor_poses(self):
        return self.sensor_positions, rotation(self.sensor_angles)

    def displacement(self, loads):
        return self.mechanics.displacement(loads)

    def magnet_centre(self):
        """The main magnet's centre at rest (m, scene frame)."""
        centre = jnp.array([0.0, 0.0, 1.0]) * (self.gap + self.height / 2)
        return centre if self.offset is None else centre + self.offset

    def source_field(self, points, displacement):
        field = self.magnets_field(points, displacement)
        if self.soft:
            field = field + soft_parts_field(
                self.soft, points, displacement, lambda x: self.magnets_field(x, displacement)
            )
        return field

    def magnets_field(self, points, displacement):
        """The permanent magnets' flux density (T) at ``points`` (m, scene frame)."""
        polarization = self.remanence if self.direction is None else self.remanence * self.direction
        field = posed_cylinder(
            points,
            centre=self.magnet_centre() + displacement,
            angles=self.angles,
            radius=self.radius,
            height=self.height,
            polarization=polarization,
            fidelity=self.fidelity,
        )
        for magnet in self.extra:
            field = field + magnet.field(points, displacement, self.fidelity)
        return field

    def transduce(self, field):
        if isinstance(self.transducer, Hall3D):
            return field
        return self.transducer(field)[..., None]

    def outputs(self, result):
        loads, field = result.loads, result.chip_field
        closest = jnp.argmax(loads.normal)
        force = loads.normal[closest] - loads.normal[0]
        uz = result.displacement[:, 2]
        field_rest, field_closest = field[0, 0, 2], field[closest, 0, 2]
        ideal = self.transduce(field)
        judged = self.chip_range()
        return {
            "compliance": (uz[0] - uz[closest]) / force,
            "closest_gap": self.gap + jnp.min(uz),
            "field_rest": field_rest,
            "field_closest": field_closest,
            "sensitivity": (field_closest - field_rest) / force,
            "field_max": jnp.max(jnp.abs(field)),
            "inplane_field_max": jnp.max(jnp.abs(field[..., 0])),
            "inplane_field_min": jnp.min(field[..., 0]),
            "embed": self.mechanics.top() - self.gap,
            "reach": self.gap + self.height - self.mechanics.bottom(),
            MECHANICS_CONVERGED: jnp.all(result.converged).astype(float),
            **self.mechanics.outputs(result.displacement),
            **effect_outputs(self.effects, ideal, (ideal[closest, 0, -1] - ideal[0, 0, -1]) / force),
            **({} if judged is None else {"saturation_ratio": judged.ratio(ideal)}),
        }

    def probe_points(self):
        return None if self.inductors is None else self.inductors.positions

    def extras(self, displacement, loads, probe_field, key=None):
        if self.inductors is None:
            return {}
        coils = self.inductors
        bz = probe_field[..., 2]
        dt = loads.time[1] - loads.time[0]
        output = coils.amplification * emf(bz * coils.area, dt=dt, turns=coils.turns)
        if key is not None:
            output = add_noise(output, key, coils.noise)
        return {"inductor_emf": output, "slip": slip_flags(output, window=coils.window)}
