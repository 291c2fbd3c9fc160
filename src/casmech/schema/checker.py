"""The Checker: reports findings and evaluates scalars, vectors and names for `semantic`.

Every finding is collected in `Checker.found`; the caller raises them all at once. A value whose
check failed is None, and references to a parameter that failed are not reported again.
"""

from __future__ import annotations

import math
import re
from collections import ChainMap
from collections.abc import Mapping
from typing import Any

import numpy as np

from casmech.core import dimensions, traced, units
from casmech.core.dimensions import DimensionError
from casmech.core.expressions import CONSTANTS, FUNCTIONS, Expr, ExpressionError, from_number
from casmech.core.expressions import parse as parse_expression
from casmech.elements import force_types
from casmech.errors import Diagnostic, Source, did_you_mean, failed
from casmech.schema import limits, resolved, spec
from casmech.schema.dimensions import expected
from casmech.schema.loader import Document, Path, format_path
from casmech.schema.resolved import GROUND, ScalarFunction
from casmech.schema.scale import Scale

NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
RESERVED = frozenset({"t", *CONSTANTS, *FUNCTIONS})
ZERO = 1e-12  # a vector shorter than this is zero-length (its direction is meaningless)
WHY_RESERVED = "pi, e, t and the function names cannot be parameters"
WHY_GROUND = "'ground' is the fixed global frame, always present; choose another name"
TIME_KEYS = "joint f, driver angle/displacement"  # and the force elements' state keys


class _Given:
    """An expression's root that is a number given as it is (a traced number)."""

    def __init__(self, number):
        self.number = number

    def evaluate(self, env, backend):
        return self.number

    def names(self):
        return ()


def _dimension(value: Any, names: Mapping[str, Any]):
    """The dimension of a parameter's value as written (None: no unit stated), with the
    earlier parameters' `names`."""
    if not isinstance(value, str):
        return None
    try:
        return dimensions.dimension(parse_expression(value), names)
    except (ExpressionError, DimensionError):
        return None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


