"""Adams SFORCE and SPRINGDAMPER statements -> casmech tsda / rsda forces.

Adams's SFORCE value is positive when it pushes the markers apart (translational) or turns the
I marker positively about the J marker's z axis (rotational). A FUNCTION affine in the measures

    F = F0 + a DM(I, J) + b VR(I, J)      ->  tsda  k = -a, c = -b, free length F0 / k
    T = T0 + a AZ(I, J) + b WZ(I, J, J)   ->  rsda  k = -a, c = -b, about the joint whose axis
                                              is J's z axis, free angle from AZ at t = 0

is written with its stiffness, damping and free length/angle as parameters (so `--set` can
change them). With k = 0 a constant F0/T0 becomes the actuator. Anything else is a warning.
"""

from __future__ import annotations

import numpy as np

from casmech.elements.joint_types import having
from casmech.importers.adm_connections import marker_notes
from casmech.importers.adm_frames import tidy
from casmech.importers.adm_functions import NotTranslated, affine
from casmech.importers.adm_model import Deck, Marker
from casmech.importers.adm_parser import Statement, function_text
from casmech.importers.emit import Imported, Item


def _pair(measure, i: int, j: int, allowed: dict[str, tuple]) -> str:
    """The measure's role (stiffness/damping) if it is one of `allowed` between I and J."""
    if measure.name not in allowed:
        raise NotTranslated(f"{measure.name.upper()} is not translated here")
    if measure.markers not in [form(i, j) for form in allowed[measure.name]]:
        raise NotTranslated(f"{measure.name.upper()}{measure.markers} is not between the I "
                            f"and J markers ({i}, {j}) in a translated order")
    return {"dm": "k", "az": "k", "vr": "c", "wz": "c"}[measure.name]


TRANSLATIONAL = {"dm": (lambda i, j: (i, j), lambda i, j: (j, i)),
                 "vr": (lambda i, j: (i, j), lambda i, j: (j, i))}
ROTATIONAL = {"az": (lambda i, j: (i, j),),
              "wz": (lambda i, j: (i, j), lambda i, j: (i, j, j))}


def _coefficients(text: str, i: int, j: int, allowed) -> tuple[float, float, float]:
    form = affine(text)
    roles = {"k": 0.0, "c": 0.0}
    for measure, coefficient in form.coefficients.items():
        roles[_pair(measure, i, j, allowed)] -= coefficient
    return form.constant, roles["k"], roles["c"]


def _parameters(model: Imported, name: str, values: dict[str, float], line: int) -> dict:
    """Adds `<name>_<key>` parameters; returns key -> parameter name."""
    out = {}
    for key, value in values.items():
        model.parameters.append((f"{name}_{key}", float(value), f"line {line}"))
        out[key] = f"{name}_{key}"
    return out


def _tsda(deck, model, statement, name, i: Marker, j: Marker, f0, k, c) -> Item:
    units = deck.units
    values = {"k": k * units.stiffness, "c": c * units.damping}
    if k != 0:
        values["l0"] = f0 / k * units.length
    p = _parameters(model, name, values, statement.line)
    data = {"name": name, "type": "tsda", "body_i": deck.part_name(i),
            "at_i": tidy(i.frame.origin), "body_j": deck.part_name(j),
            "at_j": tidy(j.frame.origin), "stiffness": p["k"], "damping": p["c"]}
    if k != 0:
        data["free_length"] = p["l0"]
    elif f0 != 0:  # casmech's actuator is a tension: the opposite of Adams's push
        data["actuator"] = repr(-f0 * units.force)
    return Item(data)


def _find_joint(deck, statement, joints: list[Item], i: Marker, j: Marker):
    """(joint item, sign of its axis along J's z) of a revolute/cylindrical joint between the
    markers' parts whose axis is J's z axis."""
    parts = {deck.part_name(i), deck.part_name(j)}
    z = j.frame.axis(2)
    for item in joints:
        data = item.data
        if data.get("type") in having("angle") and \
                {data["body_i"], data["body_j"]} == parts:
            axis = np.asarray(data["axis"], float)
            if np.linalg.norm(np.cross(axis, z)) < 1e-9:
                return item, float(np.sign(axis @ z))
    raise NotTranslated("no revolute or cylindrical joint between the two parts about the J "
                        "marker's z axis (casmech's rsda acts in such a joint)")


