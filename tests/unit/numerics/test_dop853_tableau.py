"""numerics.dop853_tableau: the copied tables and constants are the installed scipy's (whose
DOP853 stepper runtime.dop853's Python path runs), and the method's order conditions hold."""

import numpy as np
from scipy.integrate import DOP853
from scipy.integrate._ivp import dop853_coefficients as scipys
from scipy.integrate._ivp import rk

from casmech.numerics import dop853_tableau as ours


def test_the_tables_are_scipys():
    for name in ("A", "B", "C", "E3", "E5", "D"):
        np.testing.assert_array_equal(getattr(ours, name), getattr(scipys, name), err_msg=name)
    assert (ours.N_STAGES, ours.N_STAGES_EXTENDED, ours.INTERPOLATOR_POWER) == (
        scipys.N_STAGES, scipys.N_STAGES_EXTENDED, scipys.INTERPOLATOR_POWER)
    assert (ours.SAFETY, ours.MIN_FACTOR, ours.MAX_FACTOR) == (
        rk.SAFETY, rk.MIN_FACTOR, rk.MAX_FACTOR)
    assert ours.ERROR_ORDER == DOP853.error_estimator_order


def test_order_conditions():
    """Quadrature conditions sum b_i c_i^(k-1) = 1/k up to order 8 and row sums c_i = sum_j
    a_ij (independent of scipy: properties of any 8th-order explicit pair)."""
    b, c = ours.B, ours.C[:ours.N_STAGES]
    for k in range(1, 9):
        # the tables carry 30 digits, double precision holds 16: roundoff of the sums
        np.testing.assert_allclose(b @ c ** (k - 1), 1 / k, rtol=1e-13, atol=0, err_msg=k)
    np.testing.assert_allclose(ours.A.sum(axis=1), ours.C, rtol=0, atol=1e-13)
