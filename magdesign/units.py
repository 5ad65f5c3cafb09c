"""SI constants and the parser for quantities written with units ("6.4 mm", "0.32 mm/N").

Everything inside magdesign is SI (m, kg, s, A, K; derived T, N, Pa, V, Ohm).
Spec files may give a quantity as a string with its unit, or as a plain number that is
then taken to be SI already. :func:`parse` checks the dimension against what the key
expects and raises :class:`SpecError` naming the key otherwise.
"""

import math
import re

MU0 = 1.25663706212e-6  # vacuum permeability (T m / A), CODATA 2018

# Multipliers for writing SI values in code: 6.4 * mm is 6.4e-3 (m).
mm = 1e-3
um = 1e-6
cm = 1e-2
mT = 1e-3
uT = 1e-6
kPa = 1e3
MPa = 1e6
deg = math.pi / 180.0


class SpecError(ValueError):
    """A spec value is missing, malformed or of the wrong unit; the message names the key."""


# Dimension exponents over the SI base units (m, kg, s, A, K).
_DIMENSIONLESS = (0, 0, 0, 0, 0)
_BASE = {
    "m": (1.0, (1, 0, 0, 0, 0)),
    "g": (1e-3, (0, 1, 0, 0, 0)),
    "s": (1.0, (0, 0, 1, 0, 0)),
    "A": (1.0, (0, 0, 0, 1, 0)),
    "K": (1.0, (0, 0, 0, 0, 1)),
    "N": (1.0, (1, 1, -2, 0, 0)),
    "Pa": (1.0, (-1, 1, -2, 0, 0)),
    "J": (1.0, (2, 1, -2, 0, 0)),
    "W": (1.0, (2, 1, -3, 0, 0)),
    "T": (1.0, (0, 1, -2, -1, 0)),
    "Wb": (1.0, (2, 1, -2, -1, 0)),
    "V": (1.0, (2, 1, -3, -1, 0)),
    "Ohm": (1.0, (2, 1, -3, -2, 0)),
    "Hz": (1.0, (0, 0, -1, 0, 0)),
    "rad": (1.0, _DIMENSIONLESS),
}
_NO_PREFIX = {
    "deg": (math.pi / 180.0, _DIMENSIONLESS),
    "%": (1e-2, _DIMENSIONLESS),
    "ppm": (1e-6, _DIMENSIONLESS),
    "G": (1e-4, (0, 1, -2, -1, 0)),  # gauss
    "min": (60.0, (0, 0, 1, 0, 0)),
    "1": (1.0, _DIMENSIONLESS),
}
_PREFIX = {"p": 1e-12, "n": 1e-9, "u": 1e-6, "µ": 1e-6, "m": 1e-3, "c": 1e-2, "k": 1e3, "M": 1e6, "G": 1e9}
_ALIASES = {"Ω": "Ohm", "ohm": "Ohm", "°": "deg"}

# Units deeper or higher than these are typing errors, and would exhaust the recursion or
# overflow the factor.
_MAX_UNIT_NESTING = 20
_MAX_UNIT_POWER = 12
# Largest magnitude of a quantity in SI units: anything above is a typing error, and
# would overflow the products of the model (1e200 squared is already inf).
_LARGEST = 1e200
# Longest echo of a spec value in an error message (characters).
_ECHO = 80


def echo(value) -> str:
    """repr(value), cut to about _ECHO characters for an error message."""
    try:
        text = repr(value)
    except ValueError:  # an integer too long for Python to print
        text = f"<an integer of about {int(value.bit_length() * math.log10(2))} digits>"
    return text if len(text) <= _ECHO else f"{text[: _ECHO - 20]}...({len(text)} characters)"


_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")
_TOKEN = re.compile(r"\s*(\(|\)|/|\*|\^|-?\d+|[A-Za-zµΩ°%]+)")


def _unit_atom(name):
    name = _ALIASES.get(name, name)
    if name in _NO_PREFIX:
        return _NO_PREFIX[name]
    if name in _BASE:
        return _BASE[name]
    if len(name) > 1 and name[0] in _PREFIX and name[1:] in _BASE:
        scale, dim = _BASE[name[1:]]
        return _PREFIX[name[0]] * scale, dim
    raise ValueError(f"unknown unit {name!r}")


def _combine(a, b, power):
    return a[0] * b[0] ** power, tuple(x + power * y for x, y in zip(a[1], b[1]))


