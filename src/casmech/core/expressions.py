"""The safe expression language of model files (never `eval`).

    expr    := sum (COMPARE sum)?          # COMPARE: '<' | '<=' | '>' | '>=' (not chained)
    sum     := product (('+' | '-') product)*
    product := unary (('*' | '/') unary)*
    unary   := ('+' | '-') unary | power
    power   := atom ('**' unary)?          # right-associative, binds tighter than unary minus
    atom    := NUMBER UNIT? | NAME | NAME '(' expr (',' expr)* ')' | '(' expr ')'
    UNIT    := a unit of core/units.py right after its number (`30 deg`, `2 kN*m`)

Names are parameters or variables (`t`, `length`, ...) and may be dotted (`pivot.angle`,
`bar.vx`: states of the mechanism, resolved in semantic); `pi` and `e` are builtin constants;
calls are limited to the functions of `FUNCTIONS`, checked (name and arity) at parse time.
A comparison is 1.0 when it holds and 0.0 when not; `if(c, a, b)` is `a` where c != 0, else `b`
(CasADi `if_else`, numpy `where`), `max`/`min` are exact (`fmax`/`fmin`): all three are
continuous only where their branches meet, so a contact law written with them has a kink
the integrator sees (docs/format.md).
An `Expr` evaluates with the "numpy" backend (floats or arrays) or the "casadi" backend
(SX/MX/DM or floats), both defined by tables, not branches.
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable, Mapping
from typing import Any

import casadi
import numpy as np

from casmech.core import traced, units
from casmech.core.records import record
from casmech.errors import did_you_mean

# limits that keep the recursive parser and evaluator far from Python's recursion limit
MAX_DEPTH = 50  # nested parentheses, calls, signs and powers
MAX_TOKENS = 1000  # bounds the depth of long operator chains


class ExpressionError(Exception):
    """A problem inside an expression; `offset`/`length` locate it in the text (0-based)."""

    code = "E200"

    def __init__(self, message: str, offset: int, length: int = 1, hint: str | None = None):
        super().__init__(message)
        self.message = message
        self.offset = offset
        self.length = length
        self.hint = hint


class ExpressionSyntaxError(ExpressionError):
    """The text is not an expression (E200)."""


class ExpressionFunctionError(ExpressionSyntaxError):
    """Call of an unknown function or with the wrong number of arguments (E203)."""

    code = "E203"


class ExpressionNameError(ExpressionError):
    """A name without a value at evaluation time (E201)."""

    code = "E201"


def step(x, x0, h0, x1, h1):
    """Adams' STEP: h0 up to x0, h1 from x1, a cubic in between (the language's `step` on
    CasADi values; contact friction)."""
    a = (x - x0) / (x1 - x0)
    cubic = h0 + (h1 - h0) * a * a * (3.0 - 2.0 * a)
    return casadi.if_else(x <= x0, h0, casadi.if_else(x >= x1, h1, cubic))


def _step_numpy(x, x0, h0, x1, h1):
    if isinstance(x, traced.Traced):  # a symbolic parameter's expression: fmin, fmax
        a = np.minimum(np.maximum((x - x0) / (x1 - x0), 0.0), 1.0)
    else:
        a = np.clip((np.asarray(x, float) - x0) / (x1 - x0), 0.0, 1.0)
    return h0 + (h1 - h0) * a * a * (3.0 - 2.0 * a)


def _if_numpy(condition, a, b):
    return np.where(np.asarray(condition) != 0, a, b)[()]


def _if_casadi(condition, a, b):
    return casadi.if_else(condition, a, b)


def _compare(numpy_op: Callable, casadi_op: Callable):
    """(numpy, casadi) of a comparison: 1.0 where it holds, else 0.0, in both backends."""
    return (lambda a, b: np.multiply(numpy_op(a, b), 1.0)), casadi_op


# name -> (arity, numpy implementation, casadi implementation)
FUNCTIONS: dict[str, tuple[int, Callable[..., Any], Callable[..., Any]]] = {
    "sin": (1, np.sin, casadi.sin),
    "cos": (1, np.cos, casadi.cos),
    "tan": (1, np.tan, casadi.tan),
    "asin": (1, np.arcsin, casadi.asin),
    "acos": (1, np.arccos, casadi.acos),
    "atan": (1, np.arctan, casadi.atan),
    "sinh": (1, np.sinh, casadi.sinh),
    "cosh": (1, np.cosh, casadi.cosh),
    "tanh": (1, np.tanh, casadi.tanh),
    "exp": (1, np.exp, casadi.exp),
    "log": (1, np.log, casadi.log),
    "sqrt": (1, np.sqrt, casadi.sqrt),
    "abs": (1, np.abs, casadi.fabs),
    "sign": (1, np.sign, casadi.sign),
    "floor": (1, np.floor, casadi.floor),
    "atan2": (2, np.arctan2, casadi.atan2),
    "min": (2, np.minimum, casadi.fmin),
    "max": (2, np.maximum, casadi.fmax),
    "step": (5, _step_numpy, step),
    "if": (3, _if_numpy, _if_casadi),
}

CONSTANTS: dict[str, float] = {"pi": math.pi, "e": math.e}

# operator -> (numpy implementation, casadi implementation); numpy never raises on x/0 or 0**-1
BINARY: dict[str, tuple[Callable[[Any, Any], Any], Callable[[Any, Any], Any]]] = {
    "+": (np.add, casadi.plus),
    "-": (np.subtract, casadi.minus),
    "*": (np.multiply, casadi.times),
    "/": (np.divide, casadi.rdivide),
    "**": (np.float_power, casadi.power),
    "<": _compare(np.less, casadi.lt),
    "<=": _compare(np.less_equal, casadi.le),
    ">": _compare(np.greater, casadi.gt),
    ">=": _compare(np.greater_equal, casadi.ge),
}
COMPARISONS = ("<", "<=", ">", ">=")
UNARY: dict[str, Callable[[Any], Any]] = {"+": operator.pos, "-": operator.neg}
BACKENDS = {"numpy": 0, "casadi": 1}


# ---------------------------------------------------------------------------------------- AST
def _number(value: float, backend: int) -> Any:
    return np.float64(value) if backend == BACKENDS["numpy"] else value


@record
class Number:
    """A number in SI (a unit's factor applied) and its unit's dimension; `offset`, `length`
    its span in the text."""

    value: float  # SI (a unit's factor applied)
    offset: int
    length: int
    dimension: tuple | None = None  # core.units.Dimension of its unit; None: no unit


    def evaluate(self, env, backend):
        return _number(self.value, backend)

    def names(self):
        return ()


@record
class Constant:
    """A named constant of CONSTANTS (pi, e); `offset`, `length` its span in the text."""

    name: str
    offset: int
    length: int

    def evaluate(self, env, backend):
        return _number(CONSTANTS[self.name], backend)

    def names(self):
        return ()


@record
class Name:
    """A name the environment gives a value (a parameter, a state: `pivot.angle`); `offset`,
    `length` its span in the text."""

    name: str
    offset: int
    length: int

    def evaluate(self, env, backend):
        if self.name not in env:
            hint = did_you_mean(self.name, env)
            raise ExpressionNameError(f"unknown name '{self.name}'", self.offset, self.length, hint)
        return env[self.name]

    def names(self):
        return ((self.name, self.offset, self.length),)


@record
class Unary:
    """A unary operation (`op` one of UNARY's) of one node; `offset` its place in the text."""

    op: str
    operand: Any
    offset: int

    def evaluate(self, env, backend):
        return UNARY[self.op](self.operand.evaluate(env, backend))

    def names(self):
        return self.operand.names()


@record
class Binary:
    """A binary operation (`op` one of BINARY's) of two nodes; `offset` its place in the
    text."""

    op: str
    left: Any
    right: Any
    offset: int

    def evaluate(self, env, backend):
        a, b = self.left.evaluate(env, backend), self.right.evaluate(env, backend)
        return BINARY[self.op][backend](a, b)

    def names(self):
        return self.left.names() + self.right.names()


@record
class Call:
    """A call of a function of FUNCTIONS on argument nodes; `offset`, `length` its span in
    the text."""

    function: str
    args: tuple[Any, ...]
    offset: int
    length: int

    def evaluate(self, env, backend):
        impl = FUNCTIONS[self.function][1 + backend]
        return impl(*(arg.evaluate(env, backend) for arg in self.args))

    def names(self):
        return tuple(n for arg in self.args for n in arg.names())


@record
class Expr:
    """A parsed expression: immutable, evaluable with either backend."""

    text: str
    root: Any

    def evaluate(self, env: Mapping[str, Any], backend: str = "numpy") -> Any:
        """Value of the expression; `env` maps every symbol to a number or CasADi expression."""
        if backend not in BACKENDS:
            raise ValueError(f"unknown backend {backend!r}; expected one of {sorted(BACKENDS)}")
        with np.errstate(all="ignore"):
            return self.root.evaluate(env, BACKENDS[backend])

    def names_with_offsets(self) -> tuple[tuple[str, int, int], ...]:
        """Every reference to a symbol as (name, offset, length), in text order."""
        return self.root.names()

    @property
    def symbols(self) -> frozenset[str]:
        return frozenset(name for name, _, _ in self.names_with_offsets())

    @property
    def is_constant(self) -> bool:
        return not self.symbols

    def __str__(self) -> str:
        return self.text


# ------------------------------------------------------------------------------------ tokens
_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z][A-Za-z0-9_]*)*)"  # dotted: pivot.angle
    r"|(?P<op>\*\*|<=|>=|[-+*/(),<>])"
)


