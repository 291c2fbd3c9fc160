"""The expression language: grammar, both backends, step, errors with offsets, safety."""

import math

import casadi
import numpy as np
import pytest

from casmech.core.expressions import (
    FUNCTIONS,
    ExpressionError,
    ExpressionFunctionError,
    ExpressionNameError,
    ExpressionSyntaxError,
    parse,
)


def numeric(text, backend="numpy", **env):
    return float(parse(text).evaluate(env, backend))


def step_reference(x, x0, h0, x1, h1):
    """Adams STEP, written out from its definition."""
    if x <= x0:
        return h0
    if x >= x1:
        return h1
    a = (x - x0) / (x1 - x0)
    return h0 + (h1 - h0) * a * a * (3 - 2 * a)


# name -> (arguments, reference implementation from the standard library)
REFERENCES = {
    "sin": ((0.7,), math.sin),
    "cos": ((0.7,), math.cos),
    "tan": ((0.7,), math.tan),
    "asin": ((0.3,), math.asin),
    "acos": ((0.3,), math.acos),
    "atan": ((-2.5,), math.atan),
    "sinh": ((0.7,), math.sinh),
    "cosh": ((0.7,), math.cosh),
    "tanh": ((0.7,), math.tanh),
    "exp": ((1.3,), math.exp),
    "log": ((2.5,), math.log),
    "sqrt": ((2.0,), math.sqrt),
    "abs": ((-3.25,), abs),
    "sign": ((-3.25,), lambda x: math.copysign(1.0, x)),
    "floor": ((-2.5,), math.floor),
    "atan2": ((-1.0, -2.0), math.atan2),
    "min": ((2.0, -1.5), min),
    "max": ((2.0, -1.5), max),
    "step": ((0.3, 0.1, 1.0, 0.6, 3.0), step_reference),
    "if": ((-0.5, 2.0, 3.0), lambda c, a, b: a if c != 0 else b),
}

# double-precision evaluation of the same elementary function: a few ulps
RTOL, ATOL = 1e-14, 1e-15


