"""Spin-valve / GMR sensors with one sensitive in-plane axis (the spin-valve matrix and the
magnetic-suspension sensor; docs/references.md).

The field is given as a flux density B = mu0 H (T) in the magnet (world) frame. The
chip sees it in its own frame (a, b, c), a along the sensitive direction (the
spin-valve paper, Eqs. 3-4):

    H_sensor = Rx(alpha) Ry(beta) Rz(gamma) H

with the right-handed rotation matrices of Eq. 4 (:func:`chip_frame`; the rotation and
the maps into and out of a chip's frame live in :mod:`magdesign.frames`). Only the
component along a changes the resistance:

    R = R0 (1 + s * f(H_a + offset)),    V = I_bias R

s the sensitivity (1/T; 0.72 %/mT is 7.2 /T), f the identity within the linear range
and a smooth saturation beyond it (:func:`magdesign.transducers.signal.soft_clip`).
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._validation import check_nonnegative, check_positive
from magdesign.frames import rotation_matrix, to_body
from magdesign.transducers.signal import soft_clip
from magdesign.units import MU0, mT

# The map of a field into the chips' frames, under the name the transducers' API gives it.
to_chip = to_body


def chip_frame(
    h: Float[ArrayLike, "... 3"],
    alpha: Float[ArrayLike, "..."] = 0.0,
    beta: Float[ArrayLike, "..."] = 0.0,
    gamma: Float[ArrayLike, "..."] = 0.0,
) -> Float[Array, "... 3"]:
    """The field ``h`` (any unit), (..., 3), in the chip frame (H_a, H_b, H_c), Eq. 3."""
    return to_chip(rotation_matrix(alpha, beta, gamma), jnp.asarray(h))


class SpinValve(eqx.Module):
    """A spin-valve (GMR) resistor under a constant bias current.

    Fields:
        resistance: R0 at zero field (Ohm), > 0.
        sensitivity: relative resistance change per tesla of B = mu0 H along the
            sensitive axis (1/T), > 0; 0.72 %/mT is 7.2.
        bias_current: I (A), >= 0.
        linear_range: half-width of the linear range (T), > 0, or None for an ideal
            linear element (no published range).
        saturation_field: the field (T) the effective field tends to far beyond the
            linear range, > linear_range (ignored when linear_range is None).
        offset: shift of the transfer curve (T): the element reads H_a + offset.
    """

    resistance: Float[ArrayLike, ""]
    sensitivity: Float[ArrayLike, ""]
    bias_current: Float[ArrayLike, ""]
    linear_range: Float[ArrayLike, ""] | None = None
    saturation_field: Float[ArrayLike, ""] | None = None
    offset: Float[ArrayLike, ""] = 0.0

    def __check_init__(self):
        check_positive(resistance=self.resistance, unit="Ohm")
        check_positive(sensitivity=self.sensitivity, unit="1/T")
        check_nonnegative(bias_current=self.bias_current, unit="A")
        if self.linear_range is not None:
            check_positive(linear_range=self.linear_range, unit="T")
            if self.saturation_field is None:
                raise ValueError("saturation_field is needed when linear_range is given")
            excess = jnp.asarray(self.saturation_field) - self.linear_range
            check_positive(**{"saturation_field - linear_range": excess}, unit="T")

    def effective_field(
        self,
        b: Float[ArrayLike, "... 3"],
        alpha: Float[ArrayLike, "..."] = 0.0,
        beta: Float[ArrayLike, "..."] = 0.0,
        gamma: Float[ArrayLike, "..."] = 0.0,
    ) -> Float[Array, "..."]:
        """The field (T) that sets the resistance: H_a + offset, saturated smoothly."""
        h_a = chip_frame(b, alpha, beta, gamma)[..., 0] + self.offset
        if self.linear_range is None:
            return h_a
        return soft_clip(h_a, self.linear_range, self.saturation_field)

    def relative_change(
        self,
        b: Float[ArrayLike, "... 3"],
        alpha: Float[ArrayLike, "..."] = 0.0,
        beta: Float[ArrayLike, "..."] = 0.0,
        gamma: Float[ArrayLike, "..."] = 0.0,
    ) -> Float[Array, "..."]:
        """(R - R0) / R0 (-) at the field ``b`` (T), (..., 3); angles (rad) as in Eq. 4."""
        return self.sensitivity * self.effective_field(b, alpha, beta, gamma)

    def resistance_at(
        self,
        b: Float[ArrayLike, "... 3"],
        alpha: Float[ArrayLike, "..."] = 0.0,
        beta: Float[ArrayLike, "..."] = 0.0,
        gamma: Float[ArrayLike, "..."] = 0.0,
    ) -> Float[Array, "..."]:
        """R (Ohm) at the field ``b`` (T), (..., 3)."""
        return self.resistance * (1.0 + self.relative_change(b, alpha, beta, gamma))

    def voltage(
        self,
        b: Float[ArrayLike, "... 3"],
        alpha: Float[ArrayLike, "..."] = 0.0,
        beta: Float[ArrayLike, "..."] = 0.0,
        gamma: Float[ArrayLike, "..."] = 0.0,
    ) -> Float[Array, "..."]:
        """Output voltage I R (V) at the field ``b`` (T), (..., 3)."""
        return self.bias_current * self.resistance_at(b, alpha, beta, gamma)

    def equivalent_field(
        self, resistance: Float[ArrayLike, "..."], reference: Float[ArrayLike, "..."] | None = None
    ) -> Float[Array, "..."]:
        """Equivalent field change (T) of the spin-valve paper, Eqs. 1-2: dR% / sensitivity.

        dR = (resistance - reference) / reference, ``reference`` defaulting to R0; a
        ratio of voltages under the same bias current may be passed instead of a
        ratio of resistances. Exact inverse of the linear range only.
        """
        reference = self.resistance if reference is None else reference
        return (jnp.asarray(resistance) - reference) / reference / self.sensitivity


def inesc_spin_valve() -> SpinValve:
    """The spin-valve paper's chip (Section 4.1): six 2 x 35 um^2 spin valves in series (INESC-MN).

    R0 = 2 kOhm, 0.72 %/mT, 1 mA bias (2.000 V at zero field, 2.0144 / 1.9856 V at
    +-1 mT; the paper rounds to 2.015 / 1.985 V), linear within +-2.5 mT. The
    saturation field 3.47 mT is where 0.72 %/mT reaches MR / 2 = 2.5 % (MR ~ 5 %, the
    resistance swing of the whole transfer curve, centred at zero field).
    """
    sensitivity = 0.72e-2 / mT
    return SpinValve(
        resistance=2e3,
        sensitivity=sensitivity,
        bias_current=1e-3,
        linear_range=2.5 * mT,
        saturation_field=0.5 * 0.05 / sensitivity,
    )


def panasonic_meander(resistance: float = 1e3) -> SpinValve:
    """The GMR meander of Sajat's (2008) magnetic-suspension thesis: 0.131 mV per A/m at a 0.6 V bias.

    0.131 mV per A/m of H is 0.131e-3 / (0.6 * MU0) = 173.7 /T relative change per
    tesla of B = mu0 H. The thesis does not give R0 legibly; every output voltage depends
    on it only through I R0 = 0.6 V, so ``resistance`` is a placeholder. The thesis
    reports no saturation over its measurements: the element is ideal linear.
    """
    bias_voltage = 0.6
    return SpinValve(
        resistance=resistance,
        sensitivity=0.131e-3 / (bias_voltage * MU0),
        bias_current=bias_voltage / resistance,
    )


def nve_aa003() -> SpinValve:
    """NVE AA003-02 GMR bridge at a 5 V supply, from NVE's AA-series catalogue.

    A 5 kOhm bridge, sensitivity 2.0-3.2 mV/V/Oe (mid value 2.6 mV/V per 0.1 mT: 26 /T of
    output per supply volt), linear to 14 Oe (1.4 mT), saturating at 20 Oe (2 mT); 5 V
    across 5 kOhm is a 1 mA bias.
    """
    return SpinValve(resistance=5e3, sensitivity=26.0, bias_current=1e-3, linear_range=1.4e-3, saturation_field=2.0e-3)