@record
class Token:
    """One token of an expression's text: its kind, text and offset."""

    kind: str  # number | name | op | end
    text: str
    offset: int


def tokenize(text: str) -> list[Token]:
    tokens, pos = [], 0
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        if match is None:
            raise _bad_character(text, pos)
        if match.lastgroup != "space":
            tokens.append(Token(match.lastgroup, match.group(), pos))
        pos = match.end()
    if len(tokens) > MAX_TOKENS:
        raise ExpressionSyntaxError(f"expression longer than {MAX_TOKENS} tokens", 0, len(text))
    tokens.append(Token("end", "", len(text)))
    return tokens


def _bad_character(text: str, pos: int) -> ExpressionSyntaxError:
    char = text[pos]
    hint = "use '**' for powers" if char == "^" else None
    return ExpressionSyntaxError(f"unexpected character {char!r}", pos, 1, hint)


# ------------------------------------------------------------------------------------ parser
class _Parser:
    def __init__(self, text: str):
        self.text = text
        self.tokens = tokenize(text)
        self.pos = 0
        self.depth = 0

    @property
    def token(self) -> Token:
        return self.tokens[self.pos]

    def advance(self) -> Token:
        token = self.token
        self.pos += 1
        return token

    def accept(self, *ops: str) -> Token | None:
        if self.token.kind == "op" and self.token.text in ops:
            return self.advance()
        return None

    def expect(self, op: str, what: str) -> Token:
        token = self.accept(op)
        if token is None:
            raise self.unexpected(f"expected {what}")
        return token

    def unexpected(self, expected: str) -> ExpressionSyntaxError:
        token = self.token
        got = "end of expression" if token.kind == "end" else repr(token.text)
        return ExpressionSyntaxError(
            f"{expected}, got {got}", token.offset, max(len(token.text), 1)
        )

    def parse(self) -> Any:
        if self.token.kind == "end":
            raise ExpressionSyntaxError("empty expression", 0, max(len(self.text), 1))
        node = self.comparison()
        if self.token.kind != "end":
            raise self.unexpected("expected an operator")
        return node

    def comparison(self) -> Any:
        """sum (COMPARE sum)?: one comparison, so `a < b < c` is an error, not Python's chain."""
        node = self.sum()
        token = self.accept(*COMPARISONS)
        if token is None:
            return node
        node = Binary(token.text, node, self.sum(), token.offset)
        if self.token.kind == "op" and self.token.text in COMPARISONS:
            raise ExpressionSyntaxError("comparisons do not chain", self.token.offset,
                                        len(self.token.text), "write the two with if(...)")
        return node

    def binary_chain(self, ops: tuple[str, ...], operand: Callable[[], Any]) -> Any:
        node = operand()
        while (token := self.accept(*ops)) is not None:
            node = Binary(token.text, node, operand(), token.offset)
        return node

    def sum(self) -> Any:
        return self.binary_chain(("+", "-"), self.product)

    def product(self) -> Any:
        return self.binary_chain(("*", "/"), self.unary)

    def unary(self) -> Any:
        token = self.accept("+", "-")
        if token is None:
            return self.power()
        self.enter(token)
        node = Unary(token.text, self.unary(), token.offset)
        self.depth -= 1
        return node

    def power(self) -> Any:
        base = self.atom()
        token = self.accept("**")
        if token is None:
            return base
        self.enter(token)
        node = Binary("**", base, self.unary(), token.offset)
        self.depth -= 1
        return node

    def enter(self, token: Token) -> None:
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExpressionSyntaxError("expression nested too deeply", token.offset, 1)

    def atom(self) -> Any:
        token = self.token
        if token.kind == "number":
            self.advance()
            if self.token.kind == "name":  # its unit (core/units.py)
                return self.quantity(token)
            return Number(float(token.text), token.offset, len(token.text))
        if token.kind == "name":
            self.advance()
            if self.token.text == "(" and self.token.kind == "op":
                return self.call(token)
            if token.text in CONSTANTS:
                return Constant(token.text, token.offset, len(token.text))
            return Name(token.text, token.offset, len(token.text))
        if self.accept("(") is not None:
            self.enter(token)
            node = self.comparison()
            self.expect(")", "')'")
            self.depth -= 1
            return node
        raise self.unexpected("expected a number, a name or '('")

    def quantity(self, number: Token) -> Number:
        """A number with its unit (the tokens from here): its SI value and dimension."""
        try:
            factor, dimension, self.pos = units.read(self.tokens, self.pos)
        except units.UnitError as error:
            raise ExpressionSyntaxError(error.message, error.offset, error.length,
                                        error.hint) from None
        end = self.tokens[self.pos - 1]
        return Number(float(number.text) * factor, number.offset,
                      end.offset + len(end.text) - number.offset, dimension)

    def call(self, name: Token) -> Call:
        self.enter(name)
        self.expect("(", "'('")
        args = [self.comparison()]
        while self.accept(",") is not None:
            args.append(self.comparison())
        close = self.expect(")", "',' or ')'")
        self.depth -= 1
        node = Call(name.text, tuple(args), name.offset, close.offset + 1 - name.offset)
        _check_call(node)
        return node


def _check_call(node: Call) -> None:
    if node.function not in FUNCTIONS:
        hint = did_you_mean(node.function, FUNCTIONS) or f"functions: {', '.join(FUNCTIONS)}"
        raise ExpressionFunctionError(
            f"unknown function '{node.function}'", node.offset, len(node.function), hint
        )
    arity = FUNCTIONS[node.function][0]
    if len(node.args) != arity:
        plural = "s" if arity != 1 else ""
        raise ExpressionFunctionError(
            f"'{node.function}' takes {arity} argument{plural}, got {len(node.args)}",
            node.offset,
            node.length,
        )


def parse(text: str) -> Expr:
    """Parse `text`; raises ExpressionSyntaxError (E200) or ExpressionFunctionError (E203)."""
    return Expr(text, _Parser(text).parse())


def from_number(value: float) -> Expr:
    """The expression of a plain number (a YAML int or float)."""
    return Expr(repr(value), Number(float(value), 0, len(repr(value))))
