"""What the lowering attaches to force elements and joints beyond their geometry: the state a
force law reads, bound to the joint or body it names, and the ForceIR of a joint's effort
motors and stop. The formulas that evaluate them are casmech.equations' (coordinates.py,
motors.py, limits.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import field, fields, replace
from typing import Any

from casmech.core.records import record
from casmech.core.states import BODY_STATES, split
from casmech.elements.coordinate_kinds import BY_MODE
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.elements.joint_types import REGISTRY, attributes
from casmech.model.ir import ForceIR, JointIR
from casmech.schema.resolved import ScalarFunction


def has_coordinates(joint_type: str) -> bool:
    """Whether a joint of this type has a coordinate a force law may read."""
    return bool(attributes(joint_type))


@record
class BoundFunction(ScalarFunction):
    """A force law with the state it reads bound: name -> (kind, attribute, joint or body)."""

    states: Mapping[str, tuple[str, str, Any]] = field(default_factory=dict)


def _binding(name: str, bodies: Mapping[str, int], joints: Mapping[str, Any]):
    owner, attribute = split(name)
    if owner in joints and attribute in attributes(joints[owner].type):
        return "joint", attribute, joints[owner]
    if owner in bodies and attribute in BODY_STATES:
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


def motors(joint, frame, poses) -> list[ForceIR]:
    """The effort motors of one resolved joint (`frame`: its global joint frame at t = 0): of
    each effort mode's coordinate kind, its ForceIR type, the directions its measure reads and
    the joint point on both bodies."""
    out = []
    body = {"i": joint.body_i, "j": joint.body_j}
    points = {"s_i": poses.local(joint.body_i, "P", frame["P"]),
              "s_j": poses.local(joint.body_j, "P", frame["P"])}
    for key, function in joint.motor.items():
        kind = BY_MODE[key][0]
        local = {}
        for name, where in kind.vectors.items():
            quantity, side = where.split("@")
            if quantity != "P":
                local[name] = poses.local(body[side], quantity, frame[quantity])
        out.append(ForceIR(joint.name, kind.effort, poses.index[joint.body_i],
                           poses.index[joint.body_j], points, {}, function, axes=local,
                           source=joint.source))
    return out


# a joint state's geometry beyond coordinates': ForceIR axis key -> JointIR.geometry key
EXTRA_GEOMETRY = {"axis_i_i": "axis_i@i", "axis_j_i": "axis_j@i", "axis_i_j": "axis_i@j",
                  "axis_j_j": "axis_j@j", "q_i": "q@i", "q_j": "q@j"}


def coordinate_geometry(joint: JointIR) -> ForceIR:
    """The geometry equations/coordinates.py and joint_states.py read a joint's states from
    (the joint frame's u, v, w on body_i, u on body_j, the joint point on both; a universal
    joint's axes and a spherical joint's frames as joint_states.py names them), from its
    JointIR frames."""
    g = joint.geometry
    axes = {f"{key}_i": g[f"{key}@i"] for key in "uvw"} | {"u_j": g["u@j"]}
    axes |= {key: g[name] for key, name in EXTRA_GEOMETRY.items() if name in g}
    axes |= {key: g[name] for kind in KINDS.values() for key, name in kind.vectors.items()
             if key not in axes and not name.startswith("P@") and name in g}
    return ForceIR(joint.name, joint.type, joint.body_i, joint.body_j,
                   {"s_i": g["P@i"], "s_j": g["P@j"]}, {}, axes=axes, source=joint.source)


def stop(joint, geometry: ForceIR) -> ForceIR:
    """The stop of a resolved joint with a `limit:` (on the coordinate its joint type's entry
    names); `geometry` is lower.joint_coordinates."""
    kind = KINDS[REGISTRY[joint.type].limit].limit
    return replace(geometry, type=kind, params=dict(joint.limit))


def friction(joint, geometry: ForceIR) -> ForceIR:
    """The friction of a resolved joint with a `friction:` (along the coordinate its type's
    stop acts on): sliding by the rate's sign (`direction` 0) until the runtime sets a mode."""
    kind = KINDS[REGISTRY[joint.type].limit].friction
    return replace(geometry, type=kind,
                   params=dict(joint.friction) | {"direction": 0.0, "stuck": 0.0})
