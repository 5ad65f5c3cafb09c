import math

import pytest

from magdesign.units import SpecError, convert, parse, unit_factor


@pytest.mark.parametrize(
    "text, unit, expected",
    [
        ("6.4 mm", "m", 6.4e-3),
        ("0.32 mm/N", "m/N", 0.32e-3),
        ("4.8 mT", "T", 4.8e-3),
        ("83 kPa", "Pa", 83e3),
        ("1.17 T", "T", 1.17),
        ("0.72 %/mT", "1/T", 7.2),
        ("0.131 mV/(A/m)", "V*m/A", 0.131e-3),
        ("2 kOhm", "Ohm", 2e3),
        ("-0.12 %/K", "1/K", -1.2e-3),
        ("10 deg", "rad", math.pi / 18),
        ("36 mm^2", "m^2", 36e-6),
        ("50 uT", "T", 50e-6),
        ("1 kg*m/s^2", "N", 1.0),
        ("100 Hz", "1/s", 100.0),
        (3.5, "m", 3.5),
        ("0.49", "1", 0.49),
    ],
)
def test_parse_reads_si_values(text, unit, expected):
    assert parse(text, unit, key="k") == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize(
    "value, fragment",
    [
        ("6.4", "missing unit"),
        ("6.4 mT", "wrong unit"),
        ("6 furlong", "unknown unit"),
        ("abc", "expected a quantity in m"),
        (True, "expected a quantity in m"),
        ([1, 2], "expected a quantity in m"),
        ("6.4 mm)", "cannot read unit"),
    ],
)
def test_parse_errors_name_the_key_and_the_unit(value, fragment):
    with pytest.raises(SpecError) as error:
        parse(value, "m", key="magnet.radius")
    message = str(error.value)
    assert message.startswith("magnet.radius:") and fragment in message and "\n" not in message


def test_convert_inverts_unit_factor():
    assert unit_factor("mm/N") == pytest.approx(1e-3)
    assert convert(7.4458e-3, "mm") == pytest.approx(7.4458)


@pytest.mark.parametrize(
    "value",
    [
        "1 mm^",  # a power with no exponent
        "1 km^200",  # a factor that overflows
        "1 mm^x",
        "1 (mm",
        "1 " + "(" * 3000 + "mm" + ")" * 3000,  # nesting that would exhaust the recursion
        "(" * 3000 + "1 mm" + ")" * 3000,
        "1 " + "*".join(["km"] * 400),  # a factor of 1e1200: inf
        float("nan"),
        float("inf"),
        -float("inf"),
        1e308,
        10**100_000,  # too long for Python to print or convert
        "1e999 mm",
        "nan mm",
        "x" * 200_000,
    ],
    ids=lambda value: type(value).__name__,
)
def test_hostile_values_give_one_short_line_naming_the_key(value):
    """Every broken quantity is a SpecError (never IndexError, OverflowError,
    RecursionError or a silent inf / NaN), one line that names the key and echoes at most
    about 80 characters of the value."""
    with pytest.raises(SpecError) as error:
        parse(value, "m", key="magnet.radius")
    message = str(error.value)
    assert message.startswith("magnet.radius:") and "\n" not in message
    assert len(message) < 400, message


def test_largest_usable_quantities_still_read():
    assert parse("1e190 Pa", "Pa", key="k") == pytest.approx(1e190)
    assert parse("2 mm^12", "m^12", key="k") == pytest.approx(2e-36)