def test_every_function_has_a_reference():
    assert set(REFERENCES) == set(FUNCTIONS)


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_function_numeric(name, backend):
    args, reference = REFERENCES[name]
    names = [f"a{k}" for k in range(len(args))]
    value = numeric(f"{name}({', '.join(names)})", backend, **dict(zip(names, args, strict=True)))
    np.testing.assert_allclose(value, reference(*args), rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
@pytest.mark.parametrize("symbol", [casadi.SX, casadi.MX])
def test_function_symbolic_then_evaluated(name, symbol):
    args, reference = REFERENCES[name]
    symbols = [symbol.sym(f"a{k}") for k in range(len(args))]
    env = {f"a{k}": s for k, s in enumerate(symbols)}
    expr = parse(f"{name}({', '.join(env)})").evaluate(env, "casadi")
    value = casadi.Function("f", symbols, [expr])(*args)
    np.testing.assert_allclose(float(value), reference(*args), rtol=RTOL, atol=ATOL)


@pytest.mark.parametrize(
    ("text", "value"),
    [
        ("1", 1.0),
        ("1.5", 1.5),
        (".5", 0.5),
        ("1.", 1.0),
        ("1e-3", 1e-3),
        ("2.0E+3", 2000.0),
        ("-x**2", -9.0),  # ** binds tighter than unary minus
        ("2**3**2", 512.0),  # ** is right-associative
        ("2**-1", 0.5),
        ("-2**-2", -0.25),
        ("1 - 2 - 3", -4.0),  # left-associative
        ("8 / 4 / 2", 1.0),
        ("2 + 3 * 4", 14.0),
        ("(2 + 3) * 4", 20.0),
        ("--x", 3.0),
        ("+x", 3.0),
        ("2 * pi", 2 * math.pi),
        ("e", math.e),
        ("max(x, 2) ** 2 / 3", 3.0),
    ],
)
def test_grammar_and_precedence(text, value):
    # exact in binary for all but pi and e, which are one rounding away
    np.testing.assert_allclose(numeric(text, x=3.0), value, rtol=1e-15, atol=0)
    np.testing.assert_allclose(numeric(text, "casadi", x=3.0), value, rtol=1e-15, atol=0)


def test_numpy_backend_gives_non_finite_instead_of_raising():
    assert math.isinf(numeric("1 / x", x=0.0))
    assert math.isnan(numeric("sqrt(x)", x=-1.0))
    assert math.isinf(numeric("10 ** 400"))


def test_symbols_and_constants():
    expr = parse("a * sin(omega * t) + pi - e + step(t, 0, 0, 1, a)")
    assert expr.symbols == {"a", "omega", "t"}
    assert not expr.is_constant
    assert parse("2 * pi / 3 + sqrt(e)").is_constant
    assert parse("a + b*a").names_with_offsets() == (("a", 0, 1), ("b", 4, 1), ("a", 6, 1))


def test_missing_name_at_evaluation():
    with pytest.raises(ExpressionNameError) as caught:
        parse("1 + lenght").evaluate({"length": 1.0}, "numpy")
    assert (caught.value.offset, caught.value.length, caught.value.code) == (4, 6, "E201")
    assert caught.value.hint == "did you mean 'length'?"


def test_unknown_backend():
    with pytest.raises(ValueError, match="backend"):
        parse("1").evaluate({}, "torch")


@pytest.mark.parametrize(
    ("text", "offset", "hint"),
    [
        ("x^2", 1, "use '**' for powers"),
        ("1 + * 2", 4, None),
        ("(1 + 2", 6, None),
        ("1 2", 2, None),
        ("sin(1,)", 6, None),
        ("", 0, None),
        ("   ", 0, None),
        ("1.5.3", 3, None),
        ("2x", 1, "a name right after a number is its unit (deg, mm, kN, rpm, ...: "
                  "docs/format.md#units); to multiply, write '*' between them"),
    ],
)
def test_syntax_error_offsets(text, offset, hint):
    with pytest.raises(ExpressionSyntaxError) as caught:
        parse(text)
    assert (caught.value.code, caught.value.offset, caught.value.hint) == ("E200", offset, hint)


@pytest.mark.parametrize(
    ("text", "offset", "length", "hint"),
    [
        ("2 * sqr(x)", 4, 3, "did you mean 'sqrt'?"),
        ("1 + sin(1, 2)", 4, 9, None),
        ("step(t, 0, 1)", 0, 13, None),
        ("x(2)", 0, 1, None),
        ("pi(2)", 0, 2, None),
    ],
)
def test_unknown_function_or_arity(text, offset, length, hint):
    with pytest.raises(ExpressionFunctionError) as caught:
        parse(text)
    error = caught.value
    assert (error.code, error.offset, error.length) == ("E203", offset, length)
    assert hint is None or error.hint == hint


@pytest.mark.parametrize(
    "text",
    [
        "__import__('os')",
        '__import__("os").system("ls")',
        "os.system('ls')",
        "x.__class__",
        "lambda: 1",
        "[1, 2]",
        "1 if x else 2",
        "open('f')",
        "eval('1')",
        "getattr(x, 'y')",
        "x; y",
        "x = 1",
        "1 @ 2",
        "not x",
        "x == 2",
        "x < 2 < 3",
        "x <> 2",
        "x =< 2",
    ],
)
def test_python_is_rejected(text):
    with pytest.raises(ExpressionError):
        parse(text)


@pytest.mark.parametrize(
    ("text", "x", "value"),
    [
        ("x < 2", 1.0, 1.0),
        ("x < 2", 2.0, 0.0),
        ("x <= 2", 2.0, 1.0),
        ("x > 2", 2.0, 0.0),
        ("x >= 2", 2.0, 1.0),
        ("1 + x > 2 * x", 0.5, 1.0),  # comparison binds loosest
        ("if(x > 0, x**2, -x)", -3.0, 3.0),
        ("if(x > 0, x**2, -x)", 3.0, 9.0),
        ("if(x, 1, 2)", 0.0, 2.0),  # any non-zero is true
        ("(x < 1) * 10 + (x >= 1) * 20", 1.0, 20.0),
        ("max(0, 1 - x) ** 1.5", 0.75, 0.125),
        ("min(x, 2) + if(x < 0, 0, 1)", -1.0, -1.0),
    ],
)
def test_comparisons_and_if(text, x, value):
    # exact in binary: comparisons and branches of small dyadic numbers round nowhere
    for backend in ("numpy", "casadi"):
        np.testing.assert_allclose(numeric(text, backend, x=x), value, rtol=0, atol=0)


def test_if_and_comparison_over_arrays_and_symbols():
    x = np.array([-1.0, 0.0, 2.0])
    got = parse("if(x > 0, x, 0) + (x <= 0)").evaluate({"x": x}, "numpy")
    np.testing.assert_array_equal(got, [1.0, 1.0, 2.0])  # exact: small integers
    s = casadi.SX.sym("s")
    f = casadi.Function("f", [s], [parse("if(s > 0, s**2, 0)").evaluate({"s": s}, "casadi")])
    df = casadi.Function("df", [s], [casadi.jacobian(f(s), s)])
    # the branch taken is differentiated: 2 s above 0, 0 below (exact)
    assert (float(df(3.0)), float(df(-3.0))) == (6.0, 0.0)
    # the branch not taken never poisons the value (1/s at 0 is inf)
    g = parse("if(s > 0, 1 / s, 0)")
    h = casadi.Function("h", [s], [g.evaluate({"s": s}, "casadi")])
    assert float(h(0.0)) == 0.0


def test_chained_comparison_error():
    with pytest.raises(ExpressionSyntaxError) as caught:
        parse("0 < x < 1")
    assert (caught.value.offset, caught.value.length) == (6, 1)
    assert "if(" in caught.value.hint


def test_nesting_and_length_limits_are_errors_not_crashes():
    for text in ["(" * 100 + "1" + ")" * 100, "-" * 100 + "1", "+".join(["1"] * 600)]:
        with pytest.raises(ExpressionSyntaxError):
            parse(text)
    assert numeric("+".join(["1"] * 500)) == 500.0


def test_step_levels_and_knots():
    step = parse("step(x, 1, -2, 3, 5)")
    f = casadi.Function("f", [x := casadi.SX.sym("x")], [step.evaluate({"x": x}, "casadi")])
    df = casadi.Function("df", [x], [casadi.jacobian(f(x), x)])
    for x_value, level in [(-5.0, -2.0), (1.0, -2.0), (3.0, 5.0), (7.0, 5.0), (2.0, 1.5)]:
        # exact: the cubic gives h0, h1 and the midpoint exactly
        assert float(f(x_value)) == level
        assert numeric("step(x, 1, -2, 3, 5)", x=x_value) == level
    eps = 1e-7
    for knot in (1.0, 3.0):
        # continuity: the cubic's value moves by O(eps^2) next to a knot
        np.testing.assert_allclose(float(f(knot - eps)), float(f(knot + eps)), rtol=0, atol=1e-12)
        # zero slope on both sides: the cubic's derivative is O(eps) next to a knot
        for side in (knot - eps, knot + eps):
            np.testing.assert_allclose(float(df(side)), 0.0, rtol=0, atol=1e-5)
    # slope at the midpoint: 1.5 (h1 - h0) / (x1 - x0), a closed form; AD is exact to rounding
    np.testing.assert_allclose(float(df(2.0)), 1.5 * 7 / 2, rtol=1e-14, atol=0)
    # numpy and casadi backends agree on a grid (same arithmetic, different libraries)
    grid = np.linspace(0, 4, 41)
    np.testing.assert_allclose(
        [numeric("step(x, 1, -2, 3, 5)", x=v) for v in grid],
        [float(f(v)) for v in grid],
        rtol=1e-14,
        atol=1e-14,
    )
