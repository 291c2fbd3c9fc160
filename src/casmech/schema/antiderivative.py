"""Closed-form antiderivatives of expressions of t (speed motors hold their speed exactly).

`integral(expr, constants)` returns an `Expr` of t equal to the integral of `expr` from 0 to t,
built from the expression tree by these rules (c: any subtree without t, parameters included):

- polynomials in t: sums, differences, products and constant multiples or quotients of them,
  powers t**n with n a non-negative integer constant;
- sin, cos, exp of a*t + b (a, b constant, a evaluated != 0);
- step(a*t + b, t0, y0, t1, y1) with constant t0 < t1, y0, y1 (casmech's smooth cubic step);
- sums, differences and constant multiples of the above.

Anything else raises `NoClosedForm` naming the subtree (its offset in the text), so the caller
can say which part has no closed form. The result is an ordinary `Expr` (both backends, bound
parameters stay symbolic for casmech.optimal).
"""

from __future__ import annotations

from casmech.core import traced
from casmech.core.expressions import Binary, Call, Constant, Expr, Name, Number, Unary

T = "t"
MAX_POWER = 12  # t**n expanded for integer 0 <= n <= MAX_POWER


class NoClosedForm(Exception):
    def __init__(self, node, why: str):
        super().__init__(why)
        self.node, self.why = node, why


def _num(value: float) -> Number:
    return Number(float(value), 0, 0)


def _zero(node) -> bool:
    return isinstance(node, Number) and node.value == 0.0


def _bin(op: str, left, right):
    """A Binary node, with the trivial cases x + 0, 0 + x, x - 0, 0 * x, x * 0 folded."""
    if op in "+-" and _zero(right):
        return left
    if op == "+" and _zero(left):
        return right
    if op == "*" and (_zero(left) or _zero(right)):
        return _num(0)
    return Binary(op, left, right, 0)


def _call(name: str, *args) -> Call:
    return Call(name, tuple(args), 0, 0)


def has_t(node) -> bool:
    return any(name == T for name, _, _ in node.names())


def _value(node, constants) -> float:
    """The value of a subtree without t, for a decision on the form of the integral (the
    integral keeps the subtree itself, so a symbolic parameter stays an expression)."""
    return float(traced.value(node.evaluate(dict(constants), 0)))


# ------------------------------------------------------------------------- polynomials in t
def polynomial(node) -> list | None:
    """Coefficients (subtrees without t, ascending powers) if `node` is a polynomial in t."""
    if not has_t(node):
        return [node]
    if isinstance(node, Name):
        return [_num(0), _num(1)]
    if isinstance(node, Unary):
        inner = polynomial(node.operand)
        return None if inner is None else [Unary(node.op, c, 0) for c in inner]
    if isinstance(node, Binary):
        return POLY_RULES.get(node.op, lambda n: None)(node)
    return None


def _add(node) -> list | None:
    a, b = polynomial(node.left), polynomial(node.right)
    if a is None or b is None:
        return None
    size = max(len(a), len(b))
    a, b = a + [_num(0)] * (size - len(a)), b + [_num(0)] * (size - len(b))
    return [_bin(node.op, x, y) for x, y in zip(a, b, strict=True)]


