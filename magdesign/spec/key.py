"""What a spec key is: :class:`Key`, its kinds, defaults, domains and plausible ranges.

The table of every key is :data:`magdesign.spec.keys.KEYS`; this module holds the vocabulary
that table is written in, and the units a spec usually writes an SI unit in (for the advice
given on a plain number outside its plausible range).
"""

import dataclasses
import math
from collections.abc import Callable, Mapping

# The types a key's value may have (Key.kind).
KINDS = {
    "quantity": 'a number with a unit ("3 mm") or a plain SI number',
    "quantities": "a list of quantities",
    "points": "a list of [x, y, z] quantities",
    "plane points": "a list of [x, y] quantities",
    "choice": "one of the names listed",
    "names": "a list of names",
    "integer": "a whole number",
    "integers": "a list of whole numbers",
    "grids": "a list of [rows, columns] pairs of whole numbers",
    "bool": "true or false",
    "tables": "an array of tables, [[...]]",
    "quantity or table": "a quantity, or a table of the keys below it",
    "output": "the name of an output",
    "unit": 'a unit to show the output in, e.g. "mm"',
    "text": "a string",
}


class Required:
    """The default of a key that a spec must give (where its table applies)."""

    def __repr__(self):
        return "required"


REQUIRED = Required()


@dataclasses.dataclass(frozen=True)
class Depends:
    """The default of a key that depends on the rest of the spec, said in words."""

    text: str


# A physical domain: (lowest, lowest allowed?, highest, highest allowed?); None: no bound there.
POSITIVE = (0.0, False, None, False)
NONNEGATIVE = (0.0, True, None, False)
# Plausible magnitudes of a plain SI number, (low, high): a plain number whose magnitude is
# above high, or nonzero and below low, is most likely written in another unit.
LENGTH = (0.0, 0.5)
AREA = (0.0, 0.25)
FIELD = (0.0, 2.0)
FORCE = (0.0, 1e4)
MODULUS = (1e3, 1e12)
ANGLE = (0.0, 2.0 * math.pi)
TIME = (0.0, 1e4)
VOLTAGE = (0.0, 100.0)
READING = "T or V"  # a reading's unit: T for a Hall chip, V for a spin valve or GMR bridge
READING_PLAUSIBLE = {"T": FIELD, "V": VOLTAGE}
# The units a spec usually writes an SI unit in, with their names, tried in order for the
# advice of a plain number outside its plausible range.
WRITTEN_UNITS = {
    "m": (("mm", "millimetres"), ("um", "micrometres")),
    "m^2": (("mm^2", "square millimetres"),),
    "T": (("mT", "millitesla"), ("uT", "microtesla")),
    "N": (("mN", "millinewtons"),),
    "Pa": (("kPa", "kilopascals"), ("MPa", "megapascals")),
    "s": (("ms", "milliseconds"),),
    "V": (("mV", "millivolts"),),
    "rad": (("deg", "degrees"),),
    "1/K": (("%/K", "percent per kelvin"), ("ppm/K", "ppm per kelvin")),
    "m/N": (("mm/N", "millimetres per newton"), ("um/N", "micrometres per newton")),
    "T/N": (("mT/N", "millitesla per newton"), ("uT/N", "microtesla per newton")),
    "V/N": (("mV/N", "millivolts per newton"),),
}
# Plausible magnitudes of a plain SI number given for an output (a target's value, a limit's
# bound), by the output's SI unit: a compliance of 0.32 is 0.32 m/N, a field_max of 4.8 is 4.8 T.
OUTPUT_PLAUSIBLE = {
    "m": LENGTH,
    "m^2": AREA,
    "T": FIELD,
    "N": FORCE,
    "V": VOLTAGE,
    "s": TIME,
    "rad": ANGLE,
    "m/N": (0.0, 0.01),
    "T/N": (0.0, 10.0),
    "V/N": (0.0, 100.0),
}


@dataclasses.dataclass(frozen=True)
class Key:
    """One spec key.

    Attributes:
        name: the dotted key, ``table.key``.
        kind: its type (a key of :data:`KINDS`).
        meaning: what it sets, in one line.
        unit: the SI unit of a quantity ("1": dimensionless; :data:`READING`: the reading's
            unit, T or V); "" for keys that are not quantities.
        default: the value (SI) when the key is absent; :data:`REQUIRED`; None for "absent
            (the feature is off)"; or :class:`Depends`.
        domain: the physical domain of a number (see :data:`POSITIVE`), or None.
        plausible: (low, high), the plausible magnitudes of a plain SI number (a dict by
            unit for a reading), or None.
        real_parts: (highest, why): a value above ``highest`` (SI, with or without a unit)
            is far outside real parts and warns; or None.
        choices: {name: meaning} of a choice, a list of names or a preset.
        presets: {name: factory} of the parts a preset names (the factory returns the part).
        length: the number of items of a list, or None (any).
    """

    name: str
    kind: str
    meaning: str
    unit: str = ""
    default: object = REQUIRED
    domain: tuple | None = None
    plausible: tuple | Mapping | None = None
    real_parts: tuple | None = None
    choices: Mapping[str, str] = dataclasses.field(default_factory=dict)
    presets: Mapping[str, Callable] = dataclasses.field(default_factory=dict)
    length: int | None = None

    @property
    def table(self) -> str:
        """The table the key sits in ("mechanics", "design.variables.*")."""
        return self.name.rpartition(".")[0]

    @property
    def field(self) -> str:
        """The key's name inside its table ("thickness")."""
        return self.name.rpartition(".")[2]

    def plausible_range(self, unit: str) -> tuple | None:
        """(low, high) of a plain number read in ``unit``, or None."""
        return self.plausible.get(unit) if isinstance(self.plausible, Mapping) else self.plausible
