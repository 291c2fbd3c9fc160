"""Closed-form integrals of speed expressions (schema/antiderivative.py) against numerical
quadrature (scipy.integrate.quad) at random times, and the cases without a closed form."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import quad

from casmech.core.expressions import parse
from casmech.schema.antiderivative import NoClosedForm, integral

PARAMETERS = {"w": 2.5, "a": -0.7, "c": 0.0}

INTEGRABLE = [
    "2*pi",
    "w",
    "3*t**2 - t + 1",
    "(t + 1)*(t - 2)**3 / 4",
    "-(t*(a - t))**2",
    "t/w + w*t**4",
    "a*sin(w*t + 1) - 3*cos(2*t)/w + exp(-t/2)",
    "sin(c*t + 1)",  # a = 0 at these parameters: a constant
    "cos(-(t - 1)*w)",
    "step(t, 0.5, 0, 1.5, 2)",
    "-2*step(2*t - 1, 0, 1, 1, 3) + 1",
    "step(t, 1, a, 2, w) * 3 / w",
    "5 - 0.1*(t - 2)**2 + exp(a*t)",
]

NOT_INTEGRABLE = {  # text -> offset of the part reported (a call, or a binary's operator)
    "sqrt(t)": 0,
    "t*sin(t)": 1,
    "sin(t**2)": 0,
    "1 / (1 + t)": 2,
    "t**0.5": 1,
    "2 + abs(t - 1)": 4,
    "step(t, 0, 0, t, 1)": 0,
}


@pytest.mark.parametrize("text", INTEGRABLE)
def test_integral_matches_quadrature(text, rng):
    speed = parse(text)
    angle = integral(speed, PARAMETERS)

    def f(s):
        return float(speed.evaluate({**PARAMETERS, "t": s}))

    for t in rng.uniform(-1.0, 4.0, 4):
        expected = quad(f, 0.0, t, epsabs=1e-13, epsrel=1e-13, limit=200, points=[0.5, 1.5])[0]
        got = float(angle.evaluate({**PARAMETERS, "t": t}))
        # closed form vs adaptive quadrature: measured 1.1e-12 relative at worst (120 points)
        np.testing.assert_allclose(got, expected, rtol=1e-10, atol=1e-11)


@pytest.mark.parametrize("text", INTEGRABLE)
def test_integral_is_zero_at_zero_and_its_derivative_is_the_speed(text):
    speed, t = parse(text), ca.SX.sym("t")
    angle = integral(speed, PARAMETERS).evaluate({**PARAMETERS, "t": t}, "casadi")
    rate = ca.Function("rate", [t], [ca.jacobian(angle, t), angle])
    for s in (0.0, 0.3, 1.2, 2.7):
        derivative, value = (float(v) for v in rate(s))
        # AD of the closed form against the expression itself: rounding only (measured 1e-15)
        np.testing.assert_allclose(derivative, speed.evaluate({**PARAMETERS, "t": s}),
                                   rtol=1e-12, atol=1e-12)
        if s == 0.0:
            assert value == 0.0


@pytest.mark.parametrize("text, offset", NOT_INTEGRABLE.items())
def test_no_closed_form_names_the_part(text, offset):
    with pytest.raises(NoClosedForm) as error:
        integral(parse(text), PARAMETERS)
    assert error.value.node.offset == offset
    assert error.value.why
