"""The state a user force law reads: joint coordinates and body positions and velocities.

The names are casmech.geometry.states'; here is how each is computed from the coordinates `x`:

- `<joint>.angle`, `<joint>.angle_dot` (joint types whose casmech.joint_types entry has the
  coordinate "angle": revolute, cylindrical): rotation of body_j about the joint axis, measured
  from the pose written in the file like a driver angle; the formula is the rsda's
  (`forces.springs.joint_angle`, atan2 of the joint frames, so in (-pi, pi]); the rate is its time
  derivative by AD.
- `<joint>.displacement`, `<joint>.displacement_dot` ("displacement": translational,
  cylindrical): slide of body_j's copy of the joint point along the axis carried by body_i, 0
  at the pose in the file.
- `<body>.x .y .z .vx .vy .vz .wx .wy .wz`: what the results columns of that name hold (CM
  position and velocity, angular velocity, all global).

Semantic checks use the names (`schema/force_laws.py`); lowering binds the ones an expression
uses (`bind`), and `eom` evaluates them (`values`) beside `t`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, replace
from typing import Any

from casmech.compiler import body, eom
from casmech.forces.springs import joint_angle
from casmech.geometry.states import split
from casmech.geometry.values import constant
from casmech.joint_types import attributes
from casmech.schema.resolved import ScalarFunction


def displacement(geometry, x):
    """Slide of body_j's joint point along the axis on body_i, from body_i's joint point."""
    axis = x.frame(geometry.body_i).A @ constant(geometry.axes["w_i"])
    gap = eom.point(x, geometry.body_j, geometry.points["s_j"]) - eom.point(
        x, geometry.body_i, geometry.points["s_i"])
    return axis.T @ gap


def _angle(geometry, x):
    return joint_angle(geometry, x)


def _rate(coordinate: Callable) -> Callable:
    return lambda geometry, x: eom.rate(coordinate(geometry, x), x)


# attribute of states.JOINT_COORDINATES -> value(joint geometry, x)
JOINT_VALUES: dict[str, Callable] = {
    "angle": _angle,
    "angle_dot": _rate(_angle),
    "displacement": displacement,
    "displacement_dot": _rate(displacement),
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


def has_coordinates(joint_type: str) -> bool:
    """Whether a joint of this type has a coordinate a force law may read."""
    return bool(attributes(joint_type))


@dataclass(frozen=True)
class BoundFunction(ScalarFunction):
    """A force law with the state it reads bound: name -> (kind, attribute, joint or body)."""

    states: Mapping[str, tuple[str, str, Any]] = field(default_factory=dict)


def _binding(name: str, bodies: Mapping[str, int], joints: Mapping[str, Any]):
    owner, attribute = split(name)
    if owner in joints and attribute in JOINT_VALUES:
        return "joint", attribute, joints[owner]
    if owner in bodies and attribute in BODY_VALUES:
        return "body", attribute, bodies[owner]
    return None


def bind_function(function, bodies: Mapping[str, int], joints: Mapping[str, Any]):
    """`function` with the state names it uses bound (unchanged when it uses none), in sorted
    order: the set of names iterates by string hash, which differs between processes, and the
    order is part of the parametric library's structure signature (its cache key)."""
    if function is None:
        return None
    found = {name: _binding(name, bodies, joints) for name in sorted(function.expr.symbols)}
    states = {name: binding for name, binding in found.items() if binding is not None}
    if not states:
        return function
    base = {f.name: getattr(function, f.name) for f in fields(ScalarFunction)}
    return BoundFunction(**base, states=states)


def bind(force, bodies: Mapping[str, int], joints: Mapping[str, Any]):
    """A ForceIR whose actuator and value read the state they name.

    `bodies`: body name -> index; `joints`: joint name -> its coordinate geometry (a ForceIR of
    the joint's bodies with axes u_i, v_i, w_i, u_j and points s_i, s_j: lower.joint_coordinates).
    """
    value = force.value and tuple(bind_function(f, bodies, joints) for f in force.value)
    return replace(force, actuator=bind_function(force.actuator, bodies, joints), value=value)


EVALUATE = {
    "joint": lambda attribute, geometry, x: JOINT_VALUES[attribute](geometry, x),
    "body": lambda attribute, index, x: BODY_VALUES[attribute](x, index),
}


def values(function, x) -> dict[str, Any]:
    """The bound state of a force law as CasADi expressions of x (empty for a plain one)."""
    states = getattr(function, "states", {})
    return {name: EVALUATE[kind](attribute, owner, x)
            for name, (kind, attribute, owner) in states.items()}
