"""Three-axis Hall sensors: gain, offset, noise, saturation, quantisation.

Each stage of the read-out is a small pure function (the signal stages shared with the
other read-outs and the scene's effects live in :mod:`magdesign.transducers.signal`), so
that a scene applies only the stages (effects) it lists; :class:`Hall3D` chains them all
for a whole reading:

    b  -> gain * b + offset        (:func:`apply_gain_offset`)
       -> + noise                  (:func:`add_noise`, needs a PRNG key)
       -> clip to +-full_scale     (:func:`saturate`, or the smooth :func:`soft_clip`)
       -> round to the LSB         (:func:`quantise`)

Inputs and readings are flux densities in tesla, shape (..., 3) (x, y, z of the chip).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float, PRNGKeyArray

from magdesign._tracing import on_device
from magdesign._validation import check_nonnegative, check_positive
from magdesign.transducers.signal import add_noise, quantise, saturate, soft_clip
from magdesign.units import mT, uT

# Where the smooth saturation of :class:`Hall3D` leaves the identity, as a fraction of
# the full scale: readings below 90 % of full scale are exact, the rest bend smoothly
# towards the full scale instead of clipping.
SMOOTH_KNEE = 0.9

# MLX90393 LSB size (uT per count) for HALLCONF = 0xC and RES_XYZ = 0, indexed by
# GAIN_SEL = 0..7, (x and y, z). Melexis MLX90393 datasheet (rev. 003, 2017), sensitivity
# table; each RES_XYZ step doubles the LSB.
_MLX90393_LSB_UT = (
    (0.751, 1.210),
    (0.601, 0.968),
    (0.451, 0.726),
    (0.376, 0.605),
    (0.300, 0.484),
    (0.250, 0.403),
    (0.200, 0.323),
    (0.150, 0.242),
)
_SIGNED_16_BIT_MAX = 32767


def apply_gain_offset(
    b: Float[ArrayLike, "... 3"], gain: Float[ArrayLike, "3"], offset: Float[ArrayLike, "3"]
) -> Float[Array, "... 3"]:
    """gain * b + offset (T): per-axis sensitivity error (-) and zero-field offset (T)."""
    return jnp.asarray(gain) * jnp.asarray(b) + jnp.asarray(offset)


def _per_axis(value):
    if isinstance(value, jax.Array):  # a tracer too
        return jnp.broadcast_to(jnp.asarray(value, dtype=float), (3,))
    return on_device(np.broadcast_to(np.asarray(value, dtype=np.float64), (3,)))  # no program to compile


class Hall3D(eqx.Module):
    """A three-axis Hall sensor with a digital output.

    Fields (per axis, shape (3,); a scalar is broadcast):
        lsb: flux density of one output count (T).
        full_scale: saturation of the reading (T), > 0.
        gain: sensitivity error, the factor on the true field (-); 1 is ideal.
        offset: zero-field offset (T).
        noise_std: rms noise (T), used only when a PRNG key is given.
    """

    lsb: Float[Array, "3"] = eqx.field(converter=_per_axis)
    full_scale: Float[Array, "3"] = eqx.field(converter=_per_axis)
    gain: Float[Array, "3"] = eqx.field(converter=_per_axis, default=1.0)
    offset: Float[Array, "3"] = eqx.field(converter=_per_axis, default=0.0)
    noise_std: Float[Array, "3"] = eqx.field(converter=_per_axis, default=0.0)

    def __check_init__(self):
        check_positive(lsb=self.lsb, full_scale=self.full_scale, unit="T")
        check_positive(gain=self.gain)
        check_nonnegative(noise_std=self.noise_std, unit="T")

    def __call__(
        self,
        b: Float[ArrayLike, "... 3"],
        *,
        key: PRNGKeyArray | None = None,
        smooth: bool = False,
    ) -> Float[Array, "... 3"]:
        """The reading (T), (..., 3), of the true field ``b`` (T), (..., 3).

        ``key`` adds noise; ``smooth=True`` replaces the hard clip by :func:`soft_clip`
        (identity below SMOOTH_KNEE * full_scale) and rounds with the straight-through
        estimator, so that the reading has useful gradients with respect to ``b`` and
        to the design behind it.
        """
        reading = apply_gain_offset(b, self.gain, self.offset)
        if key is not None:
            reading = add_noise(reading, key, self.noise_std)
        if smooth:
            reading = soft_clip(reading, SMOOTH_KNEE * self.full_scale, self.full_scale)
        else:
            reading = saturate(reading, self.full_scale)
        return quantise(reading, self.lsb, straight_through=smooth)

    def counts(self, b: Float[ArrayLike, "... 3"], *, key: PRNGKeyArray | None = None) -> Float[Array, "... 3"]:
        """The raw output in counts (integer-valued floats), (..., 3)."""
        return jnp.round(self(b, key=key) / self.lsb)


def ak8963() -> Hall3D:
    """AKM AK8963 in 16-bit mode, as used in the dome-Hall sensor.

    0.15 uT per LSB (AK8963 datasheet, 16-bit output); saturation at 4.8 mT, the
    figure the dome-Hall paper designs against (the datasheet's range is +-4912 uT). No noise by
    default: pass ``noise_std`` through ``eqx.tree_at`` where wanted.
    """
    return Hall3D(lsb=0.15 * uT, full_scale=4.8 * mT)


def mlx90393(gain_sel: int = 7, resolution: int = 0) -> Hall3D:
    """Melexis MLX90393 (the taxel sensor of Yan et al. 2021) at a gain and resolution setting.

    LSB sizes from the Melexis MLX90393 datasheet (rev. 003, 2017), sensitivity table
    for HALLCONF = 0xC: 0.150 uT (x, y) and 0.242 uT (z) per count at GAIN_SEL = 7,
    RES_XYZ = 0, up to 0.751 / 1.210 uT at GAIN_SEL = 0; each RES_XYZ step doubles
    them. The output is a signed 16-bit word for RES_XYZ = 0 and 1 (the only settings
    offered here), so the reading saturates at 32767 counts: 4.9 mT (x, y) and 7.9 mT (z)
    at the default setting, up to 49 mT at GAIN_SEL = 0, RES_XYZ = 1 (the datasheet's
    5..50 mT dynamic range). Yan et al. do not state their setting; the default is the
    finest resolution.
    """
    if gain_sel not in range(8):
        raise ValueError(f"gain_sel must be an integer 0..7, got {gain_sel!r}")
    if resolution not in (0, 1):
        raise ValueError(f"resolution must be 0 or 1 (signed 16-bit output), got {resolution!r}")
    lsb_xy, lsb_z = (2**resolution * value * uT for value in _MLX90393_LSB_UT[gain_sel])
    lsb = np.array([lsb_xy, lsb_xy, lsb_z])  # numpy, then on the device: no program to compile
    return Hall3D(lsb=on_device(lsb), full_scale=on_device(_SIGNED_16_BIT_MAX * lsb))
