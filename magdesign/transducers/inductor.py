"""Chip inductors as flux-rate sensors, and the stick-slip detector of the GMR-inductor paper
("A Magnetic Type Tactile Sensor by GMR elements and inductors", Sec. II-C).

A coil of N turns linking the flux Phi(t) gives EMF = -N dPhi/dt (Faraday); it is
large at the instant of a stick-slip, when the deformed layer snaps back. The paper flags
a slip when the output V_now of every inductor leaves A - 3 sigma <= V_now <= A + 3 sigma,
A and sigma the mean and standard deviation of that inductor's recent outputs.

Time runs along axis 0 of every series; further axes are channels.
"""

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Bool, Float


def emf(flux: Float[ArrayLike, "time ..."], *, dt: float, turns: float = 1.0) -> Float[Array, "time ..."]:
    """EMF = -N dPhi/dt (V) of a flux series ``flux`` (Wb) sampled every ``dt`` (s).

    The derivative is the second-order central difference inside the series and the
    first-order one-sided difference at its two ends (``jnp.gradient``); the output
    has the shape of ``flux``, which needs at least two samples.
    """
    flux = jnp.asarray(flux)
    if flux.ndim == 0 or flux.shape[0] < 2:
        raise ValueError(f"flux must have at least two samples along axis 0, got shape {flux.shape}")
    return -turns * jnp.gradient(flux, dt, axis=0)


def slip_flags(signal: Float[ArrayLike, "time channels"], *, window: int, n_sigma: float = 3.0) -> Bool[Array, " time"]:
    """The GMR-inductor paper's slip test: True where every channel leaves mean +- n_sigma * std.

    Args:
        signal: outputs (V or any unit), shape (time, channels) or (time,) for one channel.
        window: number of trailing samples (before the current one) that give the
            mean A and standard deviation sigma; a Python int (static under jit).
            The first ``window`` samples have no full history and are never flagged.
        n_sigma: half-width of the band in standard deviations (3 in the GMR-inductor paper).

    Returns:
        (time,) booleans, True where all channels are outside their band at once.
    """
    if not isinstance(window, int) or window < 2:
        raise ValueError(f"window must be an integer >= 2, got {window!r}")
    signal = jnp.asarray(signal)
    if signal.ndim == 1:
        signal = signal[:, None]
    steps = signal.shape[0]
    index = jnp.arange(steps)[:, None] - window + jnp.arange(window)[None, :]
    history = signal[jnp.clip(index, 0, None)]  # (time, window, channels)
    mean = jnp.mean(history, axis=1)
    sigma = jnp.std(history, axis=1)
    outside = jnp.abs(signal - mean) > n_sigma * sigma
    return jnp.all(outside, axis=-1) & (jnp.arange(steps) >= window)


def count_events(flags: Bool[ArrayLike, " time"]) -> Array:
    """Number of separate events in a flag series: runs of consecutive True count once."""
    flags = jnp.asarray(flags, dtype=bool)
    starts = flags[1:] & ~flags[:-1]
    return jnp.sum(starts) + flags[0]