def _parse_unit(text):
    """Parse a unit expression ("mm/N", "kg*m/s^2", "mV/(A/m)") to (factor, dimension)."""
    tokens = _TOKEN.findall(text)
    if "".join(tokens) != re.sub(r"\s+", "", text):
        raise ValueError(f"cannot read unit {echo(text)}")
    position = 0

    def peek():
        return tokens[position] if position < len(tokens) else None

    def take():
        nonlocal position
        position += 1
        return tokens[position - 1] if position <= len(tokens) else None

    def atom(depth):
        token = take()
        if token == "(":
            if depth >= _MAX_UNIT_NESTING:
                raise ValueError(f"parentheses nested deeper than {_MAX_UNIT_NESTING} in unit {echo(text)}")
            value = expression(depth + 1)
            if take() != ")":
                raise ValueError(f"unbalanced parentheses in unit {echo(text)}")
        elif token is None or token in ")/*^":
            raise ValueError(f"cannot read unit {echo(text)}")
        else:
            value = _unit_atom(token)
        if peek() == "^":
            take()
            power = take()
            if power is None or not re.fullmatch(r"-?\d+", power) or abs(int(power)) > _MAX_UNIT_POWER:
                raise ValueError(
                    f"cannot read unit {echo(text)}: a power is an integer from -{_MAX_UNIT_POWER} to {_MAX_UNIT_POWER}"
                )
            value = _combine((1.0, _DIMENSIONLESS), value, int(power))
        return value

    def expression(depth):
        value = atom(depth)
        while peek() not in (None, ")"):
            power = -1 if peek() == "/" else 1
            if peek() in ("/", "*"):
                take()
            value = _combine(value, atom(depth), power)
        return value

    result = expression(0)
    if position != len(tokens) or not math.isfinite(result[0]) or result[0] == 0.0:
        raise ValueError(f"cannot read unit {echo(text)}")
    return result


def unit_factor(unit):
    """SI value of one ``unit`` (e.g. ``unit_factor("mm/N") == 1e-3``)."""
    return _parse_unit(unit)[0]


def parse(value, unit, *, key):
    """Read a quantity from a spec and return its SI value (float).

    Args:
        value: a string "number unit" ("6.4 mm", "0.32 mm/N") or a plain number,
            which is taken to be in SI units already.
        unit: the unit the key expects, used for the dimension check and the
            message ("m", "m/N", "T", "Pa", "1" for a pure number).
        key: the spec key, named in the error message.

    Raises:
        SpecError: the value is not a number, has no unit where one is needed,
            its unit is of another dimension than ``unit`` or cannot be read, or it is
            not finite or above 1e200 in SI units.
    """
    _, expected_dim = _parse_unit(unit)
    example = f'e.g. "1 {unit}"' if unit != "1" else "a plain number"
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise SpecError(f"{key}: expected a quantity in {unit} ({example}), got {echo(value)}")
    if isinstance(value, str):
        match = _NUMBER.match(value)
        if match is None:
            raise SpecError(f"{key}: expected a quantity in {unit} ({example}), got {echo(value)}")
        number, unit_text = float(match.group(1)), match.group(2)
        if unit_text:
            try:
                factor, dim = _parse_unit(unit_text)
            except ValueError as error:
                raise SpecError(f"{key}: {error} in {echo(value)}; expected a quantity in {unit}") from None
            if dim != expected_dim:
                raise SpecError(f"{key}: wrong unit {echo(unit_text)} in {echo(value)}; expected a quantity in {unit}")
        elif expected_dim == _DIMENSIONLESS:
            factor = 1.0
        else:
            raise SpecError(f"{key}: missing unit in {echo(value)}; expected a quantity in {unit} ({example})")
    else:
        number, factor = value, 1.0
    try:
        si = float(number) * factor
    except OverflowError:
        si = math.inf
    if not math.isfinite(si) or abs(si) > _LARGEST:
        raise SpecError(f"{key}: {echo(value)} is not a finite quantity in {unit} of a usable size (below 1e200 in SI)")
    return si


def written_unit(value):
    """The unit a spec value is written in ("6.4 mm" -> "mm"); None for a plain number."""
    match = _NUMBER.match(value) if isinstance(value, str) else None
    return match.group(2) if match and match.group(2) else None


def convert(value_si, unit):
    """Express an SI value in ``unit`` (``convert(6.4e-3, "mm") == 6.4``)."""
    return value_si / unit_factor(unit)
