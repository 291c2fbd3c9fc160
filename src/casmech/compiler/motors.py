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

from casmech.compiler.ir import ForceIR
from casmech.forces.terms import Input
from casmech.geometry import euler
from casmech.geometry.values import constant

# joint motion -> (ForceIR type, axes on body i / j, points on body i / j)
KINDS = {
    "torque": ("motor_torque", {"u_i": ("u", "i"), "v_i": ("v", "i"), "u_j": ("u", "j")}),
    "force": ("motor_force", {"w_i": ("w", "i")}),
}
VARIABLES = {"motor_torque": ("angle", "angle_dot"),
             "motor_force": ("displacement", "displacement_dot")}


def lower(joint, frame, poses) -> list[ForceIR]:
    """The effort motors of one resolved joint (`frame`: its global joint frame at t = 0)."""
    out = []
    for key, function in joint.motor.items():
        kind, axes = KINDS[key]
        body = {"i": joint.body_i, "j": joint.body_j}
        local = {name: poses.local(body[side], quantity, frame[quantity])
                 for name, (quantity, side) in axes.items()}
        points = {"s_i": poses.local(joint.body_i, "P", frame["P"]),
                  "s_j": poses.local(joint.body_j, "P", frame["P"])}
        out.append(ForceIR(joint.name, kind, poses.index[joint.body_i], poses.index[joint.body_j],
                           points, {}, function, axes=local, source=joint.source))
    return out


def _point(x, k: int, s_bar):
    f = x.frame(k)
    return f.r + f.A @ constant(s_bar)


def angle(motor: ForceIR, x):
    ai, aj = x.frame(motor.body_i).A, x.frame(motor.body_j).A
    u_j = aj @ constant(motor.axes["u_j"])
    u_i, v_i = ai @ constant(motor.axes["u_i"]), ai @ constant(motor.axes["v_i"])
    return ca.atan2(v_i.T @ u_j, u_i.T @ u_j)


def displacement(motor: ForceIR, x):
    d = _point(x, motor.body_j, motor.points["s_j"]) - _point(x, motor.body_i, motor.points["s_i"])
    return (x.frame(motor.body_i).A @ constant(motor.axes["w_i"])).T @ d


COORDINATE = {"motor_torque": angle, "motor_force": displacement}


def coordinate_and_value(motor: ForceIR, x):
    """(the joint coordinate, the motor's torque or force) as expressions of t, q, q_dot."""
    value = COORDINATE[motor.type](motor, x)
    rate = ca.jacobian(value, x.q) @ x.q_dot
    names = VARIABLES[motor.type]
    return value, motor.actuator.casadi(t=x.t, **{names[0]: value, names[1]: rate})


def generalized_force(motor: ForceIR, x):
    """(coordinate_q^T value, no potential): a FORCE_ELEMENTS row of compiler/eom.py."""
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


# linearization inputs (compiler/eom.INPUT_KINDS): suffixes, the motor with its law the input
INPUTS = {"motor_torque": (("torque",), _input_law), "motor_force": (("force",), _input_law)}
