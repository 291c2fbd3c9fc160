"""casmech.core.traced: the value of every operation is NumPy's (or math's) on the values,
bit for bit; the expression's derivative by CasADi is the closed form; comparisons follow the
value, equality the function; float() refuses a number that depends on the symbols."""

import math

import casadi as ca
import numpy as np
import pytest

from casmech.core import euler, quaternions, traced
from casmech.elements.forces.contact_spec import hunt_crossley_damping

A, B = ca.SX.sym("a"), ca.SX.sym("b")
SYMBOLS = ca.vertcat(A, B)
AT = [0.7, -1.3]


def seeds():
    return traced.seed(AT[0], A), traced.seed(AT[1], B)


def gradient(x: traced.Traced) -> np.ndarray:
    f = ca.Function("g", [SYMBOLS], [ca.jacobian(x.expr, SYMBOLS)])
    return np.array(f(AT).full()).ravel()


# (operation on (a, b), d/da, d/db) at a = 0.7, b = -1.3
CASES = [
    (lambda a, b: a * b + 2.0 - b / a, lambda a, b: b + b / a**2, lambda a, b: a - 1 / a),
    (lambda a, b: a ** 3 - 2.0 ** b, lambda a, b: 3 * a**2, lambda a, b: -math.log(2) * 2**b),
    (lambda a, b: np.sin(a) * np.cos(b), lambda a, b: math.cos(a) * math.cos(b),
     lambda a, b: -math.sin(a) * math.sin(b)),
    (lambda a, b: np.arctan2(b, a), lambda a, b: -b / (a**2 + b**2),
     lambda a, b: a / (a**2 + b**2)),
    (lambda a, b: np.sqrt(a) + np.exp(b) + np.log(a), lambda a, b: 0.5 / math.sqrt(a) + 1 / a,
     lambda a, b: math.exp(b)),
    (lambda a, b: np.float_power(a, 2.5) + abs(b), lambda a, b: 2.5 * a**1.5, lambda a, b: -1.0),
    (lambda a, b: np.arccos(a) + np.tanh(b), lambda a, b: -1 / math.sqrt(1 - a**2),
     lambda a, b: 1 - math.tanh(b)**2),
    (lambda a, b: np.maximum(a, b) + np.minimum(a, b) * 2.0, lambda a, b: 1.0,
     lambda a, b: 2.0),  # fmax is a, fmin is b at these values
]


@pytest.mark.parametrize("case", range(len(CASES)))
def test_values_and_derivatives(case):
    operation, da, db = CASES[case]
    result = operation(*seeds())
    assert isinstance(result, traced.Traced)
    # the value is the float path's own result, bit for bit
    assert result.value == float(operation(np.float64(AT[0]), np.float64(AT[1])))
    # CasADi's derivative of the expression against the closed form (round-off)
    np.testing.assert_allclose(gradient(result), [da(*AT), db(*AT)], rtol=1e-14, atol=1e-15)


def test_arrays_through_numpy():
    """Object arrays of traced numbers through @, np.cross, np.linalg.norm, a division in
    place, and an euler.py function (traced.numeric): values as on floats, derivatives of the
    closed form of a rotation by a about x applied to (0, b, 1)."""
    a, b = seeds()
    axis = traced.array([1.0, 0.0, 0.0])
    assert axis.dtype == float  # no traced number: a float array, as before
    p = traced.array([traced.cos(a / 2), traced.sin(a / 2) * 1.0, 0.0, 0.0])
    rotation = traced.numeric(euler.rotation, p)
    point = rotation @ traced.array([0.0, b, 1.0])
    want = np.array([0.0, math.cos(AT[0]) * AT[1] - math.sin(AT[0]),
                     math.sin(AT[0]) * AT[1] + math.cos(AT[0])])
    # rotation values from euler.numeric on the values (as the plain path), products: round-off
    np.testing.assert_allclose(traced.value(point), want, rtol=1e-15, atol=1e-15)
    np.testing.assert_array_equal(traced.value(rotation),
                                  euler.numeric(euler.rotation, traced.value(p)))
    jacobian = ca.Function("j", [SYMBOLS], [ca.jacobian(traced.expression(point), SYMBOLS)])
    want_jacobian = [[0, 0], [-math.sin(AT[0]) * AT[1] - math.cos(AT[0]), math.cos(AT[0])],
                     [math.cos(AT[0]) * AT[1] - math.sin(AT[0]), math.sin(AT[0])]]
    # closed form; round-off
    np.testing.assert_allclose(np.array(jacobian(AT).full()), want_jacobian, rtol=1e-14,
                               atol=1e-15)
    u = np.cross(point, axis)
    u /= np.linalg.norm(u)
    assert traced.is_traced(u)
    np.testing.assert_allclose(np.linalg.norm(traced.value(u)), 1.0, rtol=1e-15, atol=0)


