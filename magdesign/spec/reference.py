"""The spec reference, rendered from the one table of spec keys (:mod:`magdesign.spec.keys`).

:func:`markdown` returns the page; ``python -m magdesign.spec.reference`` prints it.
"""

import numpy as np

from magdesign.spec.checks import domain_text
from magdesign.spec.key import KINDS, REQUIRED, WRITTEN_UNITS, Depends, Key
from magdesign.spec.keys import KEYS, TABLES
from magdesign.units import convert

_INTRO = """\
# Spec reference

A spec is a TOML file of tables. The scene's tables say what the sensor is: `[magnet]`,
`[mechanics]`, `[sensor]`, `[geometry]`, `[load]`, optionally `[scene]` (the effects of the
measurement chain), `[inductors]`, `[pole]`, `[indenter]` (what presses a skin),
`[[magnet.extra]]`, `[[magnet.magnets]]` (a skin's discrete magnets) and `[[soft]]` (arrays of tables). A design spec adds the `[design.*]` tables: what the solver may change, what it must
meet, and what it maximises. A key that is not listed here is an error naming the key.

This page is generated from the code's own table of keys (`magdesign.spec.keys`): the readers
look up every key there, so the page lists exactly the keys that are read.

## Units

A quantity is written as a string of a number and a unit, `"3 mm"`, `"0.32 mm/N"`, `"83 kPa"`,
`"4.8 mT"`: its unit must have the dimension the key expects, and it is converted to SI. A
plain number (`thickness = 0.003`) is taken to be SI already (m, T, N, Pa, s, V, rad). A plain
number far outside its key's plausible range (below) is read all the same, with a warning
that names the key and the unit it was read in, for example
`mechanics.thickness = 3 was read as 3 m; write "3 mm" for millimetres`. Dimensionless keys
(unit 1) take plain numbers. A value with a unit far outside real parts (a remanence above
1.6 T) warns too.

Columns: *default* is the value when the key is absent (*required*: the spec must give it
where its table applies; *absent*: the feature is off); *domain* is the physical domain (a
value outside is an error); *plausible* is the range of magnitudes a plain SI number is
expected in. In the `[design.*]` tables `*` stands for a scene parameter's dotted key
(`"geometry.gap"`) or an output's name (`compliance`).
"""

# The units a preset's values are shown in.
_PART_UNITS = {
    "lsb": "uT",
    "full_scale": "mT",
    "resistance": "Ohm",
    "sensitivity": "1/T",
    "bias_current": "mA",
    "linear_range": "mT",
    "saturation_field": "mT",
}


def _number(value: float, unit: str) -> str:
    """An SI number shown in the unit a spec would write it in ("0.0002" m -> "0.2 mm")."""
    if unit in ("", "1") or value == 0.0:
        return f"{value:g}"
    for shown, _ in WRITTEN_UNITS.get(unit, ()):
        if 0.1 <= abs(convert(value, shown)) < 1e4:
            return f"{convert(value, shown):.4g} {shown}"
    return f"{value:.4g} {unit}"


def _value(value, unit: str) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return _number(float(value), unit) if isinstance(value, float) else str(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(item, unit) for item in value) + "]"
    return str(value)


def _default(key: Key) -> str:
    if key.default is REQUIRED:
        return "required"
    if key.default is None:
        return "absent"
    if isinstance(key.default, Depends):
        return key.default.text
    return f"`{_value(key.default, key.unit)}`"


def _domain(key: Key) -> str:
    return "" if key.domain is None else domain_text(key.domain)


def _plausible(key: Key) -> str:
    if key.plausible is None:
        return ""
    ranges = key.plausible if isinstance(key.plausible, dict) else {key.unit: key.plausible}
    shown = []
    for unit, (low, high) in ranges.items():
        below = f"{low:.4g} to " if low > 0 else "up to "
        shown.append(f"{below}{high:.4g} {unit}")
    return "; ".join(shown)


def _choices(key: Key) -> str:
    return ", ".join(f"`{name}`" for name in key.choices)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _part_values(part) -> str:
    """A part's values in their usual units: "lsb 0.15 uT, full_scale 4.8 mT"."""
    shown = []
    for name, unit in _PART_UNITS.items():
        value = getattr(part, name, None)
        if value is None:
            continue
        values = np.atleast_1d(np.asarray(value, dtype=float))
        numbers = sorted(set(float(v) for v in values), key=list(values).index)
        text = " / ".join(f"{convert(v, unit):.4g}" for v in numbers)
        shown.append(f"{name} {text} {unit}".replace(" 1/T", " /T"))
    return ", ".join(shown)


def _table_title(table: str) -> str:
    return f"[[{table}]]" if table in ("soft", "magnet.extra", "magnet.magnets") else f"[{table}]"


def markdown() -> str:
    """The spec reference as a Markdown page: a section per spec table, a row per key (key,
    type, unit, default, domain, plausible range of a plain number, choices or presets,
    meaning), the presets with their values, and the rules for units."""
    lines = [_INTRO]
    for table in TABLES:
        keys = [key for key in KEYS.values() if key.table == table]
        lines += [
            f"## {_table_title(table)}",
            "",
            "| key | type | unit | default | domain | plausible (plain number) | choices / presets | meaning |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for key in keys:
            unit = key.unit if key.unit else ""
            row = [
                f"`{key.field}`",
                key.kind,
                unit,
                _default(key),
                _domain(key),
                _plausible(key),
                _choices(key),
                key.meaning,
            ]
            lines.append("| " + " | ".join(_cell(cell) for cell in row) + " |")
        lines.append("")
        for key in keys:
            if key.choices:
                lines.append(f"`{key.field}`:")
                lines.append("")
                for name, meaning in key.choices.items():
                    values = f" ({_part_values(key.presets[name]())})" if name in key.presets else ""
                    lines.append(f"- `{name}`: {meaning}{values}")
                lines.append("")
    lines += ["## Types", "", "| type | written as |", "|---|---|"]
    lines += [f"| {kind} | {_cell(text)} |" for kind, text in KINDS.items()]
    return "\n".join(lines).rstrip() + "\n"


if __name__ == "__main__":
    print(markdown(), end="")
