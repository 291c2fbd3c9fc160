"""Joints and forces: references, vectors, drivers, functions of time."""

from __future__ import annotations

from typing import Any

import numpy as np

from casmech.joint_types import COORDINATES, REGISTRY, having, listed
from casmech.schema import contact, resolved
from casmech.schema.checker import ZERO, Checker, failed
from casmech.schema.loader import Path
from casmech.schema.resolved import ScalarFunction

UNIT_KEYS = frozenset({"axis", "axis_i", "axis_j"})  # normalised
NONZERO_KEYS = frozenset({"axis", "axis_i", "axis_j", "a_i", "a_j", "c"})  # E404 when zero
DRIVERS = tuple(COORDINATES)  # driver keys: the joint coordinates (casmech.joint_types)


def joint(check: Checker, index: int, given) -> resolved.Joint | None:
    path = ("joints", index)
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    check.joint_types[given.name] = given.type
    check.joint_bodies[given.name] = (given.body_i, given.body_j)
    entry = REGISTRY[given.type]
    vectors = {key: joint_vector(check, (*path, key), key, getattr(given, key))
               for key in entry.vectors}
    extra = (
        {"length": distance_length(check, path, given, vectors)}
        if "length" in entry.options else {}
    )
    extra.update(drivers(check, path, given))
    if getattr(given, "cut", False):
        extra["cut"] = True
    if given.reactions is not None:
        extra["reaction_frame"] = given.reactions.frame
    if given.reactions is not None and given.reactions.point is not None:
        extra["reaction_point"] = check.numbers((*path, "reactions", "point"),
                                                given.reactions.point)
    if getattr(given, "limit", None) is not None:
        extra["limit"] = contact.limit(check, (*path, "limit"), given.limit)
    if entry.check is not None and not failed(vectors.values()):
        for code, key, message, details in entry.check(vectors):
            check.error(code, (*path, key), message, **details)
    if hasattr(given, "f"):
        extra["f"] = check.function((*path, "f"), given.f, {"t": 0.0})
    if not bodies_ok or failed([*vectors.values(), *extra.values()]):
        return None
    return resolved.Joint(
        given.name,
        given.type,
        given.body_i,
        given.body_j,
        vectors,
        **extra,
        source=check.doc.locate(path),
        sources=joint_sources(check, path, given),
    )


def joint_sources(check: Checker, path: Path, given) -> dict[str, Any]:
    """Where each key of the joint (and of its driver, as `driver.angle`) was written."""
    sources = {key: check.doc.locate_key((*path, key)) for key in given.model_fields_set}
    driver = getattr(given, "driver", None)
    for key in driver.model_fields_set if driver is not None else ():
        sources[f"driver.{key}"] = check.doc.locate_key((*path, "driver", key))
    return sources


def joint_vector(check: Checker, path: Path, key: str, values) -> np.ndarray | None:
    if key in NONZERO_KEYS:
        return check.direction(path, values, normalise=key in UNIT_KEYS)
    return check.numbers(path, values)


def drivers(check: Checker, path: Path, given) -> dict[str, ScalarFunction | None]:
    """`driver_angle`/`driver_displacement` functions of t (None: reported as wrong)."""
    driver = getattr(given, "driver", None)
    keys = [key for key in DRIVERS if driver is not None and getattr(driver, key) is not None]
    found = {}
    if driver is not None and not keys:
        ways = " or ".join(f"`driver: {{{key}: ...}}` ({', '.join(having(key))})"
                           for key in DRIVERS)
        check.error("E100", (*path, "driver"), "a driver needs a motion",
                    expected=" or ".join(DRIVERS),
                    hint=f"write {ways}; leave `driver:` out for a joint that moves freely")
        found["driver"] = None
    for key in keys:
        where = (*path, "driver", key)
        if given.type not in having(key):
            allowed = " and ".join(having(key))
            check.error(
                "E408",
                where,
                f"a {key} driver is not allowed on a {given.type} joint",
                source=check.doc.locate_key(where),
                hint=f"allowed on {allowed} joints",
            )
            found[f"driver_{key}"] = None
        else:
            found[f"driver_{key}"] = check.function(where, getattr(driver, key), {"t": 0.0})
    return found


def distance_length(check: Checker, path: Path, given, vectors) -> float | None:
    if given.length is not None:
        length = check.number((*path, "length"), given.length)
        where = (*path, "length")
    elif failed(vectors.values()):
        return None
    else:
        length, where = float(np.linalg.norm(vectors["at_j"] - vectors["at_i"])), (*path, "at_j")
    if length is not None and length <= ZERO:
        check.error(
            "E404",
            where,
            "a distance joint needs a positive length",
            got=f"{length:g}",
            hint="use a spherical joint for coincident points",
        )
        return None
    return length


def force(check: Checker, index: int, given) -> resolved.Force | None:
    path = ("forces", index)
    fields = FORCES[given.type](check, path, given)
    if fields is None or failed([*fields.values(), *fields.get("value", ())]):
        return None
    return resolved.Force(given.name, given.type, **fields, source=check.doc.locate(path))


def tsda(check: Checker, path: Path, given) -> dict[str, Any] | None:
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    at = {key: check.numbers((*path, key), getattr(given, key)) for key in ("at_i", "at_j")}
    if not bodies_ok or failed(at.values()):
        return None
    length = float(np.linalg.norm(at["at_j"] - at["at_i"]))
    free = (
        length
        if given.free_length is None
        else (check.number((*path, "free_length"), given.free_length))
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


def rsda(check: Checker, path: Path, given) -> dict[str, Any] | None:
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


def coefficients(check: Checker, path: Path, given) -> dict[str, float | None]:
    return {
        key: check.number((*path, key), getattr(given, key)) for key in ("stiffness", "damping")
    }


def load(check: Checker, path: Path, given) -> dict[str, Any] | None:
    """A point force or a torque on one moving body."""
    if not check.reference((*path, "body"), given.body, list(check.bodies), "moving body"):
        return None
    value = tuple(
        check.function((*path, "value", k), component, {"t": 0.0})
        for k, component in enumerate(given.value)
    )
    fields = dict(body=given.body, value=value, frame=given.frame)
    if given.type == "force":
        body = check.bodies[given.body]
        default = None if body is None else body.position
        at = check.vector((*path, "at"), given.at, default) if default is not None else None
        fields["vectors"] = None if at is None else {"at": at}
    return fields


FORCES = {"tsda": tsda, "rsda": rsda, "force": load, "torque": load}
