"""A joint's `initial:`: its coordinates and rates at t = 0 (docs/format.md#initial-state).

The file's pose is the reference: every joint coordinate is 0 there (as a driver's). The keys
a joint type takes (casmech.elements.joint_types.initial_keys): `angle`, `angle_dot`
(revolute, cylindrical), `displacement`, `displacement_dot` (translational, cylindrical),
`angle_i`, `angle_i_dot`, `angle_j`, `angle_j_dot` (universal: about axis_i, about axis_j),
`orientation` (any form of a body's `orientation:`) and `angular_velocity` (spherical:
body_j's rotation and angular velocity relative to body_i, in the joint frame, the global axes
at the file's pose carried by body_i). model/initial.py poses the bodies from them along the
spanning tree (elements/joint_tree.py); runtime/assembly.py holds them while the loops close.

Checked here (E412, at the key): a coordinate (or its rate) that the joint's driver or
position/speed motor gives; and a body whose velocity the tree gives (every body below a
ground or a floating root, in a part of the mechanism where a joint has `initial:`) that
writes `velocity:` or `angular_velocity:` (its velocity follows from the joints' rates).
"""

from __future__ import annotations

from typing import Any

from casmech.core.states import JOINT_COORDINATES
from casmech.elements.coordinate_kinds import REGISTRY as COORDINATES
from casmech.elements.joint_tree import GROUND, Link, spanning_tree
from casmech.errors import failed
from casmech.schema import bodies
from casmech.schema.checker import Checker
from casmech.schema.loader import Path


def initial(check: Checker, path: Path, given) -> dict[str, Any] | None:
    """{key: value} of a joint's `initial:` ({} without one; None: reported). Scalars are
    numbers (traced numbers of symbolic parameters), `orientation` unit Euler parameters,
    `angular_velocity` a vector."""
    written = getattr(given, "initial", None)
    if written is None:
        return {}
    where = (*path, "initial")
    found: dict[str, Any] = {}
    for key in written.model_fields_set:
        value = getattr(written, key)
        if value is None:
            continue
        if key == "orientation":
            found[key] = bodies.orientation(check, (*where, key), value)
        elif key == "angular_velocity":
            found[key] = check.numbers((*where, key), value)
        else:
            found[key] = check.number((*where, key), value)
    return None if failed(found.values()) else found


def sources(check: Checker, path: Path, given) -> dict[str, Any]:
    """Where each key of `initial:` was written (`initial.angle`)."""
    written = getattr(given, "initial", None)
    return {f"initial.{key}": check.doc.locate_key((*path, "initial", key))
            for key in (written.model_fields_set if written is not None else ())}


def driven(check: Checker, joints) -> None:
    """E412 for an initial value of a coordinate that a driver (or a position or speed
    motor) gives."""
    for index, joint in enumerate(joints):
        if joint is None:
            continue
        for key in joint.initial:
            driver = JOINT_COORDINATES.get(key)  # the kind whose driver gives key at t = 0
            if driver is not None and driver in joint.drivers:
                where = ("joints", index, "initial", key)
                check.error("E412", where, f"the {driver} of "
                            f"'{joint.name}' is driven: its driver gives its {key} at t = 0",
                            source=check.doc.locate_key(where),
                            hint=f"remove initial.{key}, or the driver (or motor)")


def velocities(check: Checker, given_bodies, joints) -> None:
    """E412 for a body whose velocity its joints' `initial:` rates give that writes one."""
    if failed(joints) or not any(joint.initial for joint in joints):
        return
    names = [body.name for body in given_bodies]
    links = [Link(j.name, j.type, j.body_i, j.body_j, j.cut) for j in joints]
    tree = spanning_tree(names, links)
    root = tree.root_of()
    posed = {root[body] for j in joints if j.initial for body in (j.body_i, j.body_j)}
    for index, body in enumerate(given_bodies):
        if body.name in tree.roots or root.get(body.name) not in posed:
            continue
        for key in ("velocity", "angular_velocity"):
            if getattr(body, key) is not None:
                where = ("bodies", index, key)
                part = "the mechanism on ground" if root[body.name] == GROUND else \
                    f"the floating group of '{root[body.name]}'"
                check.error("E412", where, f"body '{body.name}' is moved by its joints' "
                            f"`initial:` values ({part} has some): its {key} follows from "
                            "their rates", source=check.doc.locate_key(where),
                            hint="give the joints' rates in `initial:` ("
                                 + ", ".join(kind.rate for kind in COORDINATES.values())
                                 + ", ...) and remove the body's " + key)
