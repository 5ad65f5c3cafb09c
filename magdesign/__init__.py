"""magdesign: differentiable design of magnetic tactile sensors in JAX.

All quantities are SI (m, T, N, Pa, s, A). Importing the package turns on JAX's
float64 mode (``jax_enable_x64``): every function computes in float64 unless it is
handed float32 arrays explicitly.
"""

import gc
import importlib.metadata

# Python's cyclic collector stays off while JAX and the package load, and what is alive
# then (modules, their functions and classes: objects that live as long as the process) is
# frozen out of later collections: the collections that the imports' 170,000 objects set
# off, each walking the whole heap, cost a tenth of a second of every command's start.
_collecting = gc.isenabled()
gc.disable()

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from magdesign import fields as fields  # noqa: E402
from magdesign import mechanics as mechanics  # noqa: E402
from magdesign import transducers as transducers  # noqa: E402
from magdesign import units as units  # noqa: E402

gc.freeze()
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
