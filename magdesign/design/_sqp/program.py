"""The compiled program around the core: a problem split into its structure and array
leaves, its arrays and starts found once, the jitted core cached per structure, the packed
solution and its unpacking."""

import functools
from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from magdesign import _export
from magdesign._tracing import (
    compiler_options,
    errors_as_nan,
    free_programs_near_mapping_limit,
    gc_paused,
    program_cache,
)
from magdesign.design._sqp.core import CoreSolution, _core
from magdesign.design._sqp.jet import Settings, problem_arrays
from magdesign.design._sqp.sqp import SQP
from magdesign.design.problem import Problem, per_problem


def _packed(problem, y0, theta, settings):
    """The core's solution as one float64 vector, read back from the device in one go."""
    return jnp.concatenate(
        [jnp.ravel(leaf).astype(jnp.float64) for leaf in jax.tree.leaves(_core(problem, y0, theta, settings))]
    )


def _unpack(problem, packed):
    """CoreSolution of numpy arrays from :func:`_packed`'s vector(s) (leading batch axes kept)."""
    host = _host(problem)
    parts = {name: packed[..., start:stop] for name, (start, stop) in host.layout.items()}
    batch, n, p = packed.shape[:-1], len(problem.variables), len(host.theta)
    return CoreSolution(
        x=parts["x"],
        multipliers=parts["multipliers"],
        outputs=parts["outputs"],
        residuals=parts["residuals"],
        active_limits=parts["active_limits"] > 0.5,
        at_lower=parts["at_lower"] > 0.5,
        at_upper=parts["at_upper"] > 0.5,
        derivatives=parts["derivatives"].reshape(*batch, n, p),
        status=parts["status"][..., 0].astype(int),
        steps=parts["steps"][..., 0].astype(int),
    )


def _split(tree):
    """(key, arrays) of a pytree: its array leaves are traced; its structure and other
    leaves (the model, Python numbers) key the compiled program, as in eqx.filter_jit,
    at a fraction of its cost per call."""
    leaves, treedef = jax.tree.flatten(tree)
    is_array = tuple(eqx.is_array(leaf) for leaf in leaves)
    static = tuple(None if array else leaf for array, leaf in zip(is_array, leaves))
    return (treedef, is_array, static), [leaf for array, leaf in zip(is_array, leaves) if array]


class _Host(NamedTuple):
    """What solving a problem needs of it outside the compiled core, found once per
    problem object (:func:`per_problem`): its arrays (numpy, :func:`problem_arrays`), its
    variables' own starts (scaled) and theta on the device, its structure and array
    leaves (:func:`_split`, the leaves on the device: numpy leaves would be copied there
    at every call), and where each part of the packed solution lies."""

    arrays: tuple
    y0: Array
    theta: Array
    key: tuple
    leaves: list
    layout: dict


@per_problem
def _host(problem):
    arrays = problem_arrays(problem, np)
    for array in arrays:  # shared by every solve of the problem
        array.flags.writeable = False
    theta = arrays[4]
    key, leaves = _split(problem)
    n, m, k = len(problem.variables), len(problem.targets) + len(problem.limit_rows), len(problem.outputs)
    sizes = {
        "x": n,
        "multipliers": m,
        "outputs": k,
        "residuals": m,
        "active_limits": m - len(problem.targets),
        "at_lower": n,
        "at_upper": n,
        "derivatives": n * len(theta),
        "status": 1,
        "steps": 1,
    }
    stops = np.cumsum(list(sizes.values())).tolist()
    layout = {name: (stop - size, stop) for (name, size), stop in zip(sizes.items(), stops)}
    return _Host(
        arrays,
        jax.device_put(_start(problem, None, arrays)),
        jax.device_put(theta),
        key,
        jax.device_put(leaves),
        layout,
    )


@program_cache
@functools.lru_cache(maxsize=64)
def _compiled(key, batched):
    """The jitted core of one structure of (problem, settings), ``key`` a pair of
    :func:`_split` keys: (arrays, y0, theta) -> packed solution, ``arrays`` the pair of
    their array leaves, vmapped over y0 and theta if ``batched``; kept exported on disk
    where :mod:`magdesign._export` is on (``key`` is the structure it is kept by). A new
    entry is a program about to be compiled: first the compiled programs are freed if
    they hold half the memory mappings the process may have."""
    free_programs_near_mapping_limit()

    def run(arrays, y0, theta):
        problem, settings = (_joined(part_key, part) for part_key, part in zip(key, arrays))
        return _packed(problem, y0, theta, settings)

    return _export.jit(
        jax.vmap(run, in_axes=(None, 0, 0)) if batched else run,
        "solve-batch" if batched else "solve",
        repr(key),
        compiler_options=compiler_options,  # probed only where the program is traced
        batched=(1, 2) if batched else (),
    )


