"""runtime.stiffness.STABLE_REAL against DOP853's stability function, computed here from the
tableau (R(z) = 1 + z b^T (I - z A)^-1 1 for y' = lambda y, z = h lambda): inside the real-axis
stability interval, where the fastest real mode is damped by about a third a step."""

import numpy as np
from scipy.integrate import DOP853
from scipy.optimize import brentq

from casmech.numerics import dop853_tableau as T
from casmech.runtime.stiffness import STABLE_REAL, stable_step


def _r(z: float) -> float:
    n = T.N_STAGES
    return 1 + z * T.B @ np.linalg.solve(np.eye(n) - z * T.A[:n, :n], np.ones(n))


def test_the_stability_function_is_one_scipy_step():
    for z in (-1.0, -STABLE_REAL, -6.5):
        stepper = DOP853(lambda t, y, z=z: z * y, 0.0, np.array([1.0]), 1.0, first_step=1.0,
                         rtol=1e3, atol=1e3)  # tolerances that accept the first step
        stepper.step()
        # one step of y' = z y from y = 1 over h = 1 is R(z); the tableau's roundoff
        np.testing.assert_allclose(stepper.y[0], _r(z), rtol=1e-12, atol=1e-14)


def test_the_bound_lies_inside_the_real_stability_interval():
    boundary = brentq(lambda x: _r(-x) + 1, 5.0, 7.0)  # R passes -1 there (it falls through 0)
    assert STABLE_REAL < boundary
    # a mode at the bound shrinks (|R| < 1) but by no more than a factor of two a step: a
    # smaller bound would only add steps
    assert 0.5 < abs(_r(-STABLE_REAL)) < 0.8
    assert all(abs(_r(-x)) < 1 for x in np.linspace(0.01, STABLE_REAL, 200))


def test_the_step_scales_with_the_radius():
    np.testing.assert_allclose(stable_step(310.0), STABLE_REAL / 310.0, rtol=1e-15, atol=0)
    assert stable_step(0.0) == np.inf