class Checker:
    """`symbols`: parameters evaluated as traced numbers (name -> CasADi symbol;
    casmech.core.traced), so that every number computed from them carries its
    expression."""

    def __init__(self, document: Document, overrides: Mapping[str, str] | None,
                 symbols: Mapping[str, Any] | None = None):
        self.doc = document
        self.overrides = dict(overrides or {})
        self.symbols = dict(symbols or {})
        # parameter values an instance gives its component that are traced numbers (the
        # document holds their values, which its validation reads)
        self.given: dict[str, Any] = {}
        self.found: list[Diagnostic] = []
        self.parameters: dict[str, float] = {}
        self.declared: dict[str, int] = {}  # parameter -> line, for "defined later"
        self.broken: set[str] = set()  # parameters that failed: no follow-up errors
        self.bodies: dict[str, resolved.Body | None] = {}
        self.joint_types: dict[str, str] = {}
        self.joint_bodies: dict[str, tuple[str, str]] = {}
        self.scale = Scale()  # the bodies' scale so far: the floors of directions
        self.dimensions: dict[str, Any] = {}  # parameter -> its core.units dimension or None

    # -- reporting
    def error(self, code: str, path: Path | str, message: str, **extra: Any) -> None:
        if "source" not in extra:
            extra["source"] = self.doc.locate(path) if isinstance(path, tuple) else None
        text = format_path(path) if isinstance(path, tuple) else path
        self.found.append(Diagnostic(code, text, message, **extra))

    def inside(self, path: Path | str, offset: int) -> Source | None:
        return self.doc.source_in_scalar(path, offset) if isinstance(path, tuple) else None

    # -- expressions
    def expression(self, path: Path | str, value: Any, variables=()) -> Expr | None:
        """Parse and check the names of a scalar (E200, E201, E202, E203, E204)."""
        try:
            expr = parse_expression(value) if isinstance(value, str) else from_number(value)
        except ExpressionError as error:
            source = self.inside(path, error.offset)
            self.error(error.code, path, error.message, source=source, hint=error.hint)
            return None
        except OverflowError:
            self.error("E204", path, "number too large", got=str(value))
            return None
        unknown: dict[str, int] = {}  # name -> offset of its first use
        for name, offset, _ in expr.names_with_offsets():
            if name not in self.parameters and name not in variables:
                unknown.setdefault(name, offset)
        for name, offset in unknown.items():
            if name not in self.broken:  # a failed parameter was reported where it is defined
                self.unknown_symbol(path, name, self.inside(path, offset), variables)
        return None if unknown or not self.dimension_fits(path, expr) else expr

    def dimension_fits(self, path: Path | str, expr: Expr) -> bool:
        """Whether the expression's units agree (core/dimensions.py) and its dimension is the
        field's (schema/dimensions.py); E205 where not."""
        try:
            found = dimensions.dimension(expr, self.dimensions)
        except DimensionError as error:
            self.error(error.code, path, error.message, source=self.inside(path, error.offset),
                       hint=error.hint)
            return False
        if found is None:
            return True
        wanted = expected(self.doc.data, path)
        if wanted is None or found == wanted:
            return True
        self.error("E205", path, f"expected a {units.describe(wanted)}, got a "
                   f"{units.describe(found)}", expected=units.describe(wanted),
                   got=expr.text, hint="write the value in units of its dimension, or as a "
                                       "plain number in SI units")
        return False

    def unknown_symbol(self, path, name: str, source, variables) -> None:
        if name == "t":
            self.error(
                "E202",
                path,
                "time 't' is not allowed here",
                source=source,
                hint="functions of time are allowed in: "
                     f"{TIME_KEYS}, {force_types.state_reading()}",
            )
        elif name in self.declared:
            message = f"'{name}' is used before it is defined"
            hint = f"parameters are evaluated in order; '{name}' is defined at line "
            self.error("E201", path, message, source=source, hint=f"{hint}{self.declared[name]}")
        else:
            names = [*self.parameters, *variables, *CONSTANTS]
            hint = did_you_mean(name, names)
            self.error("E201", path, f"unknown symbol '{name}'", source=source, hint=hint)

    def finite(self, path, expr: Expr, at: Mapping[str, float]) -> float | None:
        """The value of `expr` (a traced number when it depends on a symbolic parameter), or
        None when it is not finite or implausible (reported)."""
        result = expr.evaluate({**self.parameters, **at}, "numpy")  # overflow: reported
        value = result.value if isinstance(result, traced.Traced) else float(result)
        if not math.isfinite(value):
            where = ", ".join(f"{name} = {number:g}" for name, number in at.items())
            self.error(
                "E204",
                path,
                f"'{expr.text}' evaluates to {value}" + (f" at {where}" if where else ""),
            )
            return None
        problem = limits.implausible(path, value)
        if problem is not None:
            written = "" if _is_number(expr.text) else f"{expr.text} = "
            self.error("E411", path, problem[0], expected=problem[1],
                       got=f"{written}{value:.6g}",
                       hint="SI units: metres, kilograms, seconds, radians")
            return None
        return traced.scalar(result) if isinstance(result, traced.Traced) else value

    def number(self, path: Path | str, value: Any) -> float | None:
        if type(value) is float or type(value) is int:  # a plain number: no names, no unit
            try:
                plain = float(value)
            except OverflowError:
                plain = math.nan  # reported below
            if math.isfinite(plain) and limits.implausible(path, plain) is None:
                return plain
        if isinstance(value, traced.Traced):  # an instance's value of a component parameter
            return self.finite(path, Expr(repr(value.value), _Given(value)), {})
        expr = self.expression(path, value)
        return None if expr is None else self.finite(path, expr, {})

    def setting(self, path: Path | str, value: Any) -> float | None:
        """A number that is a setting, not model data (an analysis's t_end, a bound of an
        estimate): its value even where it is computed from a symbolic parameter."""
        return traced.value(self.number(path, value))

    def function(self, path: Path, value: Any, at: Mapping[str, float]) -> ScalarFunction | None:
        variables = tuple(at)
        expr = self.expression(path, value, variables)
        if expr is None or self.finite(path, expr, at) is None:
            return None
        source = self.doc.locate(path)
        return ScalarFunction(str(value), expr, dict(self.parameters), variables, source)

    def numbers(self, path: Path, values) -> np.ndarray | None:
        items = [self.number((*path, index), value) for index, value in enumerate(values)]
        return None if failed(items) else traced.array(items)

    def positive(self, code: str, path: Path, value, what: str) -> Any:
        """`value` (a number or an array) if all positive; else report and return None."""
        if value is not None and np.any(np.asarray(value) <= 0):
            got = ", ".join(f"{x:g}" for x in np.atleast_1d(value))
            self.error(code, path, f"{what} must be positive", got=got)
            return None
        return value

    def vector(self, path: Path, values, default=(0.0, 0.0, 0.0)) -> np.ndarray | None:
        return traced.asarray(default).copy() if values is None else self.numbers(path, values)

    def direction(self, path: Path, values, normalise: bool = True) -> np.ndarray | None:
        vector = self.numbers(path, values)
        if vector is None:
            return None
        norm = np.linalg.norm(vector)
        if norm < ZERO:
            self.error("E404", path, "zero-length vector: its direction is undefined")
            return None
        floor = self.scale.direction_floor(normalise)
        if norm < floor:
            what = ("round-off in its components decides where it points" if normalise else
                    "its length scales the constraint row, which then holds too loosely")
            self.error("E404", path, f"a direction of length {norm:.3g} is too short: {what}",
                       expected=f"a length of at least {floor:.3g}",
                       hint="write the direction itself (e.g. [0, 0, 1]) rather than a tiny "
                            "difference of points" if normalise else
                            "write a unit vector (e.g. [0, 0, 1])")
            return None
        return vector / norm if normalise else vector

    # -- names
    def parameter_values(self, parameters: Mapping[str, Any]) -> None:
        self.declared = {
            name: self.doc.locate_key(("parameters", name)).line for name in parameters
        }
        for name in self.overrides.keys() - parameters.keys():
            hint = did_you_mean(name, parameters)
            self.error("E300", f"--set {name}", f"unknown parameter '{name}'", hint=hint)
        for name in self.symbols.keys() - parameters.keys():
            hint = did_you_mean(name, parameters)
            self.error("E300", f"symbolic {name}", f"unknown parameter '{name}'", hint=hint)
        for name, value in parameters.items():
            path = ("parameters", name)
            if not self.valid_name(path, name, self.doc.locate_key(path), RESERVED, WHY_RESERVED):
                self.broken.add(name)
                continue
            where = f"--set {name}" if name in self.overrides else path
            written = self.overrides.get(name, self.given.get(name, value))
            result = self.number(where, written)
            self.dimensions[name] = _dimension(written, self.dimensions) if result is not None \
                else None
            if result is not None and name in self.symbols:
                result = traced.seed(traced.value(result), self.symbols[name])
            del self.declared[name]
            self.parameters.update({name: result} if result is not None else {})
            self.broken.update({name} if result is None else set())

    def valid_name(self, path: Path, name: str, source: Source, reserved, why: str) -> bool:
        if not NAME.match(name):
            expected = "letters, digits and '_', not starting with a digit"
            self.error("E303", path, f"invalid name '{name}'", source=source, expected=expected)
        elif name in reserved:
            self.error(
                "E302",
                path,
                f"'{name}' is a reserved name",
                source=source,
                hint=why,
            )
        return bool(NAME.match(name)) and name not in reserved

    def unique_names(self, model: spec.ModelSpec) -> None:
        first: dict[str, Path] = {}
        for section in ("bodies", "joints", "forces"):
            for index, item in enumerate(getattr(model, section)):
                path = (section, index, "name")
                if not self.valid_name(
                    path, item.name, self.doc.locate(path), {GROUND}, WHY_GROUND
                ):
                    continue
                if item.name in first:
                    where = first[item.name]
                    line = self.doc.locate(where).line
                    message = f"duplicate name '{item.name}' (first used by "
                    self.error("E301", path, f"{message}{format_path(where[:2])}, line {line})")
                first.setdefault(item.name, path)

    def reference(self, path: Path, name: str, known, what: str) -> bool:
        if name not in known:
            hint = did_you_mean(name, known)
            self.error("E300", path, f"unknown {what} '{name}'", hint=hint)
        return name in known

    def two_bodies(self, path: Path, body_i: str, body_j: str) -> bool:
        known = ChainMap({GROUND: None}, self.bodies)  # no copy: thousands of bodies
        found = all(
            [
                self.reference((*path, "body_i"), body_i, known, "body"),
                self.reference((*path, "body_j"), body_j, known, "body"),
            ]
        )
        if found and body_i == body_j:
            self.error("E304", (*path, "body_j"), f"body_i and body_j are both '{body_i}'")
        return found and body_i != body_j
