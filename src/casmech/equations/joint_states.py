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

Every rate is the time derivative by AD (x.rate), as coordinates.py's. A spherical joint's
seven states are one traced step (core.traced_steps) evaluated once per joint and state x
(`spherical_states`; GROUPS names it for readers that keep a joint's values together), or once
for many joints, mapped (`spherical_states_of`).
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from casmech.core import euler
from casmech.core.quaternions import conjugate, product
from casmech.core.traced_steps import traced
from casmech.core.values import constant
from casmech.equations import body
from casmech.model.ir import GROUND_INDEX


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


def _spherical(p_i, p_j, p_i_dot, p_j_dot, q_i, q_j):
    """(e, w): body_j's joint frame relative to body_i's as Euler parameters (4 x 1) and
    body_j's angular velocity relative to body_i's in body_i's joint frame (3 x 1)."""
    frame_i, frame_j = product(p_i, q_i), product(p_j, q_j)
    omega_i, omega_j = (body.global_rates(p, p_dot)[0]
                        for p, p_dot in ((p_i, p_i_dot), (p_j, p_j_dot)))
    return (product(conjugate(frame_i), frame_j),
            euler.rotation(frame_i).T @ (omega_j - omega_i))


SPHERICAL = traced(_spherical)  # per joint
SPHERICAL_STATES = ("e0", "e1", "e2", "e3", "wx", "wy", "wz")


def spherical_states(geometry, x) -> dict:
    """A spherical joint's e0 .. e3, wx, wy, wz at x."""
    i, j = geometry.body_i, geometry.body_j
    e, w = SPHERICAL(x.p(i), x.p(j), x.p(i, x.q_dot), x.p(j, x.q_dot),
                     constant(geometry.axes["q_i"]), constant(geometry.axes["q_j"]))
    return dict(zip(SPHERICAL_STATES, ca.vertsplit(ca.vertcat(e, w)), strict=True))


@functools.cache
def _spherical_step() -> ca.Function:
    """_spherical as one Function of dense 4 x 1 arguments (the graph SPHERICAL traces for
    them)."""
    symbols = [ca.SX.sym(f"a{k}", 4) for k in range(6)]
    return ca.Function("step_spherical", symbols, list(_spherical(*symbols)))


def spherical_states_of(geometries, x) -> dict:
    """spherical_states of several joints at x (joint name -> its states): the spherical step
    mapped over the joints in one call, each joint's values the expressions a call of its own
    gives."""
    if not geometries:
        return {}
    nb = x.n_bodies
    columns = [nb if k == GROUND_INDEX else k for g in geometries for k in (g.body_i, g.body_j)]
    # ground's p, and its rate as x.p reads it: zero
    pose, rate = (ca.horzcat(ca.reshape(v[3 * nb:], 4, nb), ground) for v, ground in (
        (x.q, x.q_ground[3:7]), (x.q_dot, ca.SX.zeros(4, 1))))
    given = [[g.axes[key] for g in geometries] for key in ("q_i", "q_j")]
    frames = [ca.horzcat(*map(constant, values)) if any(isinstance(v, ca.SX) for v in values)
              else ca.DM(np.column_stack(values)) for values in given]
    e, w = _spherical_step().map(len(geometries))(
        pose[:, columns[0::2]], pose[:, columns[1::2]], rate[:, columns[0::2]],
        rate[:, columns[1::2]], *frames)
    values = ca.vertsplit(ca.vec(ca.vertcat(e, w)))
    n = len(SPHERICAL_STATES)
    return {g.name: dict(zip(SPHERICAL_STATES, values[n * k:n * (k + 1)], strict=True))
            for k, g in enumerate(geometries)}


def relative_rotation(geometry, x):
    """Euler parameters of body_j's joint frame relative to body_i's (4 x 1)."""
    return ca.vertcat(*(spherical_states(geometry, x)[name] for name in SPHERICAL_STATES[:4]))


def relative_angular_velocity(geometry, x):
    """Body_j's angular velocity relative to body_i's, in body_i's joint frame (3 x 1)."""
    return ca.vertcat(*(spherical_states(geometry, x)[name] for name in SPHERICAL_STATES[4:]))


def _rate(coordinate):
    return lambda geometry, x: x.rate(coordinate(geometry, x))


# attribute of casmech.core.states.JOINT_STATES -> value(joint geometry, x)
VALUES = {
    "angle_i": angle_i,
    "angle_i_dot": _rate(angle_i),
    "angle_j": angle_j,
    "angle_j_dot": _rate(angle_j),
    **{name: (lambda geometry, x, name=name: spherical_states(geometry, x)[name])
       for name in SPHERICAL_STATES},
}
# attribute -> the function (geometry, x) -> {attribute: value} that gives it with others
GROUPS = dict.fromkeys(SPHERICAL_STATES, spherical_states)
