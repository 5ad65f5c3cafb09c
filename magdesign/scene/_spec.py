"""Reading one TOML table of a spec: quantities with units, choices, strict keys.

Every error is a :class:`~magdesign.units.SpecError` with a one-line message that
names the dotted key and what was expected.
"""

import re
import warnings

from magdesign.units import SpecError, echo, parse

_MISSING = object()

# The physical domain of each scene number, by dotted spec key: (lowest, lowest allowed?,
# highest, highest allowed?); None: no bound that side. Checked where the number is read
# (and on a design variable's bounds), so that the traced chain carries no checks.
_POSITIVE = (0.0, False, None, False)
_NONNEGATIVE = (0.0, True, None, False)
DOMAINS = {
    **dict.fromkeys(
        ["magnet.radius", "magnet.height", "magnet.remanence", "magnet.period", "magnet.thickness",
         "magnet.magnetization", "mechanics.outer_radius", "mechanics.thickness", "mechanics.contact_area",
         "mechanics.c10", "mechanics.youngs_modulus", "mechanics.shear_modulus", "mechanics.bulk_modulus",
         "mechanics.spring", "geometry.gap", "pole.ball_radius", "pole.diameter", "pole.length", "inductors.area",
         "inductors.turns", "sensor.amplification", "inductors.amplification", "scene.area",
         "scene.lag_time_constant", "scene.saturation_limit", "scene.lsb", "soft.size", "soft.permeability",
         "soft.saturation", "pole.permeability", "pole.saturation"],
        _POSITIVE,
    ),
    **dict.fromkeys(["mechanics.c01", "sensor.pitch", "scene.noise", "sensor.height", "inductors.noise"], _NONNEGATIVE),
    "mechanics.poisson_ratio": (-1.0, False, 0.5, False),
    "pole.demagnetizing_factor": (0.0, False, 1.0, True),
}
# The SI unit of each scene parameter a design can set free (a variable's bounds are read in it).
PARAMETER_UNITS = {
    **dict.fromkeys(["geometry.gap", "magnet.radius", "magnet.height", "magnet.period", "magnet.thickness",
                     "mechanics.outer_radius", "mechanics.thickness", "sensor.pitch", "pole.ball_radius",
                     "pole.diameter", "pole.length", "sensor.offset", "sensor.height"], "m"),
    **dict.fromkeys(["magnet.remanence", "magnet.magnetization"], "T"),
    **dict.fromkeys(["mechanics.c10", "mechanics.c01", "mechanics.youngs_modulus", "mechanics.shear_modulus",
                     "mechanics.bulk_modulus"], "Pa"),
    "mechanics.contact_area": "m^2",
    "mechanics.spring": "N/rad",
    "pole.saturation": "T",
    "soft.size": "m",
    "soft.position": "m",
    "soft.saturation": "T",
}
# A [[soft]] part's numbers, "soft[i].key" or "soft[i].key[k]", are read as "soft.key".
_SOFT_NUMBER = re.compile(r"^soft\[\d+\]\.(\w+)(\[\d\])?$")

# Values far outside real parts: allowed, with a warning. (key: (highest plausible, unit, why))
PLAUSIBLE = {
    "magnet.remanence": (1.6, "T", "the strongest permanent magnets (NdFeB) reach about 1.5 T"),
    "magnet.magnetization": (1.6, "T", "the strongest permanent magnets (NdFeB) reach about 1.5 T"),
}


def parameter_unit(name: str) -> str:
    """The SI unit of scene parameter ``name`` (:data:`PARAMETER_UNITS`); "1" if dimensionless."""
    return PARAMETER_UNITS.get(_SOFT_NUMBER.sub(r"soft.\1", name), "1")


class PlausibilityWarning(UserWarning):
    """A spec value that is allowed but far outside real parts."""


