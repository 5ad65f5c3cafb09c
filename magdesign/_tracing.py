"""Tracing costly code once per program, and the options its programs compile with."""

import contextlib
import functools
import gc

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.extend.core import ClosedJaxpr, Jaxpr

_errors = {"as_nan": False}  # set by errors_as_nan, read by checked when traced


def traced_once(fn):
    """``fn`` jitted (``equinox.filter_jit``: arrays traced, everything else static), so
    that its calls inside one program with the same structure share one trace, and the
    transformations of that trace, instead of tracing ``fn`` again at each call. For
    costly code called at several places of a program (a model's derivatives, a dome's
    tangent).

    Arguments that are not arrays are static, Python floats too: a float that changes
    from call to call is a new trace and compile each time (pass arrays). The traces are
    kept in JAX's caches, and with them their static arguments
    (a design problem and its model, a mesh): ``jax.clear_caches()`` frees them. A
    global that the function reads is read once, when it is traced.

    Two things that a trace depends on are part of the key: the error mode, which
    :func:`checked` reads when traced (the design solver traces with errors as NaN, a
    plain call with errors raised), and the abstract mesh. JAX's derivatives of
    loops run code under an empty abstract mesh and the rest under none: the same mesh,
    but different keys of the jit's trace cache, so each call names the mesh it is under.
    """
    jitted = eqx.filter_jit(lambda error_mode, args, kwargs: fn(*args, **kwargs))

    @functools.wraps(fn)
    def call(*args, **kwargs):
        error_mode = _errors["as_nan"]
        with jax.sharding.use_abstract_mesh(jax.sharding.get_abstract_mesh()):
            return jitted(error_mode, args, kwargs)

    return call


# XLA's older CPU code generator: it compiles the design solver in about half the time of
# the fusion emitters (per-kernel MLIR pipelines), and the compiled solve runs faster too.
# A dome's own calls gain little from it and keep XLA's defaults.
# XLA's loop-invariant code motion is off: it runs on every while loop at each round of
# XLA's simplification passes, and the solver's loops hold little invariant work that it
# could hoist (the one-trip loops of where_needed keep theirs on purpose), so it costs a
# quarter to a third of the compile time and saves nothing at run time.
_COMPILER_OPTIONS = {"xla_cpu_use_fusion_emitters": False, "xla_disable_hlo_passes": "while-loop-invariant-code-motion"}


@functools.cache
def compiler_options():
    """The XLA options that the design solver's programs compile with: those of
    _COMPILER_OPTIONS that this jaxlib knows, each probed alone (a jaxlib may know the pass
    list but not the fusion-emitter switch). Asked lazily, when a program is first
    compiled: the probe starts JAX's backend, which must wait for the user's device settings."""
    known = {}
    for name, value in _COMPILER_OPTIONS.items():
        try:
            jax.jit(lambda x: x + 1.0, compiler_options={name: value}).lower(1.0).compile()
        except Exception as error:
            if "No such compile option" not in str(error):  # another jaxlib's answer
                raise
            continue
        known[name] = value
    return known


# The library's own caches of programs (the design solver's), emptied with JAX's caches by
# free_programs_near_mapping_limit: each is the clear function of one.
_PROGRAM_CACHES = []


def program_cache(cache):
    """``cache`` (a dict, or a function cached by ``functools``) registered as a cache of
    compiled or jitted programs, which :func:`free_programs_near_mapping_limit` empties
    with JAX's caches; returned, so that it may decorate the function."""
    _PROGRAM_CACHES.append(getattr(cache, "cache_clear", None) or cache.clear)
    return cache


def mapped_regions():
    """(regions, limit): how many memory mappings this process holds and the most that
    Linux allows one process (vm.max_map_count); None where /proc cannot tell."""
    try:
        with open("/proc/sys/vm/max_map_count") as limit, open("/proc/self/maps", "rb") as maps:
            return maps.read().count(b"\n"), int(limit.read())
    except (OSError, ValueError):
        return None


def free_programs_near_mapping_limit() -> bool:
    """Empty JAX's caches and the library's caches of programs (:func:`program_cache`) when
    this process holds more than half the memory mappings that Linux allows it; whether it
    did. Called before a new program is compiled. XLA:CPU's fusion emitters (jaxlib 0.12's
    only code generator) load each kernel as an object of its own, about three mappings
    apiece, and a design solve's program holds about 1,300: a few dozen kept programs pass
    Linux's default limit (65,530), where the next one fails to load ("Failed to
    materialize symbols"). Emptying the library's caches with JAX's makes every later
    program compile through a call of this function. Reading the count takes milliseconds
    (a compile takes seconds); where /proc cannot tell (not Linux), nothing is done."""
    regions = mapped_regions()
    if regions is None or regions[0] <= regions[1] // 2:
        return False
    for clear in _PROGRAM_CACHES:
        clear()
    jax.clear_caches()
    return True


