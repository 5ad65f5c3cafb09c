"""Effects: the non-ideal parts of a measurement chain, each a small module.

A scene lists the effects it wants; :func:`~magdesign.scene.simulate` applies exactly
those, and an effect that is not listed is not in the traced program at all. Each
effect acts at one stage of the chain through one hook; the hooks are called in the
chain's order, and effects sharing a hook in the order of :data:`EFFECT_ORDER`:

    1. temperature_drift  source     Br -> Br (1 + coefficient * temperature_change)
    2. placement          sensors    sensor positions + offsets
    3. chip_tilt          sensors    chip rotation Rx Ry Rz (spin-valve paper, Eq. 3) composed
                                     with the chip's nominal orientation
    4. viscoelastic_lag   motion     first-order lag of the displacement time series
    5. area_averaging     sampling   field averaged over the active area, n x n
                                     Gauss-Legendre nodes in the chip plane
    6. background         field      a uniform field (e.g. the Earth's 50 uT) added
    7. saturation         reading    clip to the transducer's range
    8. noise              reading    Gaussian noise (needs a PRNG key)
    9. quantisation       reading    round to the transducer's LSB

Noise comes before quantisation because the converter quantises the noisy analog
signal. Parameters of effects are pytree leaves (differentiable); the list is static.
"""

from typing import ClassVar

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float, PRNGKeyArray

from magdesign.mechanics import lag_filter
from magdesign.scene.pose import rotation
from magdesign.transducers import add_noise, quantise, saturate


class AbstractEffect(eqx.Module):
    """One effect; it overrides the one hook of its stage, the others pass through."""

    name: ClassVar[str]

    def source_scale(self) -> Float[Array, ""] | None:
        """Factor on the source's strength (remanence / magnetisation), or None."""
        return None

    def sensors(self, positions, rotations):
        """(positions (S, 3) m, rotations (S, 3, 3)) of the sensors, adjusted."""
        return positions, rotations

    def motion(self, displacement: Float[Array, "n 3"], time: Float[Array, " n"]) -> Float[Array, "n 3"]:
        """The source's displacement time series (m), adjusted."""
        return displacement

    def sampling(self, rotations: Float[Array, "s 3 3"]) -> tuple[Float[Array, "s q 3"], Float[Array, " q"]] | None:
        """Where each sensor samples the field, if not at its centre alone: offsets (S, Q, 3)
        (m, scene frame) from each centre and weights (Q,) summing to 1; or None."""
        return None

    def field(self, field: Float[Array, "n s 3"]) -> Float[Array, "n s 3"]:
        """The flux density at the sensors in the scene frame (T), adjusted."""
        return field

    def reading(self, reading: Float[Array, "n s c"], key: PRNGKeyArray | None) -> Float[Array, "n s c"]:
        """The transducers' readings, adjusted."""
        return reading


class TemperatureDrift(AbstractEffect):
    """Reversible temperature coefficient of the remanence (NdFeB about -0.12 %/K)."""

    name: ClassVar[str] = "temperature_drift"
    coefficient: Float[Array, ""]  # (1/K)
    temperature_change: Float[Array, ""]  # (K), from the temperature the scene's Br is given at

    def source_scale(self):
        return 1.0 + self.coefficient * self.temperature_change


class Placement(AbstractEffect):
    """Sensor placement error: offsets (S, 3) or (3,) (m) added to the positions."""

    name: ClassVar[str] = "placement"
    offsets: Float[Array, "*s 3"]

    def sensors(self, positions, rotations):
        return positions + self.offsets, rotations


class ChipTilt(AbstractEffect):
    """Chip tilt (alpha, beta, gamma) (rad), (S, 3) or (3,), applied after the nominal rotation."""

    name: ClassVar[str] = "chip_tilt"
    angles: Float[Array, "*s 3"]

    def sensors(self, positions, rotations):
        return positions, rotation(self.angles) @ rotations


class ViscoelasticLag(AbstractEffect):
    """First-order lag of the displacement, time constant ``time_constant`` (s).

    The dome-Hall paper (Eq. 2) identifies G(z) = 0.01955 / (1 - 0.9804 z^-1) at 100 Hz: tau = 0.505 s.
    The loads' time stamps set the (uniform) step; the series starts at rest.
    """

    name: ClassVar[str] = "viscoelastic_lag"
    time_constant: Float[Array, ""]

    def motion(self, displacement, time):
        return lag_filter(displacement, time_constant=self.time_constant, sample_rate=1.0 / (time[1] - time[0]))


class AreaAveraging(AbstractEffect):
    """Average over a rectangular active area (width along a, height along b) (m).

    ``points`` Gauss-Legendre nodes per side (static); exact for a field polynomial of
    degree 2 points - 1 over the area.
    """

    name: ClassVar[str] = "area_averaging"
    size: Float[Array, "2"]
    points: int = eqx.field(static=True, default=3)

    def sampling(self, rotations):
        x, w = np.polynomial.legendre.leggauss(self.points)
        u, v = np.meshgrid(x, x, indexing="ij")
        local = jnp.stack([u.ravel() * self.size[0] / 2, v.ravel() * self.size[1] / 2, np.zeros(u.size)], axis=-1)
        # chip frame -> scene frame: the transpose of the chip rotation
        return jnp.einsum("sji,qj->sqi", rotations, local), jnp.asarray(np.outer(w, w).ravel() / 4.0)


