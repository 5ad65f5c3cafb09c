"""Looking spec keys up in the one table of keys (:mod:`magdesign.spec.keys`), and checking
the values read against it.

The readers look every key up here (:func:`lookup`): a key read in code and missing from the
table, or read as another type, unit or default than the table gives, raises
:class:`UnlistedKeyError` (a programming error, never a bad spec). A number read for a key
is checked against its physical domain (:func:`check_domain`: a SpecError outside it) and
its plausible range (a :class:`PlausibilityWarning` for a plain number outside it).
"""

import contextlib
import math
import re
import warnings

from magdesign.spec.key import OUTPUT_PLAUSIBLE, REQUIRED, WRITTEN_UNITS, Depends, Key
from magdesign.spec.keys import KEYS
from magdesign.units import SpecError, unit_factor


class UnlistedKeyError(LookupError):
    """Code reads a spec key that the key table does not list, or reads it otherwise than
    the table says (type, unit, default, choices): a programming error, not a bad spec."""


class PlausibilityWarning(UserWarning):
    """A spec value that is allowed but far outside real parts, or a plain number (SI) far
    outside its key's plausible range."""


_INDEX = re.compile(r"\[\d+\]")
# Kinds read by one reader: a [[soft]] part's size is one quantity for a sphere, a list else.
_FAMILY = {"quantities": "quantity", "quantity or table": "quantity"}


def spec_name(name: str) -> str:
    """The table's name of a key as code names it: "soft[0].size[1]" -> "soft.size",
    "magnet.extra[2].radius" -> "magnet.extra.radius"."""
    return _INDEX.sub("", name)


# The sets :func:`recording` collects looked-up keys into, while it runs.
_RECORDS: list[set[str]] = []


@contextlib.contextmanager
def recording():
    """Collect the names of the keys the readers look up inside the block (a set): the
    tests' check that every key of the table is read by some reader."""
    names: set[str] = set()
    _RECORDS.append(names)
    try:
        yield names
    finally:
        _RECORDS.remove(names)


def listed(name: str) -> Key:
    """The :class:`Key` of ``name`` (see :func:`spec_name`); UnlistedKeyError if the table
    does not list it."""
    key = KEYS.get(spec_name(name))
    if key is None:
        raise UnlistedKeyError(f"{name}: read as a spec key, but magdesign.spec.keys does not list it")
    return key


def lookup(name: str, kind: str | None = None) -> Key:
    """The :class:`Key` of ``name`` that a reader reads (:func:`listed`, and noted by any
    :func:`recording`); UnlistedKeyError if the table lists it with another kind than ``kind``."""
    key = listed(name)
    for names in _RECORDS:
        names.add(key.name)
    if kind is not None and _FAMILY.get(key.kind, key.kind) != _FAMILY.get(kind, kind):
        raise UnlistedKeyError(f"{name}: read as {kind}, but magdesign.spec.keys lists it as {key.kind}")
    return key


def fields(table: str) -> tuple[str, ...]:
    """The keys of spec table ``table`` ("design.variables.*" -> ("lower", "upper", ...))."""
    names = tuple(key.field for key in KEYS.values() if key.table == table)
    if not names:
        raise UnlistedKeyError(f"{table}: read as a spec table, but magdesign.spec.keys lists no key in it")
    return names


def check_read(key: Key, *, unit: str | None = None, default=REQUIRED, options=None) -> None:
    """UnlistedKeyError unless a reader reads ``key`` as the table says: in ``unit`` (one of
    the key's units), with ``default`` (:data:`REQUIRED` where it passes none) equal to the
    table's, and offering ``options`` that the table lists among its choices."""
    if unit is not None and unit not in key.unit.split(" or "):
        raise UnlistedKeyError(f"{key.name}: read in {unit}, but magdesign.spec.keys gives its unit as {key.unit}")
    if not isinstance(key.default, Depends) and not _same(default, key.default):
        raise UnlistedKeyError(
            f"{key.name}: read with the default {default!r}, but magdesign.spec.keys gives {key.default!r}"
        )
    if options is not None and not set(options) <= set(key.choices):
        extra = sorted(set(options) - set(key.choices))
        raise UnlistedKeyError(f"{key.name}: offers {extra}, which magdesign.spec.keys does not list")


