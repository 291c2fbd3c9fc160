"""Units of numbers in expressions (`30 deg`, `1000 mm`, `2 kN*m`, `9.81 m/s**2`) and the
dimensions of quantities (docs/format.md#units).

A unit follows its number and is written without spaces inside it: names of UNITS joined by
`*` and `/`, each with an optional integer power `**n` (`kg*m**2`, `N*m/deg`, `m/s**2`); `2
kN * m` (with spaces) is 2 kN times the name m, and `t` (tonne) is a unit only right after
its number (`1.5 t`), never inside one, so `0.1 m/s*t` is a speed times the time. The
number becomes its SI value (the unit's factor) with the unit's dimension: exponents of mass,
length and time (an angle is a number, as in SI: rad = 1, deg = pi/180; so `rpm` is 1/s and
a torque N m). A number without a unit is SI and of no stated dimension: it fits any field,
so every model without units reads as before.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from numbers import Rational

from casmech.errors import did_you_mean

# exponents of mass, length, time: ints, Fractions where a power makes them so (an int and the
# Fraction of the same value are equal and hash alike, so either finds a dimension in NAMES)
Dimension = tuple[Rational, Rational, Rational]


def dimension(mass: int = 0, length: int = 0, time: int = 0) -> Dimension:
    return (mass, length, time)


NUMBER = dimension()
MASS, LENGTH, TIME = dimension(mass=1), dimension(length=1), dimension(time=1)
FORCE = dimension(1, 1, -2)
TORQUE = dimension(1, 2, -2)  # also energy, and a rotational stiffness (N m/rad)
VELOCITY, RATE = dimension(length=1, time=-1), dimension(time=-1)
STIFFNESS, DAMPING = dimension(mass=1, time=-2), dimension(mass=1, time=-1)
ROTATIONAL_DAMPING = dimension(mass=1, length=2, time=-1)

# name -> (factor to SI, dimension)
UNITS: dict[str, tuple[float, Dimension]] = {
    # angle (a number)
    "rad": (1.0, NUMBER), "deg": (math.pi / 180, NUMBER), "rev": (2 * math.pi, NUMBER),
    # length
    "m": (1.0, LENGTH), "km": (1e3, LENGTH), "cm": (1e-2, LENGTH), "mm": (1e-3, LENGTH),
    "um": (1e-6, LENGTH), "in": (0.0254, LENGTH), "ft": (0.3048, LENGTH),
    # mass
    "kg": (1.0, MASS), "g": (1e-3, MASS), "mg": (1e-6, MASS), "t": (1e3, MASS),
    "lb": (0.45359237, MASS),
    # time
    "s": (1.0, TIME), "ms": (1e-3, TIME), "min": (60.0, TIME), "h": (3600.0, TIME),
    # frequency, rotational speed
    "Hz": (1.0, dimension(time=-1)), "rpm": (2 * math.pi / 60, dimension(time=-1)),
    # force
    "N": (1.0, FORCE), "kN": (1e3, FORCE), "MN": (1e6, FORCE), "mN": (1e-3, FORCE),
    "lbf": (4.4482216152605, FORCE),
    # energy, power, pressure
    "J": (1.0, TORQUE), "kJ": (1e3, TORQUE), "W": (1.0, dimension(1, 2, -3)),
    "kW": (1e3, dimension(1, 2, -3)), "Pa": (1.0, dimension(1, -1, -2)),
    "kPa": (1e3, dimension(1, -1, -2)), "MPa": (1e6, dimension(1, -1, -2)),
    "GPa": (1e9, dimension(1, -1, -2)),
}

# dimension -> (its name in messages, its SI unit)
NAMES: dict[Dimension, tuple[str, str]] = {
    NUMBER: ("number (an angle in rad)", "1"),
    MASS: ("mass", "kg"), LENGTH: ("length", "m"), TIME: ("time", "s"),
    dimension(length=2): ("area", "m^2"),
    dimension(length=1, time=-1): ("velocity", "m/s"),
    dimension(length=1, time=-2): ("acceleration", "m/s^2"),
    dimension(time=-1): ("angular velocity or frequency", "rad/s"),
    FORCE: ("force", "N"), TORQUE: ("torque or energy", "N m"),
    dimension(mass=1, length=2): ("moment of inertia", "kg m^2"),
    dimension(mass=1, time=-2): ("stiffness", "N/m"),
    dimension(mass=1, time=-1): ("damping", "N s/m"),
    dimension(mass=1, length=2, time=-1): ("rotational damping", "N m s/rad"),
}


UNKNOWN_HINT = ("a name right after a number is its unit (deg, mm, kN, rpm, ...: "
                "docs/format.md#units); to multiply, write '*' between them")


class UnitError(Exception):
    """A unit that is not one (offset and length in the expression's text)."""

    def __init__(self, message: str, offset: int, length: int, hint: str | None = None):
        super().__init__(message)
        self.message, self.offset, self.length, self.hint = message, offset, length, hint


def describe(dim: Dimension) -> str:
    """'length (m)', or the SI unit of a dimension without a name ('kg m^3')."""
    if dim in NAMES:
        name, unit = NAMES[dim]
        return f"{name} ({unit})" if unit != "1" else name
    parts = [f"{base}^{power}" if power != 1 else base
             for base, power in zip(("kg", "m", "s"), dim, strict=True) if power]
    return " ".join(parts) or "number"


def multiply(a: Dimension, b: Dimension, sign: int = 1) -> Dimension:
    return tuple(x + sign * y for x, y in zip(a, b, strict=True))


def power(a: Dimension, exponent) -> Dimension:
    from fractions import Fraction  # (a unit's powers only: not imported to read a model)

    return tuple(x * Fraction(exponent).limit_denominator(1000) for x in a)


def _adjacent(tokens: Sequence, k: int) -> bool:
    """Whether token k follows token k - 1 without a space."""
    before = tokens[k - 1]
    return tokens[k].offset == before.offset + len(before.text)


def _atom(tokens: Sequence, k: int) -> tuple[float, Dimension, int]:
    """A unit name at token k and its power (`**n`, `**-n`): (factor, dimension, next)."""
    token = tokens[k]
    if token.text not in UNITS:
        close = did_you_mean(token.text, UNITS)
        raise UnitError(f"unknown unit '{token.text}'", token.offset, len(token.text),
                        close or UNKNOWN_HINT)
    factor, dim = UNITS[token.text]
    k += 1
    if k + 1 < len(tokens) and tokens[k].text == "**" and _adjacent(tokens, k):
        sign = -1 if tokens[k + 1].text == "-" and _adjacent(tokens, k + 1) else 1
        number = tokens[k + 1 + (sign < 0)]
        if number.kind != "number" or not _adjacent(tokens, k + 1 + (sign < 0)) or \
                not number.text.isdigit():
            raise UnitError("a unit's power is an integer", tokens[k].offset, 2,
                            "write m/s**2 or m*s**-2")
        exponent = sign * int(number.text)
        factor, dim = factor ** exponent, power(dim, exponent)
        k += 2 + (sign < 0)
    return factor, dim, k


def read(tokens: Sequence, k: int) -> tuple[float, Dimension, int]:
    """The unit starting at token k (a name right after a number): its factor to SI, its
    dimension and the index of the token after it (module docstring)."""
    factor, dim, k = _atom(tokens, k)
    while (k + 1 < len(tokens) and tokens[k].kind == "op" and tokens[k].text in "*/"
           and _adjacent(tokens, k) and _adjacent(tokens, k + 1)
           and tokens[k + 1].kind == "name" and tokens[k + 1].text in UNITS
           and tokens[k + 1].text != "t"):
        sign = 1 if tokens[k].text == "*" else -1
        more, more_dim, k = _atom(tokens, k + 1)
        factor, dim = factor * more ** sign, multiply(dim, more_dim, sign)
    return factor, dim, k