def _joined(key, arrays):
    """The pytree that :func:`_split` split into ``key`` and ``arrays``."""
    treedef, is_array, static = key
    arrays = iter(arrays)
    return jax.tree.unflatten(treedef, [next(arrays) if array else leaf for array, leaf in zip(is_array, static)])


_IN_PROGRAM = {}  # id(settings) -> (settings, _in_program's answer); holds settings, so ids stay unique


def _in_program(settings):
    """``settings`` with the solver's fields that only batches read at their defaults
    (:meth:`SQP.in_program`), so that those fields key no program of their own; one
    object per ``settings`` object (building a Module costs more than a warm solve's
    overhead)."""
    entry = _IN_PROGRAM.get(id(settings))
    if entry is None:
        if len(_IN_PROGRAM) >= 64:
            _IN_PROGRAM.clear()
        program = Settings(settings.rtol, settings.atol, settings.max_steps, settings.sqp.in_program())
        entry = _IN_PROGRAM[id(settings)] = (settings, program)
    return entry[1]


def _structure(problem, settings):
    """(key, arrays) of (problem, settings) for :func:`_compiled`."""
    host, (settings_key, settings_leaves) = _host(problem), _split(_in_program(settings))
    return (host.key, settings_key), (host.leaves, settings_leaves)


def _run(problem, y0, theta, settings):
    """The packed solution as a numpy array, from the cached compiled core."""
    key, arrays = _structure(problem, settings)
    with errors_as_nan(), gc_paused():
        return np.asarray(_compiled(key, False)(arrays, y0, theta))


@functools.lru_cache(maxsize=16)
def settings_of(rtol, atol, max_steps, sqp=None):
    """The :class:`Settings` of a solve: tolerances rtol and atol (scaled), max_steps, and
    the solver ``sqp`` (:class:`SQP`; None: its defaults); one object per distinct set."""
    if sqp is not None and not isinstance(sqp, SQP):
        raise TypeError(f"solver must be an SQP, got {type(sqp).__name__}")
    if not max_steps >= 1:
        raise ValueError(f"max_steps must be at least 1, got {max_steps!r}")
    for name, value in (("rtol", rtol), ("atol", atol)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be positive and finite, got {value!r}")
    return Settings(
        np.asarray(rtol, np.float64), np.asarray(atol, np.float64), int(max_steps), SQP() if sqp is None else sqp
    )


def _start(problem: Problem, start, arrays):
    """Scaled start y0 from the variables' starts, overridden by ``start`` {name: SI}."""
    lower, upper, scale, y_start, _ = arrays
    if not start:  # the variables' own starts, checked inside their bounds on construction
        return (y_start - lower) / scale
    start = dict(start)
    unknown = sorted(set(start) - {v.name for v in problem.variables})
    if unknown:
        raise ValueError(f"start: unknown variable {unknown[0]!r}")
    values = []
    for j, v in enumerate(problem.variables):
        value = np.asarray(start.get(v.name, y_start[j]), np.float64)
        if not np.all(np.isfinite(value) & (value >= lower[j]) & (value <= upper[j])):
            raise ValueError(f"{v.name}: start {start[v.name]!r} outside the bounds [{lower[j]!r}, {upper[j]!r}]")
        values.append(value)
    return (np.stack(np.broadcast_arrays(*values), axis=-1) - lower) / scale


def batch_inputs(problem: Problem, start, count: int):
    """(y0, thetas): the inputs of ``count`` solves of ``problem`` for
    :func:`~magdesign.design._sqp.batch.solve_batch`. y0 (count, n): the starts scaled to
    the variables' bound widths, the variables' own overridden by ``start`` {name: SI
    value, or (count,) values; None: none}; thetas (count, p): the problem's target
    values, limit bounds and fixed inputs (SI, :func:`problem_arrays`' theta) on every row,
    a new array that a sweep may change column by column."""
    arrays = _host(problem).arrays
    y0 = np.broadcast_to(_start(problem, start, arrays), (count, len(problem.variables)))
    return y0, np.repeat(arrays[4][None, :], count, axis=0)
