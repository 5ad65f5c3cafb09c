"""magdesign: differentiable design of magnetic tactile sensors in JAX.

All quantities are SI (m, T, N, Pa, s, A). Importing the package turns on JAX's
float64 mode (``jax_enable_x64``): every function computes in float64 unless it is
handed float32 arrays explicitly.

Importing the package also freezes Python's garbage collector's view of every object alive
then (``gc.freeze``: JAX's and the package's modules, and whatever the process made
before): those objects are left out of later cyclic collections, which a command's start
would otherwise spend a tenth of a second on. Call ``gc.unfreeze()`` after the import where a
program made, before it, objects in reference cycles that it will drop and needs collected.
"""

import gc
import importlib.metadata

# Python's cyclic collector stays off while JAX and the package load, and what is alive
# then (modules, their functions and classes: objects that live as long as the process) is
# frozen out of later collections: the collections that the imports' 170,000 objects set
# off, each walking the whole heap, cost a tenth of a second of every command's start.
_collecting = gc.isenabled()
gc.disable()
try:
    import jax

    jax.config.update("jax_enable_x64", True)

    from magdesign import fields as fields
    from magdesign import mechanics as mechanics
    from magdesign import transducers as transducers
    from magdesign import units as units

    gc.freeze()
finally:  # the collector as it was, the import failed or not
    if _collecting:
        gc.enable()

__version__ = importlib.metadata.version("magdesign")  # from the installed distribution's metadata

# The heavier subpackages load on first use (``magdesign.scene.to_magpylib`` works after a
# plain ``import magdesign``), so that importing the package stays as quick as its kernels.
_LAZY_SUBPACKAGES = ("accuracy", "design", "inverse", "scene", "spec")


def __getattr__(name):
    if name in _LAZY_SUBPACKAGES:
        return importlib.import_module(f"magdesign.{name}")
    raise AttributeError(f"module 'magdesign' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY_SUBPACKAGES))
