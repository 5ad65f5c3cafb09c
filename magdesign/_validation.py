"""Checks of user input at call or trace time: ValueError naming the argument.

Values that are JAX tracers (inside jit, grad, vmap) cannot be inspected and are let
through; they were checked when the concrete design was built.
"""

import warnings

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


def _shape(array):
    """The shape of an array, scalar or nested list (which may hold traced values, which
    numpy cannot read). Shapes are static: this holds under jit and vmap too."""
    return jnp.asarray(array).shape if isinstance(array, (list, tuple)) else np.shape(array)


def check_scalar(why, **values):
    """Raise ValueError unless every named value is a scalar (shape ()); ``why`` says
    what the rule is for."""
    for name, value in values.items():
        shape = _shape(value)
        if shape != ():
            raise ValueError(f"{name} must be a scalar ({why}), got shape {shape}")


def check_broadcasts(target, array, vector=False, **values):
    """Raise ValueError unless every named value broadcasts with ``array`` (the argument
    named ``target``); with ``vector`` the last axis of both (the 3 components) is left
    out: (..., 3) points take (...) per-point values."""
    shape = _shape(array)
    against = shape[:-1] if vector else shape
    for name, value in values.items():
        value_shape = _shape(value)
        try:
            np.broadcast_shapes(value_shape, against)
        except ValueError:
            of = f"{target} of shape {shape}[:-1] = {against}" if vector else f"{target} of shape {shape}"
            raise ValueError(f"{name} has shape {value_shape}, which does not broadcast with {of}") from None


def renamed_keyword(function, old, old_value, new, new_value):
    """The value of keyword ``new`` of ``function``, or of its deprecated name ``old``
    (with a DeprecationWarning naming ``new``); exactly one of the two must be given."""
    if old_value is None:
        if new_value is None:
            raise TypeError(f"{function}() missing required keyword argument: {new!r}")
        return new_value
    if new_value is not None:
        raise TypeError(f"{function}(): give {new}= only ({old}= is its deprecated name)")
    warnings.warn(
        f"{function}(..., {old}=...) is deprecated; use {new}= (the same quantity)", DeprecationWarning, stacklevel=3
    )
    return old_value


def check_last_axis(name, array, size):
    """Raise ValueError unless ``array`` has a last axis of length ``size``."""
    shape = _shape(array)
    if len(shape) == 0 or shape[-1] != size:
        raise ValueError(f"{name} must have shape (..., {size}), got shape {shape}")
