"""Joint limits (stops): a one-sided spring-damper in a joint's coordinate.

The coordinate s is the one effort motors and force laws read (equations/coordinates.py) that
the joint type's entry names as its `limit` (casmech.elements.joint_types): the angle of a revolute
joint, the slide of a translational or cylindrical one, 0 at the file's pose. Outside
[lower, upper] the stop pushes back along s, never pulls:

    f = max(0, k (lower - s) - c s_dot)   where s < lower
    f = min(0, k (upper - s) - c s_dot)   where s > upper,    0 in between,

applied as the generalized force s_q^T f (virtual work, as equations/motors.py applies a motor),
with potential 1/2 k d^2 (d the overshoot). Its force and torque on body_j enter the joint's
reaction columns (equations/forces.py motor_reactions, like a motor's), and the results hold
`<joint>.limit_<effort>` (the kind's effort mode: limit_torque of an angle, limit_force of a
displacement) = f and
`<joint>.limit_gap` = the distance to the nearer bound (negative past it).
"""

from __future__ import annotations

import math

import casadi as ca

from casmech.elements.coordinate_kinds import REGISTRY, View, of_type
from casmech.equations import coordinates, motors
from casmech.model.ir import ForceIR

# ForceIR type of a stop (each kind's `limit`) -> the coordinate it stops; -> results column of f
COORDINATE = of_type("limit")
COLUMN = View(lambda: {kind.limit: kind.column for kind in REGISTRY.values()})


def bounded(bound) -> bool:
    """Whether a stop has this bound: an absent one is an infinity, which stays a number in
    the model data's split (model.parametric); a present one may be an entry of it."""
    return not (isinstance(bound, float) and math.isinf(bound))


def coordinate(limit: ForceIR, x):
    return coordinates.coordinate(COORDINATE[limit.type], limit, x)


def law(limit: ForceIR, x) -> tuple:
    """(s, f, potential) as expressions of q and q_dot."""
    p = limit.params
    s = coordinate(limit, x)
    s_dot = x.rate(s)
    k, c, lo, up = p["stiffness"], p["damping"], p["lower"], p["upper"]
    f, potential = 0, 0
    if bounded(lo):
        f += ca.if_else(s < lo, ca.fmax(0, k * (lo - s) - c * s_dot), 0)
        potential += 0.5 * k * ca.fmax(0, lo - s) ** 2
    if bounded(up):
        f += ca.if_else(s > up, ca.fmin(0, k * (up - s) - c * s_dot), 0)
        potential += 0.5 * k * ca.fmax(0, s - up) ** 2
    return s, f, potential


def generalized_force(limit: ForceIR, x):
    """(s_q^T f, potential): a FORCE_ELEMENTS row of equations/eom.py."""
    s, f, potential = law(limit, x)
    return ca.jacobian(s, x.q).T * f, potential


def gap(limit: ForceIR, s):
    """Distance to the nearer bound, negative past it."""
    lo, up = limit.params["lower"], limit.params["upper"]
    if not bounded(lo):
        return up - s
    if not bounded(up):
        return s - lo
    return ca.fmin(s - lo, up - s)


def outputs(limit: ForceIR, x) -> list:
    """The results columns of a stop: f, then the gap."""
    s, f, _ = law(limit, x)
    return [f, gap(limit, s)]


def output_names(limit: ForceIR) -> list[str]:
    return [f"{limit.name}.{COLUMN[limit.type]}", f"{limit.name}.limit_gap"]


def reaction(limit: ForceIR, x, at):
    """(force, torque about `at`) the stop exerts on body j, global
    (equations.forces.motor_reactions)."""
    s, f, _ = law(limit, x)
    return motors.coordinate_reaction(s, f, x, limit.body_j, at)
