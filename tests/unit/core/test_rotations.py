"""Axis rotation matrices (core/rotations.py) against Rodrigues' formula."""

import casadi as ca
import numpy as np
import pytest

from casmech.core import rotations
from tests.helpers.equations import rodrigues


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("angle", [0.0, 0.4, -2.9, np.pi])
def test_about_is_rodrigues(axis, angle):
    expected = rodrigues(np.eye(3)[axis], angle)
    # two closed forms of O(1) entries: roundoff only
    np.testing.assert_allclose(np.array(ca.DM(rotations.about(axis, angle))), expected,
                               rtol=0, atol=1e-15)


def test_about_is_symbolic_in_the_angle():
    angle = ca.SX.sym("angle")
    matrix = ca.Function("about", [angle], [rotations.about(2, angle)])
    # the symbolic matrix evaluated at a number is the numeric one: roundoff only
    np.testing.assert_allclose(np.array(matrix(0.7)), rodrigues([0, 0, 1], 0.7),
                               rtol=0, atol=1e-15)
