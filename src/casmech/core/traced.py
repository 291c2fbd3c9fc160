"""Traced numbers: a float and the CasADi SX expression it is of chosen parameters theta.

A model loaded with some parameters symbolic (schema.load_model_text(..., symbolic=names))
carries `Traced` numbers wherever a number depends on them: the schema and the lowering run
their ordinary code on them, so the value is what the plain float path computes and the
expression is the same computation on SX, from which CasADi differentiates.

- Arithmetic, and NumPy's ufuncs through `__array_ufunc__` (a traced scalar) or through the
  methods NumPy's object loops call (`sin`, `sqrt`, `arctan2`, ... on object arrays), give
  traced numbers. NumPy object arrays of them go through `@`, `np.cross`, `np.linalg.norm`,
  `np.column_stack`; LAPACK (eigvalsh, det, svd) does not take them: checks run on `value(x)`.
- `<`, `<=`, `>`, `>=` (Python's `min`, `max`, `argmin` with them), `sign`, `floor` and an
  expression's comparisons and `if` follow the value: the branch the code takes at theta0 is
  part of the model's structure. NumPy's `minimum`, `maximum` and `absolute` stay functions
  (CasADi's fmin, fmax, fabs). `==` holds only for the same function of theta (equal values
  and both constant, or the same expression), so a number that is 0 at theta0 but moves with
  theta is never taken for a structural zero.
- `float(x)` of a number that depends on theta raises NotANumber (a TypeError): every place
  that would silently freeze a parameter is found. `value(x)` is the deliberate way to read
  the value (for a check, a count, a setting).

Helpers keep the plain path as it is (float arrays, math functions, no traced number unless
one is given): `asarray`, `array`, `scalar`, `numeric` (an euler.py function evaluated on
numbers or traced numbers), `sin`, `cos`, `root` (a root the plain path found by iteration);
`is_traced`, `value` and `expression` read them.
"""

from __future__ import annotations

import math
import operator

import casadi as ca
import numpy as np

from casmech.core import euler


class NotANumber(TypeError):
    """A number that depends on the symbolic parameters was turned into a float."""


class Traced:
    """A float `value` and the SX scalar `expr` it is of the symbolic parameters."""

    __slots__ = ("value", "expr")
    __array_priority__ = 1000  # ndarray (op) Traced defers to Traced.__array_ufunc__

    def __init__(self, value, expr):
        self.value = float(value)
        self.expr = expr if isinstance(expr, ca.SX) else ca.SX(float(expr))

    @property
    def constant(self) -> bool:
        """Whether the expression does not depend on the symbolic parameters."""
        return self.expr.is_constant()

    # -- conversions
    def __float__(self) -> float:
        if not self.constant:
            raise NotANumber(f"a number that depends on the symbolic parameters ({self.value!r}"
                             f" = {_short(self.expr)}) was turned into a float")
        return self.value

    def __int__(self) -> int:
        return int(float(self))

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    def __repr__(self) -> str:
        return f"Traced({self.value!r}, {_short(self.expr)})"

    # -- comparisons: on the value; equality: the same function of theta
    def __eq__(self, other):
        if isinstance(other, np.ndarray):
            return NotImplemented
        if isinstance(other, Traced):
            if self.value != other.value:
                return False
            return (self.constant and other.constant) or ca.is_equal(self.expr, other.expr, 1)
        return self.value == other and self.constant

    def __ne__(self, other):
        equal = self.__eq__(other)
        return equal if equal is NotImplemented else not equal

    def __hash__(self) -> int:
        return hash(self.value)

    def __bool__(self) -> bool:
        return self != 0

    def __lt__(self, other):
        return _compare(operator.lt, self, other)

    def __le__(self, other):
        return _compare(operator.le, self, other)

    def __gt__(self, other):
        return _compare(operator.gt, self, other)

    def __ge__(self, other):
        return _compare(operator.ge, self, other)

    # -- arithmetic
    def __neg__(self):
        return Traced(-self.value, -self.expr)

    def __pos__(self):
        return self

    def __abs__(self):
        return _call(np.absolute, self)

    def __array_ufunc__(self, ufunc, method, *inputs, out=None, **kwargs):
        if method != "__call__" or kwargs or ufunc not in UFUNCS:
            return NotImplemented
        if any(isinstance(x, np.ndarray) and x.ndim for x in inputs):
            elementwise = np.frompyfunc(lambda *xs: _call(ufunc, *xs), ufunc.nin, 1)
            result = elementwise(*(_boxed(x) for x in inputs))
        else:
            result = _call(ufunc, *inputs)
        if out is None:
            return result
        out[0][...] = result  # in place (u /= norm): a float array refuses traced numbers
        return out[0]