def _same(a, b) -> bool:
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) or isinstance(b, float):
        return isinstance(a, (int, float)) and isinstance(b, (int, float)) and math.isclose(a, b, rel_tol=1e-12)
    return a is b or (type(a) is type(b) and a == b)


def domain_text(domain: tuple) -> str:
    """A domain (see :data:`magdesign.spec.key.POSITIVE`) as an interval: "(0, inf)", "[0, inf)", "(-1, 0.5)"."""
    low, low_ok, high, high_ok = domain
    left = "(-inf" if low is None else ("[" if low_ok else "(") + f"{low:g}"
    right = "inf)" if high is None else f"{high:g}" + ("]" if high_ok else ")")
    return f"{left}, {right}"


def check_domain(name: str, value: float, *, key: str | None = None, unit: str = "", written=None) -> None:
    """Check one number read for scene key ``name`` (SI ``value``, read in ``unit``).

    Raises a SpecError naming ``key`` (default ``name``) unless ``value`` lies in the key's
    physical domain. Warns (:class:`PlausibilityWarning`) where ``written``, the value as
    the spec wrote it, is a plain number outside the key's plausible range (it is read in
    SI: the warning says so and which unit was likely meant), or where the value is far
    outside real parts.
    """
    key = key or name
    entry = listed(name)
    if entry.domain is not None:
        low, low_ok, high, high_ok = entry.domain
        below = low is not None and (value < low or (value == low and not low_ok))
        above = high is not None and (value > high or (value == high and not high_ok))
        if below or above:
            raise SpecError(
                f"{key}: {value:g}{_unit_text(unit)} is not physical; expected a value in {domain_text(entry.domain)}"
            )
    if _plain(written) and unit not in ("", "1"):
        message = _plain_advice(entry.plausible_range(unit), key, written, unit)
        if message:
            warnings.warn(message, PlausibilityWarning, stacklevel=3)
            return
    if entry.real_parts is not None and abs(value) > entry.real_parts[0]:
        warnings.warn(
            f"{key}: {value:g} {entry.unit} is far outside real parts ({entry.real_parts[1]})",
            PlausibilityWarning,
            stacklevel=3,
        )


def _unit_text(unit: str) -> str:
    """A value's unit after it in a message: none for a ratio ("1"), "(SI)" where unknown."""
    return "" if unit == "1" else f" {unit or '(SI)'}"


def _plain(written) -> bool:
    return isinstance(written, (int, float)) and not isinstance(written, bool)


def check_output_number(key: str, written, unit: str) -> None:
    """Warn (:class:`PlausibilityWarning`) where ``written``, a target's value or a limit's
    bound as the spec wrote it for an output in SI ``unit``, is a plain number outside that
    unit's plausible range (:data:`OUTPUT_PLAUSIBLE`): it is read in SI."""
    if _plain(written) and unit not in ("", "1"):
        message = _plain_advice(OUTPUT_PLAUSIBLE.get(unit), key, written, unit)
        if message:
            warnings.warn(message, PlausibilityWarning, stacklevel=3)


def _plain_advice(plausible, key, written, unit):
    """The warning for a plain number ``written`` (SI, read in ``unit``) outside the
    ``plausible`` range (low, high), or None when it lies inside (or no range is known)."""
    if plausible is None:
        return None
    low, high = plausible
    size = abs(float(written))
    if size <= high and (size == 0.0 or size >= low):
        return None
    number = f"{written:g}"
    for written_unit, words in WRITTEN_UNITS.get(unit, ()):
        si = size * unit_factor(written_unit) / unit_factor(unit)
        if low <= si <= high:
            return f'{key} = {number} was read as {number} {unit}; write "{number} {written_unit}" for {words}'
    return (
        f"{key} = {number} was read as {number} {unit}, outside the plausible {low:g} to {high:g} {unit}; "
        "a plain number is SI"
    )
