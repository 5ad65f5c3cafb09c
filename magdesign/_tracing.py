"""Tracing costly code once per program."""

import functools

import equinox as eqx
import equinox._errors as _equinox_errors
import jax


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