def check_domain(name: str, value: float, *, key: str | None = None, unit: str = "") -> None:
    """SpecError naming ``key`` (default ``name``) unless ``value`` lies in the physical
    domain of the scene number ``name`` (:data:`DOMAINS`); a PlausibilityWarning when it
    is far outside real parts (:data:`PLAUSIBLE`)."""
    key = key or name
    name = re.sub(r"\.extra\[\d+\]", "", name)  # a further magnet's numbers are a magnet's
    name = _SOFT_NUMBER.sub(r"soft.\1", name)
    if name in DOMAINS:
        low, low_ok, high, high_ok = DOMAINS[name]
        below = low is not None and (value < low or (value == low and not low_ok))
        above = high is not None and (value > high or (value == high and not high_ok))
        if below or above:
            left = "(-inf" if low is None else ("[" if low_ok else "(") + f"{low:g}"
            right = "inf)" if high is None else f"{high:g}" + ("]" if high_ok else ")")
            raise SpecError(f"{key}: {value:g} {unit or '(SI)'} is not physical; expected a value in {left}, {right}")
    if name in PLAUSIBLE:
        highest, plausible_unit, why = PLAUSIBLE[name]
        if abs(value) > highest:
            warnings.warn(f"{key}: {value:g} {plausible_unit} is far outside real parts ({why})",
                          PlausibilityWarning, stacklevel=2)


class Table:
    """One table of a spec (``spec["magnet"]``), read key by key.

    Each read marks its key as used; :meth:`done` then rejects any key left over,
    listing the keys the table accepts.
    """

    def __init__(self, spec, name, *, required=True):
        self.name = name
        self._values = sub_table(spec, name, required=required)
        self._known = []

    def _get(self, key, default):
        self._known.append(key)
        value = self._values.get(key, default)
        if value is _MISSING:
            raise SpecError(f"{self.name}.{key}: missing key")
        return value

    def has(self, key):
        return key in self._values

    def quantity(self, key, unit, default=_MISSING):
        """An SI float; ``default`` (already SI) when the key is absent."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        value = parse(value, unit, key=f"{self.name}.{key}")
        check_domain(f"{self.name}.{key}", value, unit=unit)
        return value

    def quantities(self, key, unit, length=None, default=_MISSING):
        """A list of SI floats (e.g. a position ["1 mm", "0 mm", "2 mm"])."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if not isinstance(value, list) or (length is not None and len(value) != length):
            count = f"{length} " if length is not None else ""
            raise SpecError(f"{self.name}.{key}: expected a list of {count}quantities in {unit}, got {echo(value)}")
        values = [parse(item, unit, key=f"{self.name}.{key}") for item in value]
        for item in values:
            check_domain(f"{self.name}.{key}", item, unit=unit)
        return values

    def choice(self, key, options, default=_MISSING):
        """One of ``options`` (strings)."""
        value = self._get(key, default)
        if value not in options:
            raise SpecError(f"{self.name}.{key}: expected one of {', '.join(map(repr, options))}, got {echo(value)}")
        return value

    def integer(self, key, default=_MISSING, minimum=1):
        """An integer >= ``minimum``; ``default`` when the key is absent."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise SpecError(f"{self.name}.{key}: expected an integer >= {minimum}, got {echo(value)}")
        return value

    def strings(self, key, default=_MISSING):
        value = self._get(key, default)
        if not isinstance(value, list) or not all(isinstance(item, str) for item in value):
            raise SpecError(f"{self.name}.{key}: expected a list of names, got {echo(value)}")
        return value

    def done(self):
        """Reject keys that were never read."""
        check_keys(self.name, self._values, sorted(set(self._known)))


def sub_table(parent: dict, key: str, *, where: str | None = None, required: bool = True) -> dict:
    """The table ``parent[key]`` ({} when absent and not ``required``); SpecError naming
    ``where`` (default ``key``) when it is missing or not a table."""
    where = where or key
    value = parent.get(key, _MISSING)
    if value is _MISSING:
        if required:
            raise SpecError(f"[{where}]: missing table; expected a [{where}] table in the spec")
        return {}
    if not isinstance(value, dict):
        raise SpecError(f"{where}: expected a table, got {echo(value)}")
    return value


def check_keys(where: str, entry, allowed) -> None:
    """SpecError unless ``entry`` is a table whose keys are all in ``allowed``, naming the
    first unknown key (``where.key``) and the keys allowed."""
    if not isinstance(entry, dict):
        raise SpecError(f"{where}: expected a table with keys {', '.join(allowed)}, got {echo(entry)}")
    unknown = sorted(set(entry) - set(allowed))
    if unknown:
        raise SpecError(f"{where}.{unknown[0]}: unknown key; expected one of: {', '.join(allowed)}")


def check_tables(spec, allowed):
    """Reject top-level tables other than ``allowed`` (and the lead's [design])."""
    for name in spec:
        if name not in allowed and name != "design":
            raise SpecError(f"[{name}]: unknown table; expected one of: {', '.join(allowed)}, design")
