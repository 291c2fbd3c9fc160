"""Adams FUNCTION expressions that are linear in measures -> coefficients.

The forms translated are the ones written by Adams/View for springs and distance constraints:

    -100.0*(DM(204,205) - 2.0) - 1.0*VR(204,205) + 0.0          (SFORCE TRANSLATIONAL)
    -1.0*RTOD*(AZ(207,208) - 0.0*DTOR) - 5.0E-002*RTOD*WZ(207,208,208)   (SFORCE ROTATIONAL)
    DM(0202, 0102) - 2                                          (GCON)

Each measure call becomes a symbol, the rest is parsed by casmech's own expression parser, and
CasADi gives the coefficients (the gradient) and checks the expression is affine in the measures
(the gradient depends on no symbol). Anything else raises NotTranslated with the reason.
"""

from __future__ import annotations

import re

import casadi as ca

from casmech.core.expressions import ExpressionError, parse
from casmech.core.records import record

# Adams constants and the symbols of time
CONSTANTS = {"rtod": 180.0 / 3.141592653589793, "dtor": 3.141592653589793 / 180.0}
_CALL = re.compile(r"\b([a-z]+)\s*\(\s*([0-9]+(?:\s*,\s*[0-9]+)*)\s*\)")
MEASURES = {"dm", "vr", "az", "wz", "dx", "dy", "dz", "ax", "ay", "vx", "vy", "vz",
            "wx", "wy"}


class NotTranslated(Exception):
    """The expression is outside the translated forms (the message says why)."""


@record
class Measure:
    name: str  # dm, vr, az, wz, ...
    markers: tuple[int, ...]

    @property
    def symbol(self) -> str:
        return "_".join([self.name, *map(str, self.markers)])


@record
class Affine:
    constant: float
    coefficients: dict[Measure, float]


def affine(text: str) -> Affine:
    """constant + sum(coefficient * measure) for an Adams expression affine in its measures."""
    lowered = text.lower()
    measures: dict[str, Measure] = {}

    def replace(match: re.Match) -> str:
        name = match.group(1)
        if name not in MEASURES:
            raise NotTranslated(f"function {name.upper()}(...) is not translated")
        measure = Measure(name, tuple(int(m) for m in match.group(2).split(",")))
        measures[measure.symbol] = measure
        return f" {measure.symbol} "

    substituted = _CALL.sub(replace, lowered)
    try:
        expression = parse(substituted)
    except ExpressionError as error:
        raise NotTranslated(f"cannot read the expression: {error}") from None
    unknown = expression.symbols - set(measures) - set(CONSTANTS) - {"pi"}
    if unknown:
        raise NotTranslated(f"depends on {', '.join(sorted(s.upper() for s in unknown))}")
    symbols = {name: ca.SX.sym(name) for name in measures}
    value = expression.evaluate({**CONSTANTS, **symbols}, backend="casadi")
    names = sorted(symbols)
    vector = ca.vertcat(*[symbols[n] for n in names]) if names else ca.SX(0, 1)
    gradient = ca.jacobian(value, vector) if names else ca.SX(1, 0)
    if names and ca.depends_on(gradient, vector):
        raise NotTranslated("not linear in its measures")
    evaluate = ca.Function("affine", [vector], [value, gradient])
    constant, coefficients = evaluate(ca.DM.zeros(len(names)))
    coefficients = [float(c) for c in ca.DM(coefficients).full().ravel()]
    return Affine(float(constant), {measures[n]: c for n, c in zip(names, coefficients, strict=True)
                                    if c != 0.0})


_DEGREES = re.compile(r"(?<![\w.])(\d+\.?\d*|\.\d+)(?:[eE]([+-]?\d+))?[dD](?![\w(])")
_TIME = re.compile(r"\btime\b")


def time_function(text: str, time_unit: float = 1.0, scale: float = 1.0) -> str:
    """An Adams FUNCTION of TIME alone as a casmech expression of t (seconds): TIME -> t (in
    the deck's time unit), 30D -> 30*pi/180, DTOR/RTOD as numbers, the value times `scale` (the
    SI factor of its unit). NotTranslated when it reads anything but TIME (DX(..), VR(..): the
    state) or a function casmech does not have."""
    lowered = _DEGREES.sub(lambda m: f"({m.group(1)}{'e' + m.group(2) if m.group(2) else ''}"
                           "*pi/180)", text.lower())
    for call in _CALL.finditer(lowered):
        if call.group(1) in MEASURES:
            raise NotTranslated(f"reads the state ({call.group(0).upper()}); only functions "
                                "of TIME are translated")
    lowered = _TIME.sub("t" if time_unit == 1 else f"(t / {time_unit!r})", lowered)
    for name, value in CONSTANTS.items():
        lowered = re.sub(rf"\b{name}\b", repr(value), lowered)
    try:
        expression = parse(lowered)
        unknown = expression.symbols - {"t", "pi"}
        if unknown:
            raise NotTranslated(f"depends on {', '.join(sorted(s.upper() for s in unknown))}")
        expression.evaluate({"t": ca.SX.sym("t"), "pi": 3.141592653589793}, backend="casadi")
    except ExpressionError as error:
        raise NotTranslated(f"cannot read the expression: {error}") from None
    return lowered if scale == 1 else f"{float(scale)!r} * ({lowered})"
