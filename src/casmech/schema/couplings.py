"""Couplings of joint coordinates (gear, rack_pinion, coupler; joint_types.Couples): the joints
they name, the coordinate each gives and the coefficients of the row sum_k c_k s_k = 0 (a
coupler's: = its `offset`, default 0).

A coupler's `joints:` entry is a joint's name (its one coordinate: revolute angle,
translational displacement) or `<joint>.angle` / `<joint>.displacement` (a cylindrical joint's
either). Errors: an unknown joint E300, a joint without the coordinate E103, a coupler of fewer
than 2 or more than 3 coordinates or with as many coefficients as joints E105, a coordinate
named twice E301, a zero ratio, radius or coefficient E404.
"""

from __future__ import annotations

from casmech.core import traced
from casmech.elements.couplings import MAX_COORDINATES
from casmech.elements.joint_types import COORDINATES, REGISTRY, Couples, having, listed
from casmech.errors import failed
from casmech.schema import resolved
from casmech.schema.checker import ZERO, Checker
from casmech.schema.loader import Path


def _coordinate(check: Checker, path: Path, written: str, use: str | None) -> tuple | None:
    """(joint, coordinate) of one coupled joint, or None after an error."""
    name, coordinate = written, use
    if use is None and written not in check.joint_types:
        head, _, tail = written.rpartition(".")
        if tail in COORDINATES and head in check.joint_types:  # a coordinate kind
            name, coordinate = head, tail
    if not check.reference(path, name, check.joint_types, "joint"):
        return None
    entry = REGISTRY.get(check.joint_types[name])
    owned = entry.coordinates if entry is not None and entry.couples is None else ()
    if coordinate is None:
        if len(owned) != 1:
            choices = " or ".join(f"'{name}.{c}'" for c in owned)
            check.error("E103", path, f"joint '{name}' ({check.joint_types[name]}) has "
                        f"{'no' if not owned else 'more than one'} coordinate to couple",
                        expected="a joint of one coordinate, or " + " or ".join(
                            f"'<joint>.{kind}'" for kind in COORDINATES),
                        hint=f"write {choices}" if owned else None)
            return None
        coordinate = owned[0]
    if coordinate not in owned:
        check.error("E103", path, f"a coupling here reads the {coordinate} of a "
                    f"{listed(having(coordinate), 'or')} joint",
                    got=f"'{name}' is {check.joint_types[name]}")
        return None
    return name, coordinate


def _nonzero(check: Checker, path: Path, value, what: str):
    if value is not None and abs(traced.value(value)) <= ZERO:
        check.error("E404", path, f"a coupling's {what} must not be zero",
                    got=f"{traced.value(value):g}",
                    hint="a zero coefficient leaves that coordinate free: leave it out")
        return None
    return value


def _coefficients(check: Checker, path: Path, given, couples: Couples) -> tuple | None:
    if couples.joints:
        scalars = {key: _nonzero(check, (*path, key), check.number((*path, key),
                                                                    getattr(given, key)), key)
                   for key in couples.scalars}
        return None if failed(scalars.values()) else tuple(couples.coefficients(scalars))
    values = [_nonzero(check, (*path, "coefficients", k), check.number(
        (*path, "coefficients", k), value), "coefficient")
        for k, value in enumerate(given.coefficients)]
    return None if failed(values) else tuple(couples.coefficients({"coefficients": values}))


def coupling(check: Checker, index: int, given) -> resolved.Joint | None:
    """A gear, rack_pinion or coupler (module docstring); body_i and body_j are the output
    joint's."""
    path = ("joints", index)
    couples = REGISTRY[given.type].couples
    check.joint_types[given.name] = given.type
    if couples.joints:
        written = [((*path, key), getattr(given, key), use)
                   for key, use in zip(couples.joints, couples.uses, strict=True)]
    else:
        written = [((*path, "joints", k), name, None) for k, name in enumerate(given.joints)]
        count = len(given.joints)
        if not 2 <= count <= MAX_COORDINATES:
            check.error("E105", (*path, "joints"), "a coupler couples 2 or 3 joint coordinates",
                        got=f"{count}")
            return None
        if len(given.coefficients) != count:
            check.error("E105", (*path, "coefficients"), "one coefficient per joint",
                        expected=f"{count} coefficients", got=f"{len(given.coefficients)}")
            return None
    coordinates = [_coordinate(check, where, name, use) for where, name, use in written]
    coefficients = _coefficients(check, path, given, couples)
    offset = check.number((*path, "offset"), given.offset) if not couples.joints else 0.0
    if failed([*coordinates, coefficients, offset]):
        return None
    for k, pair in enumerate(coordinates):
        if pair in coordinates[:k]:
            check.error("E301", written[k][0], f"the {pair[1]} of '{pair[0]}' is coupled "
                        "twice", hint="name each coordinate once")
            return None
    body_i, body_j = check.joint_bodies[coordinates[couples.output][0]]
    check.joint_bodies[given.name] = (body_i, body_j)
    sources = {key: check.doc.locate_key((*path, key)) for key in given.model_fields_set}
    extra = {"options": {"offset": offset}} if not couples.joints else {}
    if given.reactions is not None:
        extra["reaction_frame"] = given.reactions.frame
        if given.reactions.point is not None:
            extra["reaction_point"] = check.numbers((*path, "reactions", "point"),
                                                    given.reactions.point)
            if extra["reaction_point"] is None:
                return None
    return resolved.Joint(given.name, given.type, body_i, body_j, {},
                          source=check.doc.locate(path), sources=sources,
                          couples=tuple(coordinates), coefficients=coefficients, **extra)
