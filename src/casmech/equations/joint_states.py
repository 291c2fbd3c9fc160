"""The states of universal and spherical joints (casmech.core.states.JOINT_STATES), beside
equations/coordinates.py's angle and displacement, as expressions of the coordinates `x`.

The geometry is model.bindings.coordinate_geometry's: in its `axes`, a universal joint's
`axis_i_i`, `axis_j_i` (axis_i and axis_j in body_i's frame) and `axis_i_j`, `axis_j_j` (in
body_j's); a spherical joint's `q_i`, `q_j`, the Euler parameters that turn each body's frame
into the joint frame (the global axes at the file's pose): conj(p) of the body's pose in the
file, so that p_k (x) q_k is the joint frame carried by body k.

- universal: x_i = axis_i on body_i, y_i = axis_j's direction at the file's pose on body_i,
  z_i = x_i x y_i; y_j = axis_j on body_j, x_j = axis_i's direction at the file's pose on
  body_j, z_j = x_j x y_j. The relative rotation in the cross frame (x_i, y_i, z_i) is
  Rx(angle_i) Ry(angle_j) (formulations/tree.py's universal motion): angle_i =
  atan2(z_i . y_j, y_i . y_j), the rotation about axis_i, and angle_j = atan2(x_i . z_j,
  x_i . x_j), about axis_j; both 0 at the file's pose, in (-pi, pi].
- spherical: e0 .. e3 = conj(p_i (x) q_i) (x) (p_j (x) q_j), the rotation of body_j's joint
  frame relative to body_i's (continuous in time: e0 may turn negative past a half turn);
  wx, wy, wz = R_F^T (omega_j - omega_i), the relative angular velocity in body_i's joint frame
  R_F = A(p_i (x) q_i).

Every rate is the time derivative by AD (x.rate), as coordinates.py's.
"""

from __future__ import annotations

import casadi as ca

from casmech.core import euler
from casmech.core.quaternions import conjugate, product
from casmech.core.values import constant
from casmech.equations import body


def _direction(x, k: int, vector):
    """A body-fixed direction (body k's frame; ground: global) in the global frame."""
    return x.frame(k).A @ constant(vector)


def _cross_axes(geometry, x):
    axes, i, j = geometry.axes, geometry.body_i, geometry.body_j
    x_i, y_i = _direction(x, i, axes["axis_i_i"]), _direction(x, i, axes["axis_j_i"])
    x_j, y_j = _direction(x, j, axes["axis_i_j"]), _direction(x, j, axes["axis_j_j"])
    return x_i, y_i, ca.cross(x_i, y_i), x_j, y_j, ca.cross(x_j, y_j)


def angle_i(geometry, x):
    x_i, y_i, z_i, _, y_j, _ = _cross_axes(geometry, x)
    return ca.atan2(z_i.T @ y_j, y_i.T @ y_j)


def angle_j(geometry, x):
    x_i, _, _, x_j, _, z_j = _cross_axes(geometry, x)
    return ca.atan2(x_i.T @ z_j, x_i.T @ x_j)


def _joint_frame(geometry, x, side: str):
    """Euler parameters of the joint frame carried by body_i or body_j."""
    k = geometry.body_i if side == "i" else geometry.body_j
    return product(x.p(k), constant(geometry.axes[f"q_{side}"]))


def relative_rotation(geometry, x):
    """Euler parameters of body_j's joint frame relative to body_i's (4 x 1)."""
    return product(conjugate(_joint_frame(geometry, x, "i")), _joint_frame(geometry, x, "j"))


def relative_angular_velocity(geometry, x):
    """Body_j's angular velocity relative to body_i's, in body_i's joint frame (3 x 1)."""
    i, j = geometry.body_i, geometry.body_j
    omega = [body.global_rates(x.p(k), x.p(k, x.q_dot))[0] for k in (i, j)]
    return euler.rotation(_joint_frame(geometry, x, "i")).T @ (omega[1] - omega[0])


def _rate(coordinate):
    return lambda geometry, x: x.rate(coordinate(geometry, x))


# attribute of casmech.core.states.JOINT_STATES -> value(joint geometry, x)
VALUES = {
    "angle_i": angle_i,
    "angle_i_dot": _rate(angle_i),
    "angle_j": angle_j,
    "angle_j_dot": _rate(angle_j),
    **{f"e{n}": (lambda geometry, x, n=n: relative_rotation(geometry, x)[n]) for n in range(4)},
    **{f"w{axis}": (lambda geometry, x, n=n: relative_angular_velocity(geometry, x)[n])
       for n, axis in enumerate("xyz")},
}