def _boxed(x):
    """x as an array NumPy does not dispatch on (a traced scalar in a 0-d object array)."""
    if isinstance(x, np.ndarray):
        return x
    box = np.empty((), object)
    box[()] = x
    return box


def _short(expr) -> str:
    text = str(expr)
    return text if len(text) <= 80 else text[:77] + "..."


def _compare(op, a, b):
    if isinstance(b, np.ndarray):
        return NotImplemented
    return op(a.value, b.value if isinstance(b, Traced) else b)


def _value(x):
    return x.value if isinstance(x, Traced) else x


def _expr(x):
    return x.expr if isinstance(x, Traced) else float(x)


# ufunc -> the SX operation (None: the result is a function of the value alone, a constant)
UFUNCS = {
    np.add: operator.add, np.subtract: operator.sub, np.multiply: operator.mul,
    np.divide: operator.truediv, np.float_power: operator.pow, np.power: operator.pow,
    np.negative: operator.neg, np.positive: operator.pos, np.absolute: ca.fabs,
    np.sqrt: ca.sqrt, np.square: lambda x: x * x, np.exp: ca.exp, np.log: ca.log,
    np.log1p: ca.log1p, np.expm1: ca.expm1, np.sin: ca.sin, np.cos: ca.cos, np.tan: ca.tan,
    np.arcsin: ca.asin, np.arccos: ca.acos, np.arctan: ca.atan, np.arctan2: ca.atan2,
    np.sinh: ca.sinh, np.cosh: ca.cosh, np.tanh: ca.tanh, np.hypot: lambda a, b: ca.sqrt(
        a * a + b * b), np.minimum: ca.fmin, np.maximum: ca.fmax, np.fmin: ca.fmin,
    np.fmax: ca.fmax,
    np.sign: None, np.floor: None, np.ceil: None, np.rint: None, np.isfinite: None,
    np.isnan: None, np.isinf: None, np.less: None, np.less_equal: None, np.greater: None,
    np.greater_equal: None, np.equal: None, np.not_equal: None,
}
EQUALITY = {np.equal: operator.eq, np.not_equal: operator.ne}


def _call(ufunc, *args):
    """One ufunc on scalars: NumPy's on the values, its SX operation on the expressions."""
    if not any(isinstance(x, Traced) for x in args):
        return ufunc(*args)
    if ufunc in EQUALITY:
        return np.bool_(EQUALITY[ufunc](*args) if isinstance(args[0], Traced) else
                        EQUALITY[ufunc](args[1], args[0]))
    value = ufunc(*(_value(x) for x in args))
    operation = UFUNCS[ufunc]
    if operation is None:
        return value
    return Traced(value, operation(*(_expr(x) for x in args)))


def _binary(ufunc, reflected: bool = False):
    def method(self, other):
        if isinstance(other, np.ndarray) or not _number(other):
            return NotImplemented
        return _call(ufunc, other, self) if reflected else _call(ufunc, self, other)
    return method


def _number(x) -> bool:
    return isinstance(x, (Traced, int, float, np.number)) and not isinstance(x, np.bool_)


for _name, _ufunc in (("add", np.add), ("sub", np.subtract), ("mul", np.multiply),
                      ("truediv", np.divide), ("pow", np.power)):
    setattr(Traced, f"__{_name}__", _binary(_ufunc))
    setattr(Traced, f"__r{_name}__", _binary(_ufunc, reflected=True))
# the methods NumPy's loops over object arrays call
for _ufunc in (np.sqrt, np.exp, np.log, np.log1p, np.expm1, np.sin, np.cos, np.tan, np.arcsin,
               np.arccos, np.arctan, np.sinh, np.cosh, np.tanh, np.sign, np.floor, np.ceil,
               np.rint):
    setattr(Traced, _ufunc.__name__, lambda self, f=_ufunc: _call(f, self))
Traced.arctan2 = lambda self, other: _call(np.arctan2, self, other)
Traced.hypot = lambda self, other: _call(np.hypot, self, other)
Traced.conjugate = lambda self: self


