"""The dimension of an expression (core/units.py), from its numbers' units and its names'.

None is "no stated dimension": a number without a unit, `pi`, `e`, a name whose dimension is
not known (t, the state, a parameter defined without units); anything with it is None too,
except a sum, where the stated side's dimension wins (`2 m + 1` is a length: the 1 is SI).
Stated dimensions must agree where they meet: the two sides of `+`, `-` and a comparison,
`min`/`max`, `atan2`'s arguments, `step`'s positions and its values, `if`'s branches; the
argument of sin, cos, exp, log, ... must be a number (an angle in SI); a power's exponent a
number (a constant one for a stated base). A disagreement is a DimensionError at the operator
or call.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction

from casmech.core.expressions import Binary, Call, Constant, Expr, Name, Number, Unary
from casmech.core.units import NUMBER, Dimension, describe, multiply, power


class DimensionError(Exception):
    """Dimensions that do not agree; `offset`/`length` locate it in the text (E205)."""

    code = "E205"

    def __init__(self, message: str, offset: int, length: int = 1, hint: str | None = None):
        super().__init__(message)
        self.message, self.offset, self.length, self.hint = message, offset, length, hint


def _same(a, b, offset: int, what: str):
    if a is not None and b is not None and a != b:
        raise DimensionError(f"{what}: {describe(a)} and {describe(b)}", offset)
    return a if a is not None else b


def _binary(node: Binary, names) -> Dimension | None:
    a, b = of(node.left, names), of(node.right, names)
    if node.op in ("+", "-"):
        return _same(a, b, node.offset, f"'{node.op}' of different dimensions")
    if node.op in ("<", "<=", ">", ">="):
        _same(a, b, node.offset, "a comparison of different dimensions")
        return None
    if node.op == "**":
        return _power(node, a, b)
    if a is None or b is None:
        return None
    return multiply(a, b, 1 if node.op == "*" else -1)


def _power(node: Binary, base, exponent) -> Dimension | None:
    if exponent not in (None, NUMBER):
        raise DimensionError(f"an exponent must be a number, not a {describe(exponent)}",
                             node.offset, 2)
    if base is None or base == NUMBER:
        return base
    if node.right.names():
        raise DimensionError(f"a {describe(base)} raised to a power that is not a constant",
                             node.offset, 2)
    value = node.right.evaluate({}, 0)
    return power(base, Fraction(float(value)).limit_denominator(1000))


def _number_argument(node: Call, dims) -> None:
    for dim in dims:
        if dim not in (None, NUMBER):
            raise DimensionError(f"{node.function}() of a {describe(dim)}: its argument must be "
                                 "a number (an angle in rad)", node.offset, node.length)


def _call(node: Call, names) -> Dimension | None:
    dims = [of(arg, names) for arg in node.args]
    name = node.function
    if name in ("min", "max", "atan2"):
        same = _same(dims[0], dims[1], node.offset, f"{name}() of different dimensions")
        return None if name == "atan2" else same
    if name in ("abs", "floor"):
        return dims[0]
    if name == "sqrt":
        return None if dims[0] is None else power(dims[0], Fraction(1, 2))
    if name == "sign":
        return None
    if name == "step":
        _same(_same(dims[0], dims[1], node.offset, "step() positions of different dimensions"),
              dims[3], node.offset, "step() positions of different dimensions")
        return _same(dims[2], dims[4], node.offset, "step() values of different dimensions")
    if name == "if":
        return _same(dims[1], dims[2], node.offset, "if() branches of different dimensions")
    _number_argument(node, dims)
    return None


# node class -> its dimension(node, names)
RULES = {
    Number: lambda node, names: node.dimension,
    Constant: lambda node, names: None,
    Name: lambda node, names: names.get(node.name),
    Unary: lambda node, names: of(node.operand, names),
    Binary: _binary,
    Call: _call,
}


def of(node, names: Mapping[str, Dimension | None]) -> Dimension | None:
    """The dimension of an expression's node; `names`: a name's dimension (absent: None). A
    node of another kind (a number given as it is) has none."""
    rule = RULES.get(type(node))
    return None if rule is None else rule(node, names)


def dimension(expr: Expr, names: Mapping[str, Dimension | None]) -> Dimension | None:
    """The dimension of a parsed expression (module docstring); DimensionError if its parts
    disagree."""
    return of(expr.root, names)
