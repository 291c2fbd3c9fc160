"""Effort motors (torque/force mode): a generalized force pair on a joint's two bodies.

Position and speed motors are drivers (rows of phi, schema/motors.py); an effort motor removes
no DOF. It applies +value along the coordinate of the kind it belongs to (its ForceIR type is
the kind's `effort`, casmech.elements.coordinate_kinds; equations/coordinates.py measures it):

- torque: along the angle (the rotation of body j about the axis, from the file's pose, in
  (-pi, pi] like rsda and the angle driver), generalized force angle_q^T T;
- force: along the displacement (the slide of body j's joint point along the axis fixed in
  body i), generalized force displacement_q^T F.

Virtual work gives both: T delta(angle) = (angle_q^T T) delta q. Their force and torque on body j
also enter the joint's reaction columns (the results contract: a driven joint's reaction includes
its actuation), via `reaction`.
"""

from __future__ import annotations

from dataclasses import replace

import casadi as ca

from casmech.core import euler
from casmech.elements.coordinate_kinds import BY_TYPE, REGISTRY, View
from casmech.elements.forces.terms import Input
from casmech.equations.coordinates import coordinate
from casmech.model.ir import ForceIR


def coordinate_and_value(motor: ForceIR, x):
    """(the joint coordinate, the motor's torque or force) as expressions of t, q, q_dot."""
    kind = BY_TYPE[motor.type][0]
    value = coordinate(kind.name, motor, x)
    rate = x.rate(value)
    return value, motor.actuator.casadi(t=x.t, **dict(zip(kind.attributes, (value, rate),
                                                           strict=True)))


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


# effort motor ForceIR type (each kind's `effort`) -> its law
FORCE_ELEMENTS = View(lambda: dict.fromkeys((k.effort for k in REGISTRY.values()),
                                            generalized_force))


def _input_law(motor: ForceIR, u) -> ForceIR:
    return replace(motor, actuator=Input(u[0]))


# linearization inputs (equations/eom.INPUT_KINDS): suffixes, the motor with its law the input
INPUTS = View(lambda: {k.effort: ((k.motor[2],), _input_law) for k in REGISTRY.values()})
