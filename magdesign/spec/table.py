"""Reading one TOML table of a spec: quantities with units, choices, strict keys.

Every key read is looked up in the one table of spec keys (:mod:`magdesign.spec.keys`),
which gives its unit, default, physical domain and plausible range: a key that table does
not list raises :class:`~magdesign.spec.checks.UnlistedKeyError` (a programming error). Every
error in a spec is a :class:`~magdesign.units.SpecError` with a one-line message that names
the dotted key and what was expected.
"""

from magdesign.spec.checks import check_domain, check_read, listed, lookup
from magdesign.spec.key import REQUIRED
from magdesign.units import SpecError, echo, parse

_MISSING = REQUIRED


def parameter_unit(name: str) -> str:
    """The SI unit of scene parameter ``name`` ("geometry.gap" -> "m", "soft[0].position[2]"
    -> "m"; "1" if dimensionless), from the key table."""
    return listed(name).unit


class Table:
    """One table of a spec (``spec["magnet"]``), read key by key.

    Each read marks its key as used; :meth:`done` then rejects any key left over,
    listing the keys the table accepts.
    """

    def __init__(self, spec, name, *, required=True):
        self.name = name
        self._values = sub_table(spec, name, required=required)
        self._known = []

    def _get(self, key, default, kind=None, unit=None, options=None):
        """The raw value of ``key`` (``default`` when absent), read as the key table lists it
        (:func:`magdesign.spec.checks.check_read`); SpecError when a required key is absent."""
        check_read(lookup(f"{self.name}.{key}", kind), unit=unit, default=default, options=options)
        self._known.append(key)
        value = self._values.get(key, default)
        if value is _MISSING:
            raise SpecError(f"{self.name}.{key}: missing key")
        return value

    def has(self, key):
        listed(f"{self.name}.{key}")
        return key in self._values

    def quantity(self, key, unit, default=_MISSING):
        """An SI float; ``default`` (already SI) when the key is absent."""
        value = self._get(key, default, "quantity", unit)
        if value is default and default is not _MISSING:
            return default
        si = parse(value, unit, key=f"{self.name}.{key}")
        check_domain(f"{self.name}.{key}", si, unit=unit, written=value)
        return si

    def quantities(self, key, unit, length=None, default=_MISSING):
        """A list of SI floats (e.g. a position ["1 mm", "0 mm", "2 mm"])."""
        value = self._get(key, default, "quantities", unit)
        if value is default and default is not _MISSING:
            return default
        if not isinstance(value, list) or (length is not None and len(value) != length):
            count = f"{length} " if length is not None else ""
            raise SpecError(f"{self.name}.{key}: expected a list of {count}quantities in {unit}, got {echo(value)}")
        return [self._number(key, item, unit) for item in value]

    def points(self, key, unit="m", default=_MISSING, *, plane=False):
        """A list of [x, y, z] quantities (``plane``: [x, y]) as lists of SI floats (sensor positions)."""
        value = self._get(key, default, "plane points" if plane else "points", unit)
        if value is default and default is not _MISSING:
            return default
        axes = ("x", "y") if plane else ("x", "y", "z")
        if not isinstance(value, list) or not all(isinstance(row, list) and len(row) == len(axes) for row in value):
            raise SpecError(
                f"{self.name}.{key}: expected a list of [{', '.join(axes)}] quantities in {unit}, got {echo(value)}"
            )
        return [[self._number(key, item, unit) for item in row] for row in value]

    def _number(self, key, item, unit):
        si = parse(item, unit, key=f"{self.name}.{key}")
        check_domain(f"{self.name}.{key}", si, unit=unit, written=item)
        return si

    def choice(self, key, options, default=_MISSING):
        """One of ``options`` (strings)."""
        value = self._get(key, default, "choice", options=options)
        if value not in options:
            raise SpecError(f"{self.name}.{key}: expected one of {', '.join(map(repr, options))}, got {echo(value)}")
        return value

    def integer(self, key, default=_MISSING, minimum=1):
        """An integer >= ``minimum``; ``default`` when the key is absent."""
        value = self._get(key, default, "integer")
        if value is default and default is not _MISSING:
            return default
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise SpecError(f"{self.name}.{key}: expected an integer >= {minimum}, got {echo(value)}")
        return value

    def flag(self, key, default=_MISSING):
        """True or false; ``default`` when the key is absent."""
        value = self._get(key, default, "bool")
        if not isinstance(value, bool):
            raise SpecError(f"{self.name}.{key}: expected true or false, got {echo(value)}")
        return value

    def strings(self, key, default=_MISSING):
        """A list of names."""
        value = self._get(key, default, "names")
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
