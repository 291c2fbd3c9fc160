"""equations.symbols.Coordinates: body and ground entries of q and of its rates."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from casmech.equations.symbols import Coordinates
from casmech.model.ir import GROUND_INDEX


def _value(x: Coordinates, expr) -> np.ndarray:
    """expr at q, q_dot, q_ddot, q_ground all ones (every symbol nonzero)."""
    symbols = [x.t, x.q, x.q_dot, x.q_ddot, x.q_ground]
    function = ca.Function("f", symbols, [expr])
    return np.array(function(0.0, *(np.ones(s.numel()) for s in symbols[1:])).full()).ravel()


@pytest.mark.parametrize("rate", ["q_dot", "q_ddot"])
def test_grounds_entries_of_a_rate_are_zero(rate):
    """Ground is at rest: its velocity and acceleration entries are zero, whatever its
    pseudo-coordinates (not its pose, as q's entries are)."""
    x = Coordinates.create(2)
    vector = getattr(x, rate)
    np.testing.assert_array_equal(_value(x, x.r(GROUND_INDEX, vector)), np.zeros(3))
    np.testing.assert_array_equal(_value(x, x.p(GROUND_INDEX, vector)), np.zeros(4))
    # a body's entries are the vector's: rows 3..5 (r of body 1), 10..13 (p of body 1)
    assert ca.depends_on(x.r(1, vector), vector[3:6])
    assert ca.depends_on(x.p(1, vector), vector[10:14])


def test_grounds_entries_of_q_are_its_pseudo_coordinates():
    x = Coordinates.create(2)
    for expr in (x.r(GROUND_INDEX), x.r(GROUND_INDEX, x.q), x.p(GROUND_INDEX),
                 x.p(GROUND_INDEX, x.q)):
        assert ca.depends_on(expr, x.q_ground) and not ca.depends_on(expr, x.q)
    np.testing.assert_array_equal(_value(x, ca.vertcat(x.r(GROUND_INDEX), x.p(GROUND_INDEX))),
                                  np.ones(7))  # q_ground's entries, ones here