def _times(a: list, b: list) -> list:
    out = [_num(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] = _bin("+", out[i + j], _bin("*", x, y))
    return out


def _multiply(node) -> list | None:
    a, b = polynomial(node.left), polynomial(node.right)
    return None if a is None or b is None else _times(a, b)


def _divide(node) -> list | None:
    a = polynomial(node.left)
    if a is None or has_t(node.right):
        return None
    return [_bin("/", c, node.right) for c in a]


def _power(node) -> list | None:
    """base ** n for a polynomial base and a constant integer n in 0..MAX_POWER."""
    base, exponent = polynomial(node.left), node.right
    if base is None or not isinstance(exponent, Number):
        return None
    if exponent.value != int(exponent.value) or not 0 <= exponent.value <= MAX_POWER:
        return None
    out = [_num(1)]
    for _ in range(int(exponent.value)):
        out = _times(out, base)
    return out


POLY_RULES = {"+": _add, "-": _add, "*": _multiply, "/": _divide, "**": _power}


def _integrate_polynomial(coefficients) -> object:
    """sum c_k t^(k+1) / (k+1)."""
    total = _num(0)
    for k, c in enumerate(coefficients):
        power = _bin("**", Name(T, 0, 0), _num(k + 1))
        total = _bin("+", total, _bin("/", _bin("*", c, power), _num(k + 1)))
    return total


# --------------------------------------------------------------------- functions of a*t + b
def _linear(node, constants):
    """(a, b) subtrees if `node` is a*t + b with a evaluating to non-zero, else None."""
    coefficients = polynomial(node)
    if coefficients is None or len(coefficients) > 2:
        return None
    if len(coefficients) == 1 or _value(coefficients[1], constants) == 0.0:
        return None
    return coefficients[1], coefficients[0]


def _sin(arg, a):
    return _bin("/", Unary("-", _call("cos", arg), 0), a)


def _cos(arg, a):
    return _bin("/", _call("sin", arg), a)


def _exp(arg, a):
    return _bin("/", _call("exp", arg), a)


def _step(arg, a, x0, h0, x1, h1):
    """Integral of step(x, x0, h0, x1, h1) in x, divided by a (x = a t + b):
    h0 (x - x0) + (h1 - h0) (x1 - x0) (s^3 - s^4 / 2) + (h1 - h0) max(x - x1, 0),
    s = clamp((x - x0) / (x1 - x0), 0, 1)."""
    width, rise = _bin("-", x1, x0), _bin("-", h1, h0)
    s = _call("min", _call("max", _bin("/", _bin("-", arg, x0), width), _num(0)), _num(1))
    shape = _bin("-", _bin("**", s, _num(3)), _bin("/", _bin("**", s, _num(4)), _num(2)))
    total = _bin("+", _bin("*", h0, _bin("-", arg, x0)), _bin("*", _bin("*", rise, width), shape))
    total = _bin("+", total, _bin("*", rise, _call("max", _bin("-", arg, x1), _num(0))))
    return _bin("/", total, a)


LINEAR_ARGUMENT = {"sin": _sin, "cos": _cos, "exp": _exp}


def _constant_argument(node, constants) -> bool:
    """Whether a call's first argument is a*t + b with a = 0 at these parameters."""
    coefficients = polynomial(node.args[0])
    return (coefficients is not None and len(coefficients) == 2
            and _value(coefficients[1], constants) == 0.0
            and not any(has_t(arg) for arg in node.args[1:]))


def _integrate_call(node, constants):
    if node.function in (*LINEAR_ARGUMENT, "step") and _constant_argument(node, constants):
        return _bin("*", node, Name(T, 0, 0))  # constant in time (its t-terms vanish)
    if node.function in LINEAR_ARGUMENT:
        linear = _linear(node.args[0], constants)
        if linear is not None:
            return LINEAR_ARGUMENT[node.function](node.args[0], linear[0])
        raise NoClosedForm(node, f"{node.function}() of something other than a*t + b")
    if node.function == "step":
        linear = _linear(node.args[0], constants)
        rest = node.args[1:]
        if linear is None or any(has_t(arg) for arg in rest):
            raise NoClosedForm(node, "step() needs a*t + b as its first argument and constants "
                                     "for the others")
        if _value(rest[2], constants) <= _value(rest[0], constants):
            raise NoClosedForm(node, "step() needs t1 > t0")
        return _step(node.args[0], linear[0], *rest)
    raise NoClosedForm(node, f"{node.function}() of t")


def antiderivative(node, constants):
    """A subtree whose derivative in t is `node` (raises NoClosedForm)."""
    coefficients = polynomial(node)
    if coefficients is not None:
        return _integrate_polynomial(coefficients)
    if isinstance(node, Unary):
        return Unary(node.op, antiderivative(node.operand, constants), 0)
    if isinstance(node, Binary) and node.op in "+-":
        return _bin(node.op, antiderivative(node.left, constants),
                    antiderivative(node.right, constants))
    if isinstance(node, Binary) and node.op in "*/" and not has_t(node.right):
        return _bin(node.op, antiderivative(node.left, constants), node.right)
    if isinstance(node, Binary) and node.op == "*" and not has_t(node.left):
        return _bin("*", node.left, antiderivative(node.right, constants))
    if isinstance(node, Call):
        return _integrate_call(node, constants)
    raise NoClosedForm(node, "a product, quotient or power of functions of t")


def at_zero(node):
    """`node` with t replaced by 0."""
    if isinstance(node, Name) and node.name == T:
        return _num(0)
    if isinstance(node, Unary):
        return Unary(node.op, at_zero(node.operand), node.offset)
    if isinstance(node, Binary):
        return Binary(node.op, at_zero(node.left), at_zero(node.right), node.offset)
    if isinstance(node, Call):
        return Call(node.function, tuple(at_zero(a) for a in node.args), node.offset, node.length)
    return node


def text(node) -> str:
    """Readable text of a tree (fully parenthesised where it matters)."""
    if isinstance(node, Number):
        return format(node.value, ".17g")
    if isinstance(node, Name | Constant):
        return node.name
    if isinstance(node, Unary):
        return f"{node.op}({text(node.operand)})"
    if isinstance(node, Binary):
        return f"({text(node.left)} {node.op} {text(node.right)})"
    return f"{node.function}({', '.join(text(a) for a in node.args)})"


def integral(expr: Expr, constants) -> Expr:
    """The integral of `expr` from 0 to t, as an Expr (raises NoClosedForm)."""
    primitive = antiderivative(expr.root, constants)
    root = _bin("-", primitive, at_zero(primitive))
    return Expr(text(root), root)