class Background(AbstractEffect):
    """A uniform background flux density (3,) (T) in the scene frame."""

    name: ClassVar[str] = "background"
    field_: Float[Array, "3"]

    def field(self, field):
        return field + self.field_


class Saturation(AbstractEffect):
    """Clip each reading to +-``limit`` (the transducer's range, in reading units): a
    scalar, or one limit per reading channel (C,) (a Hall sensor's x, y, z ranges)."""

    name: ClassVar[str] = "saturation"
    limit: Float[Array, ""]

    def reading(self, reading, key):
        return saturate(reading, self.limit)

    def ratio(self, ideal: Float[Array, "n s c"]) -> Float[Array, ""]:
        """The largest |ideal reading| / limit over every load point, sensor and channel
        (-), from the readings before the reading effects (n, S, C): above 1 the chip clips."""
        return (abs(ideal) / self.limit).max()  # numpy for numpy arrays (a host-side check)


class Noise(AbstractEffect):
    """Gaussian noise of standard deviation ``sigma`` (reading units; scalar or per
    channel (C,)); needs a key."""

    name: ClassVar[str] = "noise"
    sigma: Float[Array, ""]

    def reading(self, reading, key):
        if key is None:
            raise ValueError("key: the noise effect needs a PRNG key (simulate(..., key=jax.random.key(0)))")
        return add_noise(reading, key, self.sigma)


class Quantisation(AbstractEffect):
    """Round each reading to a multiple of ``lsb`` (reading units; scalar or per channel (C,))."""

    name: ClassVar[str] = "quantisation"
    lsb: Float[Array, ""]

    def reading(self, reading, key):
        return quantise(reading, self.lsb)


# Outputs the reading effects give a design (:func:`effect_outputs`), with their SI units.
EFFECT_OUTPUT_UNITS = {
    "saturation": {"saturation_ratio": "1"},
    "quantisation": {"resolution": "N"},
    "noise": {"noise_equivalent_force": "N"},
}


def judged_saturation(effects, full_scale: Float[Array, "*c"] | None = None) -> "Saturation | None":
    """The range a design's readings are judged against (its ``saturation_ratio``): the
    listed saturation effect, else the chip's own range ``full_scale`` (reading units,
    scalar or per channel (C,): a Hall preset's full scale), else None (no range known).
    A design on a chip meets the chip's range whether or not its simulation clips."""
    listed = next((effect for effect in effects if isinstance(effect, Saturation)), None)
    if listed is not None or full_scale is None:
        return listed
    return Saturation(limit=jnp.asarray(full_scale))


def effect_output_units(effects) -> dict[str, str]:
    """The outputs :func:`effect_outputs` gives for these effects, with their SI units."""
    return {name: unit for effect in effects for name, unit in EFFECT_OUTPUT_UNITS.get(effect.name, {}).items()}


def effect_outputs(effects, ideal: Float[Array, "n s c"], sensitivity: Float[Array, ""]) -> dict[str, Float[Array, ""]]:
    """What the listed reading effects mean for a design, from the ideal readings (n, S, C)
    (before the reading effects) and the reading sensitivity (reading unit per N) of the
    channel a design reads (sensor 0's last channel: a Hall chip's c axis, a valve's V):

        saturation_ratio        max over n, S, C of |ideal| / limit (-); > 1: the clip acts
        resolution              lsb / |sensitivity|: the force of one LSB (N)
        noise_equivalent_force  sigma / |sensitivity|: the force of one sigma (N)

    A per-channel limit, lsb or sigma (C,) is taken per channel (the last for the force
    outputs)."""
    values = {}
    for effect in effects:
        if isinstance(effect, Saturation):
            values["saturation_ratio"] = effect.ratio(ideal)
        elif isinstance(effect, Quantisation):
            values["resolution"] = jnp.ravel(effect.lsb)[-1] / jnp.abs(sensitivity)
        elif isinstance(effect, Noise):
            values["noise_equivalent_force"] = jnp.ravel(effect.sigma)[-1] / jnp.abs(sensitivity)
    return values


EFFECT_ORDER = (
    TemperatureDrift,
    Placement,
    ChipTilt,
    ViscoelasticLag,
    AreaAveraging,
    Background,
    Saturation,
    Noise,
    Quantisation,
)
EFFECT_NAMES = tuple(effect.name for effect in EFFECT_ORDER)


def in_order(effects) -> tuple[AbstractEffect, ...]:
    """The effects sorted into the chain's order; ValueError on a duplicate."""
    names = [effect.name for effect in effects]
    for name in names:
        if names.count(name) > 1:
            raise ValueError(f"effects: {name!r} listed twice")
    return tuple(sorted(effects, key=lambda effect: EFFECT_NAMES.index(effect.name)))
