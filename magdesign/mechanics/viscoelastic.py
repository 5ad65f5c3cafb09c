"""Viscoelastic rate dependence as a first-order discrete lag.

The dome-Hall paper ("Design and Fabrication of a Soft Magnetic Tactile Sensor", Eq. 2)
identifies the sensor's response at 100 Hz as

    G(z) = 0.01955 / (1 - 0.9804 z^-1),   i.e.   y[n] = 0.9804 y[n-1] + 0.01955 x[n].

The pole a = exp(-1 / (tau fs)) of a first-order lag sampled at fs gives the time
constant tau = -1 / (fs ln a) = 0.505 s for a = 0.9804 at 100 Hz. The numerator is not
exactly 1 - a = 0.0196: the DC gain is 0.01955 / 0.0196 = 0.9974, i.e. the identified
sensor settles 0.26 % below its input. :func:`lag_filter` takes that DC gain as
``gain`` (1 for a pure lag); DOME_HALL_GAIN is the identified value.
"""

import jax
import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from magdesign._validation import check_positive

# The dome-Hall paper's Eq. 2: G(z) = DOME_HALL_NUMERATOR / (1 - DOME_HALL_POLE z^-1) at 100 Hz.
DOME_HALL_POLE = 0.9804
DOME_HALL_NUMERATOR = 0.01955
DOME_HALL_SAMPLE_RATE = 100.0  # Hz
DOME_HALL_GAIN = DOME_HALL_NUMERATOR / (1.0 - DOME_HALL_POLE)


def lag_pole(time_constant: Float[ArrayLike, ""], sample_rate: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Pole a = exp(-1 / (tau fs)) (-) of a lag with time constant tau (s) sampled at fs (Hz)."""
    check_positive(time_constant=time_constant, unit="s")
    check_positive(sample_rate=sample_rate, unit="Hz")
    return jnp.exp(-1.0 / (jnp.asarray(time_constant) * sample_rate))


def time_constant_from_pole(pole: Float[ArrayLike, ""], sample_rate: Float[ArrayLike, ""]) -> Float[Array, ""]:
    """Time constant tau = -1 / (fs ln a) (s) of the discrete pole 0 < a < 1 at fs (Hz)."""
    check_positive(pole=pole, one_minus_pole=1.0 - jnp.asarray(pole))
    check_positive(sample_rate=sample_rate, unit="Hz")
    return -1.0 / (sample_rate * jnp.log(pole))


def lag_filter(
    x: Float[ArrayLike, "time ..."],
    *,
    time_constant: Float[ArrayLike, ""],
    sample_rate: Float[ArrayLike, ""],
    gain: Float[ArrayLike, ""] = 1.0,
    initial: Float[ArrayLike, "..."] = 0.0,
) -> Float[Array, "time ..."]:
    """First-order lag y[n] = a y[n-1] + gain (1 - a) x[n] of the series ``x`` (time on axis 0).

    Args:
        x: input series (a force (N), a displacement (m), ...), shape (time, ...).
        time_constant: tau (s), > 0; a = exp(-1 / (tau fs)).
        sample_rate: fs (Hz), > 0.
        gain: DC gain (-): a constant input x settles to gain * x.
        initial: y[-1], the output before the first sample (broadcast to x[0]);
            0 is a filter at rest, x[0] * gain a filter already settled.

    Returns:
        y, the shape of ``x``. Differentiable in x, tau, fs, gain and initial.
    """
    x = jnp.asarray(x, dtype=float)
    a = lag_pole(time_constant, sample_rate)
    b = gain * -jnp.expm1(-1.0 / (jnp.asarray(time_constant) * sample_rate))

    def step(previous, sample):
        current = a * previous + b * sample
        return current, current

    start = jnp.broadcast_to(jnp.asarray(initial, dtype=x.dtype), x.shape[1:])
    _, y = jax.lax.scan(step, start, x)
    return y
