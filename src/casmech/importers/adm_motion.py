"""Adams MOTION statements on a joint -> the casmech joint's `driver` or `motor`.

    MOTION/id, JOINT = j, ROTATION | TRANSLATION, [DISPLACEMENT | VELOCITY], FUNCTION = f(TIME)

Adams measures the motion of the joint's I marker relative to its J marker: the angle of I's x
axis about J's z axis (AZ), the slide of I's origin along J's z (DZ), absolutely (an f(0) other
than the pose in the deck is reached by assembly). casmech measures the rotation/slide of body_j
(the J marker's part) relative to body_i about/along the joint axis (the I marker's z), from the
pose in the file. So, with s = +1 when I's and J's z agree:

    driver angle (displacement) = -s (f(t) - AZ0 (DZ0))       DISPLACEMENT (the default)
    motor speed (velocity)      = -s f(t)                       VELOCITY

ACCELERATION motions, motions of a point (I, J, B1/B2/B3/X/Y/Z) and functions of anything but
TIME are warnings.
"""

from __future__ import annotations

import numpy as np

from casmech.elements.joint_types import COORDINATES, having
from casmech.importers.adm_functions import NotTranslated, time_function
from casmech.importers.adm_model import Deck
from casmech.importers.adm_parser import Statement, function_text
from casmech.importers.emit import Item

# (Adams flag, casmech joint types it drives) -> (driver/motor key: displacement, velocity)
KINDS = {flag: (having(name), COORDINATES[name].motor[:2])
         for flag, name in (("ROTATION", "angle"), ("TRANSLATION", "displacement"))}
MODES = ("DISPLACEMENT", "VELOCITY", "ACCELERATION")


def _words(statement: Statement) -> list[str]:
    """The flags, including those the parser took as further values of the argument before
    them (`JOINT = 1, ROTATION` reads like the list `JOINT = 1, ROTATION`)."""
    return [flag.key for flag in statement.flags()] + [
        value.text.upper() for argument in statement.arguments if argument.key != "FUNCTION"
        for value in argument.values[1:] if value.text.isalpha()]


def _flag(statement: Statement, names) -> str | None:
    for word in _words(statement):
        for name in names:
            if len(word) >= 3 and name.startswith(word):
                return name
    return None


def _initial(kind: str, i, j) -> float:
    """AZ(I, J) or DZ(I, J, J) at t = 0."""
    if kind == "ROTATION":
        x_i = i.frame.axis(0)
        return float(np.arctan2(x_i @ j.frame.axis(1), x_i @ j.frame.axis(0)))
    return float((i.frame.origin - j.frame.origin) @ j.frame.axis(2))


def _translate(deck: Deck, statement: Statement, joints: dict[str, tuple[Item, Statement]]
               ) -> tuple[Item, dict, str]:
    if statement.find("JOINT") is None:
        raise NotTranslated("only motions on a JOINT are translated (not point motions)")
    ident = str(deck.reader.ident(statement, "JOINT"))  # as adm._ident keys the joints
    if ident not in joints:
        raise NotTranslated(f"JOINT/{ident} is not a translated joint of this deck")
    item, joint_statement = joints[ident]
    kind = _flag(statement, KINDS) or "ROTATION"
    types, keys = KINDS[kind]
    if item.data["type"] not in types:
        raise NotTranslated(f"a {kind} motion on a {item.data['type']} joint")
    mode = _flag(statement, MODES) or "DISPLACEMENT"
    if mode == "ACCELERATION":
        raise NotTranslated("ACCELERATION motions are not translated (give the displacement)")
    argument = statement.find("FUNCTION")
    if argument is None:
        raise NotTranslated("no FUNCTION (user subroutines are not translated)")
    units = deck.units
    scale = 1.0 if kind == "ROTATION" else units.length
    rate = 1.0 / units.time
    text = time_function(function_text(argument), units.time,
                         scale * (rate if mode == "VELOCITY" else 1.0))
    i = deck.marker(joint_statement, "I")
    j = deck.marker(joint_statement, "J")
    negate = i.frame.axis(2) @ j.frame.axis(2) >= 0  # body_j turns opposite to I about J

    def signed(expression: str) -> str:
        return f"-({expression})" if negate else expression

    if mode == "VELOCITY":
        return item, {"motor": {keys[1]: signed(text)}}, mode
    start = _initial(kind, i, j) * scale
    return item, {"driver": {keys[0]: signed(f"{text} - {start!r}" if start else text)}}, mode


def motion(deck: Deck, statement: Statement, joints: dict[str, tuple[Item, Statement]]) -> bool:
    """Adds the motion to its joint's item; False (with a warning) when not translated."""
    try:
        item, keys, mode = _translate(deck, statement, joints)
        (section, values), = keys.items()
        given = item.data.get(section, {})
        if set(given) & set(values) or {"driver", "motor"} - {section} & set(item.data):
            raise NotTranslated(f"the joint {item.data['name']} already has this motion, or "
                                "one of the other mode (casmech takes one form per joint)")
    except NotTranslated as error:
        deck.reader.warn(statement, f"MOTION not translated: {error}",
                         where=statement.find("FUNCTION"))
        return False
    item.data[section] = {**given, **values}
    item.comments = [*item.comments, *statement.comments, f"MOTION/{statement.ident} {mode} "
                     f"(line {statement.line}): {function_text(statement.find('FUNCTION'))}"]
    return True
