"""Tree joints of the joint-coordinate formulation: the motion a joint type allows (the
`motion` of its casmech.elements.joint_types entry; `FREE` for a body no tree joint reaches).

A tree joint moves the child's joint frame F_c relative to the parent's F_p by a rotation (a
quaternion of the joint coordinates theta, and the same rotation as a matrix: of cos and sin of
the angles for the types that turn about axes) and a translation (F_c's origin in F_p
coordinates). Its velocities u are theta_dot, except for quaternion coordinates, whose
velocities are the relative angular velocity in F_c (theta_dot = 1/2 G(theta)^T u, the rate
law of Euler parameters); the relative angular velocity in F_c is the type's `spin` (the sum of
its axes' rates, each axis seen in F_c), or u[0:3] for a quaternion joint. Everything else (the
motion subspace, its rate) comes from AD of these maps (formulations/articulated.py).
`coordinates` inverts them numerically, for initial states. `drivers` names the coordinate a
joint driver prescribes: the driver rows of casmech.elements.joint_types measure the same angle
(atan2 of the joint frames, 0 at the file's pose) and the same slide along the axis.

Frames (tree.frames): "axes" uses the joint's triad u, v, w (w the axis; ex, ey, ez when the
type has no axis), the same on both bodies; "cross" (universal) puts the parent's axis on F_p's
x and the child's on F_c's y, so the joint keeps them perpendicular.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import field

import casadi as ca
import numpy as np

from casmech.core import euler, rotations
from casmech.core.quaternions import from_matrix, unit
from casmech.core.records import record


@record
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
    # (names of theta's entries, of u's): the joint's state attributes where an entry is one
    # (results columns `<joint>.<name>`, docs/format.md "Joint states"), other names where
    # it is not; None: from `drivers`, each coordinate kind's value and rate
    # (elements.joint_types.state_names reads both)
    names: tuple[tuple[str, ...], tuple[str, ...]] | None = None
    # theta -> the rotation matrix of F_c in F_p, of cos and sin of the angles (None: the
    # matrix of `rotation`'s quaternion)
    turn: Callable | None = None
    # (theta, u) -> the relative angular velocity in F_c (None: see angular_velocity)
    spin: Callable | None = None

    def matrix(self, theta):
        """The rotation matrix of F_c in F_p."""
        return euler.rotation(self.rotation(theta)) if self.turn is None else self.turn(theta)

    def angular_velocity(self, theta, u):
        """The relative angular velocity in F_c: the type's `spin`, u[0:3] for a quaternion
        joint (by the definition of its velocities), else None (formulations.articulated
        takes it by AD of the quaternion)."""
        if self.spin is not None:
            return self.spin(theta, u)
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


def no_translation(theta):
    return ca.DM.zeros(3, 1)


def slide(theta):
    """F_c's origin moved along F_p's z (the joint axis) by the last coordinate."""
    return ca.vertcat(0, 0, theta[-1])


def about_z(index: int) -> dict:
    """The Motion's turn and spin of a joint turning about F_p's z (the joint axis) by
    coordinate `index`: Rz(theta[index]), and that coordinate's rate about z."""
    return {"turn": lambda theta: rotations.about(2, theta[index]),
            "spin": lambda theta, u: ca.vertcat(0, 0, u[index])}


def universal_turn(theta):
    """Rx(alpha) Ry(beta) of a universal joint's (alpha, beta)."""
    return rotations.about(0, theta[0]) @ rotations.about(1, theta[1])


def universal_spin(theta, u):
    """A universal joint's angular velocity in F_c: alpha's rate about F_p's x, seen through
    Ry(beta), plus beta's about F_c's y."""
    return rotations.about(1, theta[1]).T @ ca.vertcat(u[0], 0, 0) + ca.vertcat(0, u[1], 0)


def universal_angles(r: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(alpha, beta) of R = Rx(alpha) Ry(beta)."""
    return np.array([np.arctan2(r[2, 1], r[1, 1]), np.arctan2(r[0, 2], r[0, 0])])


# a body that no tree joint reaches floats: quaternion, then its origin (F_p: ground's)
# (its states are not results columns: the body's own columns are global, its velocities
# here are in the body's frame)
FREE = Motion(7, 6, lambda th: unit(th[0:4]), lambda th: th[4:7],
              lambda r, d: np.concatenate([from_matrix(r), d]), quaternions=(0,),
              names=(("e0", "e1", "e2", "e3", "x", "y", "z"), ("wx", "wy", "wz", "vx", "vy", "vz")))