def test_quaternion_of_a_traced_matrix():
    """quaternions.from_matrix on a traced rotation: the quaternion the value gives, and the
    derivative of the closed form (cos a/2, sin a/2, 0, 0)."""
    a, _ = seeds()
    p = traced.array([traced.cos(a / 2), traced.sin(a / 2), 0.0, 0.0])
    q = quaternions.from_matrix(traced.numeric(euler.rotation, p))
    np.testing.assert_allclose(traced.value(q), traced.value(p), rtol=1e-15, atol=1e-15)
    jacobian = ca.Function("j", [A], [ca.jacobian(traced.expression(q), A)])
    want = [-math.sin(AT[0] / 2) / 2, math.cos(AT[0] / 2) / 2, 0, 0]
    # closed form; round-off
    np.testing.assert_allclose(np.array(jacobian(AT[0]).full()).ravel(), want, rtol=1e-13,
                               atol=1e-15)


def test_comparisons_equality_and_conversions():
    a, b = seeds()
    assert a > b and b < 0 and a >= 0.7 and not a < 0.7  # on the values
    assert np.argmin(np.abs(traced.array([a, b, 2.0]))) == 0
    zero = traced.Traced(0.0, A * 0 + ca.sin(A) - ca.sin(A) * 1)  # 0 at a, not as a function
    moving = a - 0.7  # 0 at theta0, moves with it
    assert moving != 0 and not moving == 0.0 and bool(moving)  # never a structural zero
    assert traced.Traced(0.0, 0.0) == 0 and float(traced.Traced(2.0, 2.0)) == 2.0
    assert a == a and a != traced.seed(AT[0], B)
    with pytest.raises(traced.NotANumber, match="depends on the symbolic parameters"):
        float(a)
    with pytest.raises(traced.NotANumber):
        np.asarray([a, 1.0], float)
    assert f"{a:.2f}" == "0.70" and zero.value == 0.0
    assert traced.scalar(np.float64(2.5)) == 2.5 and traced.scalar(a) is a


def test_a_root_of_an_implicit_equation():
    """traced.root (Newton's steps on SX from the root): Hunt-Crossley's damping as a function
    of the restitution e, its derivative against central differences of the plain bisection
    (the implicit function's derivative, by CasADi through the unrolled steps)."""
    e = traced.seed(0.8, A)
    damping = hunt_crossley_damping(e)
    assert damping.value == hunt_crossley_damping(0.8)
    h = 1e-4
    fd = (hunt_crossley_damping(0.8 + h) - hunt_crossley_damping(0.8 - h)) / (2 * h)
    got = float(ca.Function("d", [A], [ca.jacobian(damping.expr, A)])(0.8))
    # second-order differences at h = 1e-4 of a smooth root: h^2 truncation ~1e-8, the
    # bisection's round-off 1e-16 / h ~1e-12
    np.testing.assert_allclose(got, fd, rtol=1e-7, atol=0)
    # away from 0.8 the unrolled steps converge to the root there (quadratically)
    moved = float(ca.Function("v", [A], [damping.expr])(0.75))
    np.testing.assert_allclose(moved, hunt_crossley_damping(0.75), rtol=1e-13, atol=0)
