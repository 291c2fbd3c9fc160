"""Effort motors (torque/force mode): a generalized force pair on a joint's two bodies.

Position and speed motors are drivers (rows of phi, schema/motors.py); an effort motor removes
no DOF. It is lowered like an rsda (revolute/cylindrical rotation) or a force along the axis of a
translational/cylindrical joint, and applies +value along the joint's coordinate:

- torque: angle = atan2(v_i . u_j, u_i . u_j) (the rotation of body j about the axis, from the
  file's pose, in (-pi, pi] like rsda and the angle driver), generalized force angle_q^T T;
- force: displacement = w_i . d_ij (the slide of body j's joint point along the axis fixed in
  body i), generalized force displacement_q^T F.

Virtual work gives both: T delta(angle) = (angle_q^T T) delta q. Their force and torque on body j
also enter the joint's reaction columns (the results contract: a driven joint's reaction includes
its actuation), via `reaction`.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

from casmech.core import euler
from casmech.elements.forces.terms import Input
from casmech.equations.coordinates import JOINT_VALUES
from casmech.model.ir import ForceIR

VARIABLES = {"motor_torque": ("angle", "angle_dot"),
             "motor_force": ("displacement", "displacement_dot")}


# ForceIR type -> the joint coordinate it acts along (equations/coordinates.py)
COORDINATE = {"motor_torque": JOINT_VALUES["angle"], "motor_force": JOINT_VALUES["displacement"]}


def coordinate_and_value(motor: ForceIR, x):
    """(the joint coordinate, the motor's torque or force) as expressions of t, q, q_dot."""
    value = COORDINATE[motor.type](motor, x)
    rate = x.rate(value)
    names = VARIABLES[motor.type]
    return value, motor.actuator.casadi(t=x.t, **{names[0]: value, names[1]: rate})


def generalized_force(motor: ForceIR, x):
    """(coordinate_q^T value, no potential): a FORCE_ELEMENTS row of equations/eom.py."""
    coordinate, value = coordinate_and_value(motor, x)
    return ca.jacobian(coordinate, x.q).T * value, 0.0


def reaction(motor: ForceIR, x, at):
    """(force, torque about `at`) the motor exerts on body j, global, as functions of
    (t, q, q_dot): a motor law may read the joint rate, so `reactions` takes q_dot."""
    coordinate, value = coordinate_and_value(motor, x)
    return coordinate_reaction(coordinate, value, x, motor.body_j, at)


def coordinate_reaction(coordinate, value, x, b: int, at):
    """(force, torque about `at`) on body b of a generalized force `value` along a joint
    coordinate (coordinate_q^T value, the part acting on body b's coordinates)."""
    p = x.p(b)
    force = ca.jacobian(coordinate, x.r(b)).T * value
    n_bar = 0.5 * euler.g_matrix(p) @ ca.jacobian(coordinate, p).T * value
    torque = euler.rotation(p) @ n_bar + ca.cross(x.r(b) - at, force)
    return force, torque


FORCE_ELEMENTS = {"motor_torque": generalized_force, "motor_force": generalized_force}


def _input_law(motor: ForceIR, u) -> ForceIR:
    return replace(motor, actuator=Input(u[0]))


# linearization inputs (equations/eom.INPUT_KINDS): suffixes, the motor with its law the input
INPUTS = {"motor_torque": (("torque",), _input_law), "motor_force": (("force",), _input_law)}
