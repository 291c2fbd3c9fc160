"""Tree joints of the joint-coordinate formulation: one entry per joint type.

A tree joint moves the child's joint frame F_c relative to the parent's F_p by a rotation (a
quaternion of the joint coordinates theta) and a translation (F_c's origin in F_p
coordinates). Its velocities u are theta_dot, except for quaternion coordinates, whose
velocities are the relative angular velocity in F_c (theta_dot = 1/2 G(theta)^T u, the rate
law of Euler parameters). Everything else (the motion subspace, its rate) comes from AD of
these two maps (compiler/articulated.py). `coordinates` inverts them numerically, for initial
states. `drivers` names the coordinate a joint driver prescribes: the driver rows of
compiler/joints.py measure the same angle (atan2 of the joint frames, 0 at the file's pose)
and the same slide along the axis.

Frames (tree.frames): "axes" uses the joint's triad u, v, w (w the axis; ex, ey, ez when the
type has no axis), the same on both bodies; "cross" (universal) puts the parent's axis on F_p's
x and the child's on F_c's y, so the joint keeps them perpendicular.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from casmech.compiler import euler

IDENTITY = ca.DM([1.0, 0.0, 0.0, 0.0])
# the relative angular velocity (in F_c) of a joint whose rotation is one quaternion block:
# its velocities u[0:3] by definition (their rate law is theta_dot = 1/2 G^T u)


@dataclass(frozen=True)
class Motion:
    """The motion a tree joint allows (module docstring)."""

    n_q: int
    n_v: int
    rotation: Callable  # theta -> quaternion of F_c in F_p (4x1, unit on unit theta)
    translation: Callable  # theta -> F_c's origin in F_p coordinates (3x1)
    coordinates: Callable[[np.ndarray, np.ndarray], np.ndarray]  # (R, d) -> theta
    quaternions: tuple[int, ...] = ()  # starts of quaternion blocks in theta
    drivers: Mapping[str, int] = field(default_factory=dict)  # driver -> coordinate index
    frame: str = "axes"

    def angular_velocity(self, theta, u):
        """The relative angular velocity in F_c: u[0:3] for a quaternion joint (by the
        definition of its velocities), else None (compiler.articulated takes it by AD)."""
        return u[0:3] if self.quaternions == (0,) else None

    def rates(self, theta, u):
        """theta_dot from (theta, u)."""
        if not self.quaternions:
            return u
        parts, k, j = [], 0, 0
        for start in self.quaternions:
            parts += [u[j:j + start - k]]
            j += start - k
            parts += [0.5 * euler.g_matrix(theta[start:start + 4]).T @ u[j:j + 3]]
            k, j = start + 4, j + 3
        parts += [u[j:]]
        return ca.vertcat(*parts)


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
    """Unit quaternion (e0 >= 0) of a rotation matrix (Shepperd's method)."""
    r = np.asarray(rotation, float)
    trace = np.trace(r)
    candidates = [trace, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(candidates))
    q = np.zeros(4)
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
    return q if q[0] >= 0 else -q


def _angle(r: np.ndarray, axis: int) -> float:
    """Rotation angle of a rotation about coordinate axis `axis`."""
    j, m = (axis + 1) % 3, (axis + 2) % 3
    return float(np.arctan2(r[m, j], r[j, j]))


def _zero(theta):
    return ca.DM.zeros(3, 1)


def _slide(theta):
    return ca.vertcat(0, 0, theta[-1])


def _universal_angles(r: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(alpha, beta) of R = Rx(alpha) Ry(beta)."""
    return np.array([np.arctan2(r[2, 1], r[1, 1]), np.arctan2(r[0, 2], r[0, 0])])


MOTIONS: dict[str, Motion] = {
    "revolute": Motion(1, 1, lambda th: about(2, th[0]), _zero,
                       lambda r, d: np.array([_angle(r, 2)]), drivers={"angle": 0}),
    "translational": Motion(1, 1, lambda th: IDENTITY, _slide,
                            lambda r, d: np.array([d[2]]), drivers={"displacement": 0}),
    "cylindrical": Motion(2, 2, lambda th: about(2, th[0]), _slide,
                          lambda r, d: np.array([_angle(r, 2), d[2]]),
                          drivers={"angle": 0, "displacement": 1}),
    "spherical": Motion(4, 3, lambda th: unit(th[0:4]), _zero,
                        lambda r, d: from_matrix(r), quaternions=(0,)),
    "universal": Motion(2, 2, lambda th: product(about(0, th[0]), about(1, th[1])), _zero,
                        _universal_angles, frame="cross"),
    "planar": Motion(3, 3, lambda th: about(2, th[2]), lambda th: ca.vertcat(th[0], th[1], 0),
                     lambda r, d: np.array([d[0], d[1], _angle(r, 2)])),
    "fixed": Motion(0, 0, lambda th: IDENTITY, _zero, lambda r, d: np.zeros(0)),
    # a body that no tree joint reaches floats: quaternion, then its origin (F_p: ground's)
    "free": Motion(7, 6, lambda th: unit(th[0:4]), lambda th: th[4:7],
                   lambda r, d: np.concatenate([from_matrix(r), d]), quaternions=(0,)),
}
