"""method auto's probe (runtime.stiffness.decay_rate) against the closed-form eigenvalues of
linear ODEs: a damped oscillator's -zeta omega +- i omega sqrt(1 - zeta^2) and a first-order
lag's -1/tau."""

from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from casmech.runtime.stiffness import decay_rate


def _system(matrix: np.ndarray) -> SimpleNamespace:
    """A stand-in for a JointSystem whose tree ODE is x' = matrix x."""
    t, x = ca.SX.sym("t"), ca.SX.sym("x", matrix.shape[0])
    ode = ca.Function("joint_ode", [t, x], [ca.DM(matrix) @ x], ["t", "x"], ["ode"])
    return SimpleNamespace(dynamics=ode, given_jacobian=None)


def _oscillator(omega: float, zeta: float) -> np.ndarray:
    return np.array([[0.0, 1.0], [-omega**2, -2 * zeta * omega]])


@pytest.mark.parametrize(("omega", "zeta", "tau"), [(1e3, 0.05, 0.1), (1e3, 0.9, 1.0),
                                                     (10.0, 0.5, 1e-3)])
def test_the_fastest_decay_is_the_largest_minus_real_part(omega, zeta, tau):
    matrix = np.zeros((3, 3))
    matrix[:2, :2] = _oscillator(omega, zeta)
    matrix[2, 2] = -1 / tau
    expected = max(zeta * omega, 1 / tau)  # the modes' decay rates, in closed form
    # eigenvalues of a 3 x 3 matrix with entries up to 1e6: roundoff well below 1e-9 relative
    np.testing.assert_allclose(decay_rate(_system(matrix), 0.0, np.ones(3)), expected,
                               rtol=1e-9, atol=0)


def test_a_fast_undamped_oscillation_does_not_count_and_growth_is_zero():
    """An undamped 1e4 rad/s spring has no decay (its spectral radius would be 1e4); a growing
    mode alone gives 0, not a negative rate."""
    # a purely imaginary pair: its real parts are roundoff of the 1e8 entry (~1e-8 of 1e4)
    assert decay_rate(_system(_oscillator(1e4, 0.0)), 0.0, np.ones(2)) == pytest.approx(
        0.0, abs=1e-4)
    assert decay_rate(_system(np.array([[2.0]])), 0.0, np.ones(1)) == 0.0


def test_a_jacobian_that_is_not_finite_gives_none():
    t, x = ca.SX.sym("t"), ca.SX.sym("x")
    ode = ca.Function("joint_ode", [t, x], [ca.sqrt(x)], ["t", "x"], ["ode"])
    assert decay_rate(SimpleNamespace(dynamics=ode, given_jacobian=None), 0.0,
                      np.zeros(1)) is None
