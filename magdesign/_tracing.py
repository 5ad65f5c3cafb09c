"""Tracing costly code once per program, and the options its programs compile with."""

import contextlib
import functools
import gc

import equinox as eqx
import equinox._errors as _equinox_errors
import jax
from jax.extend.core import ClosedJaxpr, Jaxpr


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

    Two things that a trace depends on are part of the key: equinox's error mode, which
    equinox's runtime checks read when traced (the design solver traces with errors as
    NaN, a plain call with errors raised), and the abstract mesh. JAX's derivatives of
    loops run code under an empty abstract mesh and the rest under none: the same mesh,
    but different keys of the jit's trace cache, so each call names the mesh it is under.
    """
    jitted = eqx.filter_jit(lambda error_mode, args, kwargs: fn(*args, **kwargs))

    @functools.wraps(fn)
    def call(*args, **kwargs):
        error_mode = getattr(_equinox_errors, "EQX_ON_ERROR", None)
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
    """While the design solver's core is traced and lowered, equinox's runtime errors become
    NaN: the linear solves of optimistix's implicit adjoint (lineax raises on a non-finite
    answer), a soft part's saturation solve. The core reports NaN as a status
    ("nonfinite") or as NaN derivatives, so it never raises; and a runtime error is a
    host callback, which keeps a program out of JAX's persistent compilation cache, so
    that the command would compile the solver afresh on every run. equinox reads its
    error mode (``EQX_ON_ERROR``) from the environment once, on import, and offers no
    public switch for a block of code: this and :func:`traced_once` are the one place
    that sets and reads two private names of equinox (0.13). Where they are missing,
    errors stay errors and the cache misses, which tests/test_cli.py notices."""
    names = ("EQX_ON_ERROR", "branched_error_if_impl_jit")
    if not all(hasattr(_equinox_errors, name) for name in names):
        yield
        return
    saved = [getattr(_equinox_errors, name) for name in names]
    # the unjitted check reads EQX_ON_ERROR when traced; the jitted one would reuse a
    # trace made outside this block
    _equinox_errors.EQX_ON_ERROR = "nan"
    _equinox_errors.branched_error_if_impl_jit = _equinox_errors.branched_error_if_impl
    try:
        yield
    finally:
        for name, value in zip(names, saved):
            setattr(_equinox_errors, name, value)
