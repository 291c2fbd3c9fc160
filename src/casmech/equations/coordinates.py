"""The state a user force law reads: joint coordinates and body positions and velocities.

The names are casmech.core.states'; here is how each is computed from the coordinates `x`:

- `<joint>.<kind>`, `<joint>.<kind>_dot` for each coordinate kind its joint type has
  (casmech.elements.coordinate_kinds: `angle`, the rotation of body_j about the joint axis
  from the pose written in the file, like a driver angle, atan2 of the joint frames, so in
  (-pi, pi]; `displacement`, the slide of body_j's copy of the joint point along the axis
  carried by body_i, 0 at the pose in the file): the kind's measure over the joint's two
  frames; the rate is its time derivative by AD.
- `<body>.x .y .z .vx .vy .vz .wx .wy .wz`: what the results columns of that name hold (CM
  position and velocity, angular velocity, all global).
- a universal joint's two angles and a spherical joint's relative rotation and angular
  velocity (casmech.core.states.JOINT_STATES): equations/joint_states.py's formulas, in
  JOINT_VALUES too.

Semantic checks use the names (`schema/force_laws.py`); lowering binds the ones an expression
uses (model/bindings.py), and `eom` evaluates them (`values`) beside `t`.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from typing import Any

from casmech.core.values import constant
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.equations import body, joint_states


def coordinate(kind: str, geometry, x):
    """The value of a joint's coordinate of this kind: its measure over the joint's frames and
    the geometry's vectors (lower.joint_coordinates: axes u_i, v_i, w_i, u_j, points s_i, s_j)."""
    vectors = {**geometry.axes, **geometry.points}
    return KINDS[kind].value(x.frame(geometry.body_i), x.frame(geometry.body_j),
                             {key: constant(vectors[key]) for key in KINDS[kind].vectors})


class _JointValues(Mapping):
    """attribute of states.JOINT_COORDINATES (a registered kind's value or rate) or of
    joint_states.VALUES -> value(joint geometry, x)."""

    def __getitem__(self, attribute: str) -> Callable:
        for name, kind in KINDS.items():
            if attribute == kind.name:
                return lambda geometry, x: coordinate(name, geometry, x)
            if attribute == kind.rate:
                return lambda geometry, x: x.rate(coordinate(name, geometry, x))
        return joint_states.VALUES[attribute]

    def __iter__(self) -> Iterator[str]:
        yield from (attribute for kind in KINDS.values() for attribute in kind.attributes)
        yield from joint_states.VALUES

    def __len__(self) -> int:
        return sum(1 for _ in self)


JOINT_VALUES: Mapping[str, Callable] = _JointValues()


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
