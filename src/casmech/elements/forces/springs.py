"""The spring-damper-actuators: tsda (along the distance of two points) and rsda (about a
revolute or cylindrical joint's axis): checks, lowering, law, kernel (their YAML classes:
elements/forces/specs.py).

tension = stiffness (coordinate - rest) + damping rate + actuator(t, coordinate, rate, state),
generalized force -coordinate_q^T tension, potential 1/2 stiffness (coordinate - rest)^2
(terms.spring). The actuator may read the state (casmech.core.states).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from casmech.core import traced
from casmech.core.values import constant
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.elements.forces.terms import Input, SpringKind, distance, spring
from casmech.elements.joint_types import having, listed
from casmech.errors import failed

ANGLE = KINDS["angle"]  # an rsda acts along a joint's angle
SPRINGS = {
    "tsda": SpringKind(distance, ("s_i", "s_j"), "free_length", ("length", "length_dot")),
    "rsda": SpringKind(ANGLE.measure, tuple(ANGLE.vectors), "free_angle", ANGLE.attributes),
}


# ---------------------------------------------------------------------------- resolution
def coefficients(check, path, given) -> dict[str, float | None]:
    """stiffness and damping; negative ones only with `allow_negative: true` (E103)."""
    values = {key: check.number((*path, key), getattr(given, key))
              for key in ("stiffness", "damping")}
    return {key: non_negative(check, (*path, key), value, given.allow_negative)
            for key, value in values.items()}


def non_negative(check, path, value, allowed: bool):
    """`value` (a number or an array) unless it is negative without `allowed` (then E103,
    None). A negative stiffness or damping feeds energy into the mechanism (an unstable spring,
    a negative resistance), and a negative free length is no length: a sign slip makes them
    as readily as an intent, so the element's `allow_negative: true` says they are meant."""
    values = np.atleast_1d(value) if value is not None else np.zeros(0)
    if allowed or not np.any(values < 0):
        return value
    key = path[-1].replace("_", " ")
    check.error("E103", path, f"{key} must not be negative", got=", ".join(f"{v:g}"
                                                                          for v in values),
                hint="write `allow_negative: true` on the element if it is meant (a negative "
                     "stiffness or damping feeds energy into the mechanism)")
    return None


def resolve_tsda(check, path, given) -> dict[str, Any] | None:
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    at = {key: check.numbers((*path, key), getattr(given, key)) for key in ("at_i", "at_j")}
    if not bodies_ok or failed(at.values()):
        return None
    length = traced.scalar(np.linalg.norm(at["at_j"] - at["at_i"]))
    free = (
        length
        if given.free_length is None
        else non_negative(check, (*path, "free_length"),
                          check.number((*path, "free_length"), given.free_length),
                          given.allow_negative)
    )
    at_zero = {"t": 0.0, "length": length, "length_dot": 0.0}
    return dict(
        body_i=given.body_i,
        body_j=given.body_j,
        vectors=at,
        free_length=free,
        **coefficients(check, path, given),
        actuator=check.function((*path, "actuator"), given.actuator, at_zero),
    )


def resolve_rsda(check, path, given) -> dict[str, Any] | None:
    joint = (*path, "joint")
    if not check.reference(joint, given.joint, list(check.joint_types), "joint"):
        return None
    if check.joint_types[given.joint] not in having("angle"):
        check.error(
            "E103",
            joint,
            f"an rsda acts about the axis of a {listed(having('angle'), 'or')} joint",
            got=f"'{given.joint}' is {check.joint_types[given.joint]}",
        )
        return None
    body_i, body_j = check.joint_bodies[given.joint]
    at_zero = {"t": 0.0, "angle": 0.0, "angle_dot": 0.0}
    return dict(
        joint=given.joint,
        body_i=body_i,
        body_j=body_j,
        free_angle=check.number((*path, "free_angle"), given.free_angle),
        **coefficients(check, path, given),
        actuator=check.function((*path, "actuator"), given.actuator, at_zero),
    )


# ------------------------------------------------------------------------------ lowering
def lower_tsda(force, model, poses) -> dict[str, Any]:
    v = force.vectors
    at_i, at_j = traced.asarray(v["at_i"]), traced.asarray(v["at_j"])
    length = force.free_length if force.free_length is not None else np.linalg.norm(at_j - at_i)
    points = {"s_i": poses.local(force.body_i, "P", at_i),
              "s_j": poses.local(force.body_j, "P", at_j)}
    params = {"stiffness": force.stiffness, "damping": force.damping}
    return dict(body_i=poses.index[force.body_i], body_j=poses.index[force.body_j],
                points=points, params=params | {"free_length": traced.scalar(length)},
                actuator=force.actuator)


def lower_rsda(force, model, poses) -> dict[str, Any]:
    joint, frame = poses.joint(force.joint)
    axes = {"u_i": poses.local(joint.body_i, "u", frame["u"]),
            "v_i": poses.local(joint.body_i, "v", frame["v"]),
            "u_j": poses.local(joint.body_j, "u", frame["u"])}
    params = {"stiffness": force.stiffness, "damping": force.damping}
    return dict(body_i=poses.index[joint.body_i], body_j=poses.index[joint.body_j], points={},
                params=params | {"free_angle": force.free_angle}, actuator=force.actuator,
                axes=axes)


# ------------------------------------------------------------------------------- the law
def coordinate(kind: SpringKind, geometry, x):
    """The coordinate a spring of `kind` acts along (an rsda's or a joint's angle)."""
    return kind.coordinate(x.frame(geometry.body_i), x.frame(geometry.body_j),
                           *(constant(v) for v in kind.vector_values(geometry)))


def law(force, x, read) -> tuple:
    """(generalized force, potential) of a tsda or rsda; `read(function, x)`: the state its
    actuator reads."""
    states = read(force.actuator, x) if force.actuator is not None else None
    kind = SPRINGS[force.type]
    return spring(kind, coordinate(kind, force, x), (x.q, x.q_dot, x.t),
                  kind.parameters(force), force.actuator, states)


def joint_angle(geometry, x):
    """Rotation of body j about a joint's axis, as an rsda measures it (u_i, v_i, u_j in the
    geometry's axes; equations/coordinates.py)."""
    return coordinate(SPRINGS["rsda"], geometry, x)


def with_inputs(force, u):
    """Stiffness and damping 0, the actuator the input u[0]."""
    return replace(force, actuator=Input(u[0]),
                   params={**force.params, "stiffness": 0.0, "damping": 0.0})


# -------------------------------------------------------------------------------- kernel
def kernel_data(force) -> np.ndarray:
    """[its vectors, stiffness, damping, rest] (equations/force_kernels.py)."""
    kind = SPRINGS[force.type]
    return np.concatenate([*kind.vector_values(force), kind.parameters(force)])


def kernel(force_type: str, frame, motion, data, value, actuator, frame_name) -> tuple:
    """(generalized over the pair's 14 coordinates, potential) from kernel_data (kernelised
    actuators read no other state)."""
    kind = SPRINGS[force_type]
    n = 3 * len(kind.vectors)
    value_of = kind.coordinate(frame(0), frame(1), *(data[k:k + 3] for k in range(0, n, 3)))
    return spring(kind, value_of, motion, (data[n], data[n + 1], data[n + 2]), actuator)

