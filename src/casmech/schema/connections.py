"""Joints: references, vectors, drivers, functions of time (force elements:
schema/force_laws.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from casmech.core import traced
from casmech.elements.joint_types import COORDINATES, REGISTRY, having, listed
from casmech.errors import failed
from casmech.schema import contact, couplings, initial, resolved
from casmech.schema.checker import ZERO, Checker
from casmech.schema.loader import Path

UNIT_KEYS = frozenset({"axis", "axis_i", "axis_j"})  # normalised
NONZERO_KEYS = frozenset({"axis", "axis_i", "axis_j", "a_i", "a_j", "c"})  # E404 when zero


def joint(check: Checker, index: int, given) -> resolved.Joint | None:
    if REGISTRY[given.type].couples is not None:
        return couplings.coupling(check, index, given)
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
    options = {key: option(check, (*path, key), getattr(given, key), given.type)
               for key in entry.options if key != "length"}
    if options:
        extra["options"] = None if failed(options.values()) else options
    if getattr(given, "cut", False):
        extra["cut"] = True
    if given.reactions is not None:
        extra["reaction_frame"] = given.reactions.frame
    if given.reactions is not None and given.reactions.point is not None:
        extra["reaction_point"] = check.numbers((*path, "reactions", "point"),
                                                given.reactions.point)
    if getattr(given, "limit", None) is not None:
        extra["limit"] = contact.limit(check, (*path, "limit"), given.limit)
    if getattr(given, "friction", None) is not None:
        extra["friction"] = contact.friction(check, (*path, "friction"), given.friction,
                                              entry)
    if getattr(given, "initial", None) is not None:
        extra["initial"] = initial.initial(check, path, given)
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


def option(check: Checker, path: Path, value, joint_type: str):
    """A joint type's scalar option other than `length` (a screw's lead): required, nonzero."""
    if value is None:
        check.error("E100", path, f"a {joint_type} joint needs `{path[-1]}`",
                    hint=f"write `{path[-1]}: ...` (docs/format.md)")
        return None
    number = check.number(path, value)
    if number is not None and abs(traced.value(number)) <= ZERO:
        check.error("E404", path, f"a {joint_type}'s {path[-1]} must not be zero",
                    got=f"{traced.value(number):g}")
        return None
    return number


def joint_sources(check: Checker, path: Path, given) -> dict[str, Any]:
    """Where each key of the joint (and of its driver, as `driver.angle`) was written."""
    sources = {key: check.doc.locate_key((*path, key)) for key in given.model_fields_set}
    driver = getattr(given, "driver", None)
    for key in driver.model_fields_set if driver is not None else ():
        sources[f"driver.{key}"] = check.doc.locate_key((*path, "driver", key))
    return sources | initial.sources(check, path, given)


def joint_vector(check: Checker, path: Path, key: str, values) -> np.ndarray | None:
    if key in NONZERO_KEYS:
        return check.direction(path, values, normalise=key in UNIT_KEYS)
    return check.numbers(path, values)


def drivers(check: Checker, path: Path, given) -> dict[str, Any]:
    """{"drivers": {coordinate kind: function of t}} ({} without `driver:`; the value None:
    reported as wrong). The keys are the registered coordinate kinds."""
    driver = getattr(given, "driver", None)
    if driver is None:
        return {}
    kinds = tuple(COORDINATES)
    keys = [key for key in kinds if getattr(driver, key, None) is not None]
    if not keys:
        ways = " or ".join(f"`driver: {{{key}: ...}}` ({', '.join(having(key))})"
                           for key in kinds if having(key))
        check.error("E100", (*path, "driver"), "a driver needs a motion",
                    expected=" or ".join(kinds),
                    hint=f"write {ways}; leave `driver:` out for a joint that moves freely")
        return {"drivers": None}
    found = {}
    for key in keys:
        where = (*path, "driver", key)
        if given.type not in having(key):
            allowed = listed(having(key)) if having(key) else "no"
            check.error(
                "E408",
                where,
                f"a {key} driver is not allowed on a {given.type} joint",
                source=check.doc.locate_key(where),
                hint=f"allowed on {allowed} joints",
            )
            found[key] = None
        else:
            found[key] = check.function(where, getattr(driver, key), {"t": 0.0})
    return {"drivers": None if failed(found.values()) else found}


def distance_length(check: Checker, path: Path, given, vectors) -> float | None:
    if given.length is not None:
        length = check.number((*path, "length"), given.length)
        where = (*path, "length")
    elif failed(vectors.values()):
        return None
    else:
        length = traced.scalar(np.linalg.norm(vectors["at_j"] - vectors["at_i"]))
        where = (*path, "at_j")
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
