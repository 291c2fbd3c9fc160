"""Unit quaternions (Euler parameters [e0, e]) as rotations: products, axis rotations,
matrix -> quaternion, and the angle of a rotation about a coordinate axis.

`about`, `product`, `conjugate`, `unit` take and return CasADi expressions; `from_matrix` and
`angle_about` work on numbers.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

IDENTITY = ca.DM([1.0, 0.0, 0.0, 0.0])


def about(axis: int, angle):
    """Quaternion of a rotation by `angle` about coordinate axis 0, 1 or 2."""
    half = angle / 2
    vector = [0, 0, 0]
    vector[axis] = ca.sin(half)
    return ca.vertcat(ca.cos(half), *vector)


def product(a, b):
    """Quaternion product a (x) b: rotation(a) @ rotation(b) = rotation(a (x) b)."""
    a0, av, b0, bv = a[0], a[1:4], b[0], b[1:4]
    return ca.vertcat(a0 * b0 - av.T @ bv, a0 * bv + b0 * av + ca.cross(av, bv))


def conjugate(p):
    """The inverse rotation of a unit quaternion."""
    return ca.vertcat(p[0], -p[1:4])


def unit(p):
    return p / ca.sqrt(p.T @ p)


def from_matrix(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternion (e0 >= 0) of a rotation matrix (Shepperd's method), normalised (so a
    matrix orthonormal to roundoff gives a unit quaternion). An object array of traced numbers
    (core/traced.py) gives one: the branch is the one its values take."""
    r = rotation if isinstance(rotation, np.ndarray) and rotation.dtype.kind == "O" else \
        np.asarray(rotation, float)
    trace = np.trace(r)
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    q = np.zeros(4, r.dtype)
    if k == 0:
        q[0] = 0.5 * np.sqrt(1 + trace)
        q[1:] = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / (4 * q[0])
    else:
        i = k - 1
        j, m = (i + 1) % 3, (i + 2) % 3
        q[1 + i] = 0.5 * np.sqrt(1 + 2 * r[i, i] - trace)
        s = 4 * q[1 + i]
        q[0] = (r[m, j] - r[j, m]) / s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + m] = (r[m, i] + r[i, m]) / s
    q /= np.linalg.norm(q)
    return q if q[0] >= 0 else -q


def angle_about(r: np.ndarray, axis: int) -> float:
    """Rotation angle of a rotation matrix about coordinate axis `axis` (0, 1, 2)."""
    j, m = (axis + 1) % 3, (axis + 2) % 3
    return float(np.arctan2(r[m, j], r[j, j]))
