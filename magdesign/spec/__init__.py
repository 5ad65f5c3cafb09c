"""The spec language: reading TOML specs into scenes, design problems, sweeps and tolerances.

- :mod:`magdesign.spec.key`: what a key is (type, unit, default, physical domain, plausible
  range);
- :mod:`magdesign.spec.keys`: the one table of spec keys;
- :mod:`magdesign.spec.checks`: looking keys up in it, and checking the values read;
- :mod:`magdesign.spec.table`: reading one TOML table key by key against it;
- :mod:`magdesign.spec.scene`: scenes from a spec's tables (:func:`scene_from_spec`);
- :mod:`magdesign.spec.design`: design specs, read into a :class:`~magdesign.design.Problem`
  (:func:`problem_from_spec`), and solved ones written back (:func:`write_spec`);
- :mod:`magdesign.spec.sweep`: the inputs of a sweep and their values (``--over``, ``--points``);
- :mod:`magdesign.spec.tolerance`: the [design.tolerances] table;
- :mod:`magdesign.spec.chips`: a skin's design over candidate chip grids, the fewest chips
  that succeed (:func:`fewest_chips`);
- :mod:`magdesign.spec.sizes`: the memory a spec's sizes ask for;
- :mod:`magdesign.spec.reference`: the spec reference, rendered from the key table.

Every error in a spec is a :class:`SpecError` (one line naming the key); it is
:class:`magdesign.units.SpecError`, which the unit parser raises.
"""

import importlib

from magdesign.spec.checks import PlausibilityWarning as PlausibilityWarning
from magdesign.spec.checks import UnlistedKeyError as UnlistedKeyError
from magdesign.spec.checks import lookup as lookup
from magdesign.spec.key import Key as Key
from magdesign.spec.keys import KEYS as KEYS
from magdesign.units import SpecError as SpecError

# The readers load on first use: they build on magdesign.scene and magdesign.design, whose
# own modules read keys from this package.
_READERS = {
    "scene_from_spec": "magdesign.spec.scene",
    "default_spec": "magdesign.spec.design",
    "load_spec": "magdesign.spec.design",
    "problem_from_spec": "magdesign.spec.design",
    "write_spec": "magdesign.spec.design",
    "tolerance_problem_from_spec": "magdesign.spec.tolerance",
    "fewest_chips": "magdesign.spec.chips",
}


def __getattr__(name):
    if name in _READERS:
        return getattr(importlib.import_module(_READERS[name]), name)
    raise AttributeError(f"module 'magdesign.spec' has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_READERS))
