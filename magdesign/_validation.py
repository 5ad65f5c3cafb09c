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


def check_positive(unit=None, **values):
    """Raise ValueError unless every named value is > 0 (finite, all elements); the
    message names the value and, where given, its ``unit`` ("m")."""
    _check_sign(values, unit, np.greater, "positive")


def check_nonnegative(unit=None, **values):
    """Raise ValueError unless every named value is >= 0 (finite, all elements); the
    message names the value and, where given, its ``unit``."""
    _check_sign(values, unit, np.greater_equal, "non-negative")


def _check_sign(values, unit, compare, words):
    for name, value in values.items():
        concrete = _concrete(value)
        if concrete is not None and not (np.all(np.isfinite(concrete)) and np.all(compare(concrete, 0))):
            in_unit = f" (in {unit})" if unit else ""
            raise ValueError(f"{name} must be {words} and finite{in_unit}, got {value!r}")


def check_last_axis(name, array, size):
    """Raise ValueError unless ``array`` has a last axis of length ``size`` (a nested list
    may hold traced values, which numpy cannot read)."""
    shape = jnp.asarray(array).shape if isinstance(array, (list, tuple)) else np.shape(array)
    if len(shape) == 0 or shape[-1] != size:
        raise ValueError(f"{name} must have shape (..., {size}), got shape {shape}")
