"""Rotation matrices of joint angles, built from cos and sin of the angle itself (their
entries are the functions a hand-written model uses, without the half angles of a
quaternion's).

`about` takes and returns CasADi expressions.
"""

from __future__ import annotations

import casadi as ca


def about(axis: int, angle):
    """The matrix of a rotation by `angle` about coordinate axis 0, 1 or 2 (body -> fixed)."""
    c, s = ca.cos(angle), ca.sin(angle)
    j, k = (axis + 1) % 3, (axis + 2) % 3
    rows = [[0, 0, 0] for _ in range(3)]
    rows[axis][axis] = 1
    rows[j][j], rows[j][k], rows[k][j], rows[k][k] = c, -s, s, c
    return ca.vertcat(*[ca.horzcat(*row) for row in rows])
