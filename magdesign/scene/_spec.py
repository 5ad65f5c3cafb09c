"""Reading one TOML table of a spec: quantities with units, choices, strict keys.

Every error is a :class:`~magdesign.units.SpecError` with a one-line message that
names the dotted key and what was expected.
"""

from magdesign.units import SpecError, parse

_MISSING = object()


class Table:
    """One table of a spec (``spec["magnet"]``), read key by key.

    Each read marks its key as used; :meth:`done` then rejects any key left over,
    listing the keys the table accepts.
    """

    def __init__(self, spec, name, *, required=True):
        value = spec.get(name, _MISSING)
        if value is _MISSING:
            if required:
                raise SpecError(f"[{name}]: missing table; expected a [{name}] table in the spec")
            value = {}
        if not isinstance(value, dict):
            raise SpecError(f"{name}: expected a table, got {value!r}")
        self.name = name
        self._values = value
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
        return parse(value, unit, key=f"{self.name}.{key}")

    def quantities(self, key, unit, length=None, default=_MISSING):
        """A list of SI floats (e.g. a position ["1 mm", "0 mm", "2 mm"])."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if not isinstance(value, list) or (length is not None and len(value) != length):
            count = f"{length} " if length is not None else ""
            raise SpecError(f"{self.name}.{key}: expected a list of {count}quantities in {unit}, got {value!r}")
        return [parse(item, unit, key=f"{self.name}.{key}") for item in value]

    def choice(self, key, options, default=_MISSING):
        """One of ``options`` (strings)."""
        value = self._get(key, default)
        if value not in options:
            raise SpecError(f"{self.name}.{key}: expected one of {', '.join(map(repr, options))}, got {value!r}")
        return value

    def integer(self, key, default=_MISSING, minimum=1):
        """An integer >= ``minimum``; ``default`` when the key is absent."""
        value = self._get(key, default)
        if value is default and default is not _MISSING:
            return default
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise SpecError(f"{self.name}.{key}: expected an integer >= {minimum}, got {value!r}")
        return value

    def strings(self, key, default=_MISSING):
        value = self._get(key, default)
        if not isinstance(value, list) or not all(isinstance(item, str) for item in value):
            raise SpecError(f"{self.name}.{key}: expected a list of names, got {value!r}")
        return value

    def done(self):
        """Reject keys that were never read."""
        unknown = sorted(set(self._values) - set(self._known))
        if unknown:
            valid = ", ".join(sorted(set(self._known)))
            raise SpecError(f"{self.name}.{unknown[0]}: unknown key; expected one of: {valid}")


def check_tables(spec, allowed):
    """Reject top-level tables other than ``allowed`` (and the lead's [design])."""
    for name in spec:
        if name not in allowed and name != "design":
            raise SpecError(f"[{name}]: unknown table; expected one of: {', '.join(allowed)}, design")
