"""Checks of user input at call or trace time: ValueError naming the argument.

Values that are JAX tracers (inside jit, grad, vmap) cannot be inspected and are let
through; they were checked when the concrete design was built.
"""

import jax
import jax.numpy as jnp
import numpy as np


def _concrete(value):
    try:
        return np.asarray(value)
    except (jax.errors.TracerArrayConversionError, jax.errors.ConcretizationTypeError):
        return None


def check_positive(**values):
    """Raise ValueError unless every named value is > 0 (finite, all elements)."""
    for name, value in values.items():
        concrete = _concrete(value)
        if concrete is not None and not (np.all(np.isfinite(concrete)) and np.all(concrete > 0)):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")


def check_nonnegative(**values):
    """Raise ValueError unless every named value is >= 0 (finite, all elements)."""
    for name, value in values.items():
        concrete = _concrete(value)
        if concrete is not None and not (np.all(np.isfinite(concrete)) and np.all(concrete >= 0)):
            raise ValueError(f"{name} must be non-negative and finite, got {value!r}")


def check_last_axis(name, array, size):
    """Raise ValueError unless ``array`` has a last axis of length ``size`` (a nested list
    may hold traced values, which numpy cannot read)."""
    shape = jnp.asarray(array).shape if isinstance(array, (list, tuple)) else np.shape(array)
    if len(shape) == 0 or shape[-1] != size:
        raise ValueError(f"{name} must have shape (..., {size}), got shape {shape}")
