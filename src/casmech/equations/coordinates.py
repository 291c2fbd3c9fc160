"""The state a user force law reads: joint coordinates and body positions and velocities.

The names are casmech.core.states'; here is how each is computed from the coordinates `x`:

- `<joint>.angle`, `<joint>.angle_dot` (joint types whose casmech.elements.joint_types entry has the
  coordinate "angle": revolute, cylindrical): rotation of body_j about the joint axis, measured
  from the pose written in the file like a driver angle; the formula is the rsda's
  (`forces.springs.joint_angle`, atan2 of the joint frames, so in (-pi, pi]); the rate is its time
  derivative by AD.
- `<joint>.displacement`, `<joint>.displacement_dot` ("displacement": translational,
  cylindrical): slide of body_j's copy of the joint point along the axis carried by body_i, 0
  at the pose in the file.
- `<body>.x .y .z .vx .vy .vz .wx .wy .wz`: what the results columns of that name hold (CM
  position and velocity, angular velocity, all global).
- a universal joint's two angles and a spherical joint's relative rotation and angular
  velocity (casmech.core.states.JOINT_STATES): equations/joint_states.py's formulas, in
  JOINT_VALUES too.

Semantic checks use the names (`schema/force_laws.py`); lowering binds the ones an expression
uses (model/bindings.py), and `eom` evaluates them (`values`) beside `t`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from casmech.core.values import constant
from casmech.elements.couplings import displacement_value
from casmech.elements.forces.springs import joint_angle
from casmech.equations import body, joint_states


def displacement(geometry, x):
    """Slide of body_j's joint point along the axis on body_i, from body_i's joint point
    (elements/couplings.py writes it over the two frames)."""
    return displacement_value(x.frame(geometry.body_i), x.frame(geometry.body_j),
                              constant(geometry.axes["w_i"]), constant(geometry.points["s_i"]),
                              constant(geometry.points["s_j"]))


def _angle(geometry, x):
    return joint_angle(geometry, x)


def _rate(coordinate: Callable) -> Callable:
    return lambda geometry, x: x.rate(coordinate(geometry, x))


# attribute of states.JOINT_COORDINATES -> value(joint geometry, x)
JOINT_VALUES: dict[str, Callable] = {
    "angle": _angle,
    "angle_dot": _rate(_angle),
    "displacement": displacement,
    "displacement_dot": _rate(displacement),
    **joint_states.VALUES,
}


def _omega(x, k):
    return body.global_rates(x.p(k), x.p(k, x.q_dot))[0]


_BODY_VECTORS = {
    "": lambda x, k: x.r(k),
    "v": lambda x, k: x.r(k, x.q_dot),
    "w": _omega,
}
# attribute of states.BODY_STATES -> value(x, body index); meanings of the results columns
BODY_VALUES: dict[str, Callable] = {
    f"{kind}{axis}": (lambda x, k, vector=vector, n=n: vector(x, k)[n])
    for kind, vector in _BODY_VECTORS.items()
    for n, axis in enumerate("xyz")
}


EVALUATE = {
    "joint": lambda attribute, geometry, x: JOINT_VALUES[attribute](geometry, x),
    "body": lambda attribute, index, x: BODY_VALUES[attribute](x, index),
}


def values(function, x) -> dict[str, Any]:
    """The bound state of a force law as CasADi expressions of x (empty for a plain one)."""
    states = getattr(function, "states", {})
    return {name: EVALUATE[kind](attribute, owner, x)
            for name, (kind, attribute, owner) in states.items()}