# ------------------------------------------------------------------------------- helpers
def seed(value: float, symbol) -> Traced:
    """A symbolic parameter at its value."""
    return Traced(value, symbol)


def is_object_array(x) -> bool:
    """Whether x is a NumPy array of Python objects (traced numbers, when the lowering made
    it)."""
    return isinstance(x, np.ndarray) and x.dtype.kind == "O"


def is_traced(x) -> bool:
    """Whether `x` (a number or an array) depends on the symbolic parameters."""
    if isinstance(x, Traced):
        return not x.constant
    if is_object_array(x):
        return any(isinstance(v, Traced) and not v.constant for v in x.flat)
    if isinstance(x, (list, tuple)):
        return any(is_traced(v) for v in x)
    return False


def value(x):
    """The value of a number or array; a plain number or float array is returned as it is."""
    if isinstance(x, Traced):
        return x.value
    if is_object_array(x):
        return np.array([_value(v) for v in x.flat], float).reshape(x.shape)
    if isinstance(x, (list, tuple)) and is_traced(x):
        return value(array(x))
    return x


def expression(x):
    """The SX of a number or array (a constant where it does not depend on theta)."""
    if isinstance(x, Traced):
        return x.expr
    if is_object_array(x):
        flat = [_expr(v) for v in x.flat]
        rows, cols = (x.size, 1) if x.ndim < 2 else x.shape
        return ca.reshape(ca.vertcat(*flat), cols, rows).T if x.ndim == 2 else ca.vertcat(*flat)
    return ca.SX(ca.DM(np.asarray(x, float)))


def scalar(x):
    """float(x), unless x depends on theta (then x itself)."""
    return x if isinstance(x, Traced) and not x.constant else float(x)


def _wrap(x):
    return x if isinstance(x, Traced) else Traced(x, float(x))


def array(items) -> np.ndarray:
    """np.array(items); with a traced number among them, an object array of traced numbers
    only (NumPy's object loops call methods that floats do not have)."""
    result = np.array(items)
    if not is_object_array(result):
        return result
    return np.frompyfunc(_wrap, 1, 1)(result).astype(object) if result.ndim else \
        np.array(_wrap(result[()]), dtype=object)


def asarray(x) -> np.ndarray:
    """np.asarray(x, float), or the array of traced numbers when x depends on theta."""
    try:
        return np.asarray(x, float)
    except NotANumber:
        return array(np.asarray(x, object))


def sin(x):
    """math.sin on a float (as the plain path computes it), traced on a traced number."""
    return Traced(math.sin(x.value), ca.sin(x.expr)) if isinstance(x, Traced) else math.sin(x)


def cos(x):
    return Traced(math.cos(x.value), ca.cos(x.expr)) if isinstance(x, Traced) else math.cos(x)


def numeric(function, *args) -> np.ndarray:
    """euler.numeric(function, *args) on numbers; with traced arguments the same values (the
    function evaluated on theirs) and the function of their expressions."""
    if not any(is_traced(a) for a in args):
        return euler.numeric(function, *(value(a) for a in args))
    values = euler.numeric(function, *(value(a) for a in args))
    symbolic = function(*(expression(asarray(a)) for a in args))
    return np.array([Traced(values[k], symbolic[k])
                     for k in np.ndindex(values.shape)], dtype=object).reshape(values.shape)


NEWTON = 8  # Newton steps `root` unrolls from the root at theta0 (quadratic: exact near it)


def root(residual, found: float, *args):
    """The root of residual(x, *args) = 0 that the plain path `found` at the values of `args`,
    as a traced number when `args` are traced: Newton's iteration on SX from `found`, NEWTON
    steps unrolled, so its value is `found` and CasADi differentiates the iteration (at
    theta0 the implicit function's derivative, -residual_args / residual_x)."""
    if not any(is_traced(a) for a in args):
        return found
    x = ca.SX.sym("x")
    inputs = [ca.SX.sym(f"a{k}") for k in range(len(args))]
    f = residual(x, *inputs)
    step = ca.Function("newton", [x, *inputs], [x - f / ca.jacobian(f, x)])
    estimate = ca.SX(found)
    for _ in range(NEWTON):
        estimate = step(estimate, *(_expr(a) for a in args))
    return Traced(found, estimate)