def on_device(value):
    """``value`` (a Python number, nested lists of numbers, a numpy or jax array) as a
    strongly typed jax array (float64 for a float) on the default device, made without a
    program: ``jnp.asarray`` of a Python number runs a small conversion program (to a weak
    type) that each new process compiles again, and the first such compile sets up XLA's
    pipeline, about a tenth of a second of a command's second run. A jax array (a tracer
    too) is returned as it is."""
    if isinstance(value, jax.Array):
        return value
    return jax.device_put(np.asarray(value))


def random_key(seed: int):
    """``jax.random.key(seed)`` made without a program (see :func:`on_device`): under JAX's
    default generator, threefry2x32, a key's data is the seed's high and low 32 bits, as
    ``jax.random.key`` makes it; a negative seed, one of 2**63 or more, or another default
    generator is made by ``jax.random.key``."""
    if jax.config.jax_default_prng_impl != "threefry2x32" or not 0 <= seed < 2**63:
        return jax.random.key(seed)
    return jax.random.wrap_key_data(np.array([seed >> 32, seed & 0xFFFFFFFF], np.uint32))


def strongly_typed(leaf):
    """An inexact array ``leaf`` as a strongly typed jax array of its dtype, as
    ``jnp.asarray(leaf, dtype=leaf.dtype)``, without a program (see :func:`on_device`): a
    weakly typed or numpy leaf is copied through the host, a strongly typed jax array (a
    tracer too) is returned as it is."""
    if isinstance(leaf, jax.Array) and (isinstance(leaf, jax.core.Tracer) or not leaf.weak_type):
        return leaf
    return jax.device_put(np.asarray(leaf, dtype=leaf.dtype))


@contextlib.contextmanager
def gc_paused():
    """Python's cyclic garbage collector off for the block, then as it was. Tracing a
    program makes millions of short-lived objects, and the collections they set off
    walk the whole heap, several per cent of a first call. Nothing that the block frees is lost:
    what it leaves in cycles is collected after it."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def has_loops(fn, *args) -> bool:
    """Whether ``fn(*args)`` runs a while loop (an iterative solve) anywhere in its trace:
    in nested calls, branches, loops and custom derivatives' primal code too (not in a
    custom derivative's rule, which a trace of ``fn`` alone does not run). ``args``:
    arrays or ``jax.ShapeDtypeStruct``; ``fn`` is traced, not run."""

    def loops_in(jaxpr):
        for eqn in jaxpr.eqns:
            if eqn.primitive.name == "while":
                return True
            for value in eqn.params.values():
                for sub in value if isinstance(value, (tuple, list)) else (value,):
                    inner = sub.jaxpr if isinstance(sub, ClosedJaxpr) else sub
                    if isinstance(inner, Jaxpr) and loops_in(inner):
                        return True
        return False

    return loops_in(jax.make_jaxpr(fn)(*args).jaxpr)


@contextlib.contextmanager
def errors_as_nan():
    """While the block traces a program, :func:`checked` makes a failed check NaN instead
    of an error. The design solver's core is traced so: it reports NaN as a status
    ("nonfinite") or as NaN derivatives, so it never raises; and a runtime error is a
    host callback, which keeps a program out of JAX's persistent compilation cache, so
    that the command would compile the solver afresh on every run. The checks of the
    libraries that the core calls are off where it calls them (lineax and optimistix
    with ``throw=False``, the implicit derivatives' own solve)."""
    saved = _errors["as_nan"]
    _errors["as_nan"] = True
    try:
        yield
    finally:
        _errors["as_nan"] = saved


def checked(value, failed, message: str):
    """``value`` where ``failed`` (a boolean array) is false; where it is true, an
    equinox runtime error with ``message``, or, while :func:`errors_as_nan` traces,
    ``value`` made NaN (the whole pytree, as the error would stop it whole)."""
    if not _errors["as_nan"]:
        return eqx.error_if(value, failed, message)
    bad = jnp.any(failed)
    return jax.tree.map(lambda leaf: jnp.where(bad, jnp.nan, leaf), value)
