"""Signal stages of a read-out, shared by the transducers and the scene's effects:
Gaussian noise, hard and smooth saturation, quantisation. Each is a small pure function
of a reading (any units, as long as its arguments share them; tesla for a Hall sensor)."""

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float, PRNGKeyArray


def add_noise(
    b: Float[ArrayLike, "... 3"], key: PRNGKeyArray, noise_std: Float[ArrayLike, "3"]
) -> Float[Array, "... 3"]:
    """b plus white Gaussian noise of standard deviation ``noise_std`` (T, rms per axis)."""
    b = jnp.asarray(b)
    return b + jnp.asarray(noise_std) * jax.random.normal(key, b.shape, dtype=b.dtype)


def saturate(b: Float[ArrayLike, "..."], full_scale: Float[ArrayLike, "..."]) -> Float[Array, "..."]:
    """Hard saturation: b clipped to [-full_scale, +full_scale] (T). Zero gradient beyond."""
    full_scale = jnp.asarray(full_scale)
    return jnp.clip(jnp.asarray(b), -full_scale, full_scale)


def soft_clip(
    x: Float[ArrayLike, "..."], linear: Float[ArrayLike, "..."], limit: Float[ArrayLike, "..."]
) -> Float[Array, "..."]:
    """Smooth saturation: exactly x for |x| <= linear, tending to +-limit beyond.

    Beyond the linear range, sign(x) (linear + w tanh((|x| - linear) / w)) with
    w = limit - linear > 0: value, slope (1) and curvature (0) are continuous at
    |x| = linear, the slope decays to 0 and the output never exceeds ``limit``. Any
    units, as long as the three arguments share them.
    """
    x, linear, limit = jnp.asarray(x), jnp.asarray(linear), jnp.asarray(limit)
    width = limit - linear
    magnitude = jnp.abs(x)
    bent = jnp.sign(x) * (linear + width * jnp.tanh((magnitude - linear) / width))
    return jnp.where(magnitude <= linear, x, bent)


def quantise(
    b: Float[ArrayLike, "..."], lsb: Float[ArrayLike, "..."], *, straight_through: bool = False
) -> Float[Array, "..."]:
    """b rounded to the nearest multiple of ``lsb`` (T).

    The rounded value has a zero derivative almost everywhere. With
    ``straight_through=True`` the value is the same but the derivative is taken as 1
    (the straight-through estimator), so that gradients pass through the ADC.
    """
    b, lsb = jnp.asarray(b), jnp.asarray(lsb)
    rounded = lsb * jnp.round(b / lsb)
    if straight_through:
        return b + jax.lax.stop_gradient(rounded - b)
    return rounded