def _rsda(deck, model, statement, name, i: Marker, j: Marker, t0, k, c, joints) -> Item:
    item, sign = _find_joint(deck, statement, joints, i, j)
    x_i = i.frame.axis(0)
    az0 = float(np.arctan2(x_i @ j.frame.axis(1), x_i @ j.frame.axis(0)))
    on_j = item.data["body_j"] == deck.part_name(j)
    orientation = sign if on_j else -sign
    units = deck.units
    values = {"k": k * units.torque, "c": c * units.torque * units.time}
    if k != 0:
        values["free_angle"] = orientation * (az0 - t0 / k)
    p = _parameters(model, name, values, statement.line)
    data = {"name": name, "type": "rsda", "joint": item.data["name"], "stiffness": p["k"],
            "damping": p["c"]}
    if k != 0:
        data["free_angle"] = p["free_angle"]
    elif t0 != 0:
        data["actuator"] = repr(orientation * t0 * units.torque)
    return Item(data)


def sforce(deck: Deck, model: Imported, statement: Statement, joints: list[Item]) -> list[Item]:
    argument = statement.find("FUNCTION")
    flags = {flag.key[:5] for flag in statement.flags()}
    name = deck.name_for(statement, f"sforce_{statement.ident}")
    try:
        if argument is None:
            raise NotTranslated("no FUNCTION (user subroutines are not translated)")
        if "ACTIO" in flags:
            raise NotTranslated("ACTIONONLY forces are not translated")
        i, j = deck.marker(statement, "I"), deck.marker(statement, "J")
        text = function_text(argument)
        rotational = "ROTAT" in flags
        f0, k, c = _coefficients(text, int(i.statement.ident), int(j.statement.ident),
                                 ROTATIONAL if rotational else TRANSLATIONAL)
        item = (_rsda(deck, model, statement, name, i, j, f0, k, c, joints) if rotational
                else _tsda(deck, model, statement, name, i, j, f0, k, c))
    except NotTranslated as error:
        deck.reader.warn(statement, f"SFORCE not translated: {error}", where=argument)
        return []
    item.comments = [*statement.comments,
                     f"SFORCE/{statement.ident} (line {statement.line}): {text}",
                     *marker_notes(deck, i, j)]
    return [item]


def springdamper(deck: Deck, model: Imported, statement: Statement,
                 joints: list[Item]) -> list[Item]:
    """SPRINGDAMPER: K, C, LENGTH, FORCE (translational) or KT, CT, ANGLE, TORQUE."""
    rotational = any(flag.key.startswith("ROT") for flag in statement.flags())
    keys = ("KT", "CT", "ANGLE", "TORQUE") if rotational else ("K", "C", "LENGTH", "FORCE")
    k, c, free, preload = ((deck.reader.numbers(statement, key, 1, angle=key == "ANGLE")
                            or [0.0])[0] for key in keys)
    i, j = deck.marker(statement, "I"), deck.marker(statement, "J")
    name = deck.name_for(statement, f"springdamper_{statement.ident}")
    f0 = preload + k * free  # the same force written as F0 + a DM + b VR
    try:
        item = (_rsda(deck, model, statement, name, i, j, f0, k, c, joints) if rotational
                else _tsda(deck, model, statement, name, i, j, f0, k, c))
    except NotTranslated as error:
        deck.reader.warn(statement, f"SPRINGDAMPER not translated: {error}")
        return []
    item.comments = [*statement.comments, f"SPRINGDAMPER/{statement.ident} (line "
                     f"{statement.line})", *marker_notes(deck, i, j)]
    return [item]
