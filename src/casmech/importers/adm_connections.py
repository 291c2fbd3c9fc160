"""Adams JOINT, JPRIM and GCON statements -> casmech joints.

Composite joints are written in global coordinates at t = 0 (casmech's form) from the I marker:
`at` = its origin, the axis = its z axis (Adams's I and J markers coincide and their z axes are
parallel at an assembled pose; a pose where they do not gets a warning). body_i is the I marker's
part, body_j the J marker's. JPRIMs become casmech's basic constraints (vectors in body frames).
"""

from __future__ import annotations

import numpy as np

from casmech.importers.adm_frames import tidy
from casmech.importers.adm_functions import NotTranslated, affine
from casmech.importers.adm_model import Deck, Marker
from casmech.importers.adm_parser import Statement, function_text
from casmech.importers.emit import Item


def _at(i: Marker, j: Marker) -> dict:
    return {"at": tidy(i.frame.origin)}


def _axis(i: Marker, j: Marker) -> dict:
    return {"at": tidy(i.frame.origin), "axis": tidy(i.frame.axis(2))}


# Adams joint type -> (casmech type, keys from the I/J markers, what must coincide at t = 0)
JOINTS = {
    "REVOLUTE": ("revolute", _axis, ("origin", "z")),
    "SPHERICAL": ("spherical", _at, ("origin",)),
    "UNIVERSAL": ("universal", lambda i, j: {"at": tidy(i.frame.origin),
                                             "axis_i": tidy(i.frame.axis(2)),
                                             "axis_j": tidy(j.frame.axis(2))}, ("origin",)),
    "HOOKE": ("universal", lambda i, j: {"at": tidy(i.frame.origin),
                                         "axis_i": tidy(i.frame.axis(0)),
                                         "axis_j": tidy(j.frame.axis(1))}, ("origin",)),
    "CYLINDRICAL": ("cylindrical", _axis, ("line", "z")),
    "TRANSLATIONAL": ("translational", _axis, ("line", "z")),
    "FIXED": ("fixed", _at, ("origin", "z", "x")),
    "PLANAR": ("planar", _axis, ("z",)),
}


def _mismatch(i: Marker, j: Marker, checks) -> list[str]:
    """What an assembled joint needs that the markers do not satisfy at t = 0."""
    d = j.frame.origin - i.frame.origin
    z = i.frame.axis(2)
    tests = {
        "origin": np.linalg.norm(d) > 1e-9,
        "line": np.linalg.norm(d - (d @ z) * z) > 1e-9,
        "z": np.linalg.norm(np.cross(z, j.frame.axis(2))) > 1e-9,
        "x": np.linalg.norm(np.cross(i.frame.axis(0), j.frame.axis(0))) > 1e-9,
    }
    return [check for check in checks if tests[check]]


def _joint_type(deck: Deck, statement: Statement, table, what: str) -> str | None:
    """The type flag, abbreviations of three letters or more accepted (REV, TRANS, ...); None
    with a warning naming the statement when it is not one the table translates."""
    for flag in statement.flags():
        for name in table:
            if len(flag.key) >= 3 and name.startswith(flag.key):
                return name
    deck.reader.warn(statement, f"{what} type not translated", hint="translated: "
                     + ", ".join(table))
    return None


def joint(deck: Deck, statement: Statement) -> list[Item]:
    kind = _joint_type(deck, statement, JOINTS, "joint")
    if kind is None:
        return []
    i, j = deck.marker(statement, "I"), deck.marker(statement, "J")
    casmech_type, keys, checks = JOINTS[kind]
    for failed in _mismatch(i, j, checks):
        deck.reader.warn(statement, f"I and J markers do not agree at t = 0 ({failed}); casmech "
                         "uses the I marker's", hint="Adams would assemble them first")
    data = {"name": deck.name_for(statement, f"joint_{statement.ident}"), "type": casmech_type,
            "body_i": deck.part_name(i), "body_j": deck.part_name(j), **keys(i, j)}
    comments = [*statement.comments, f"JOINT/{statement.ident} {kind} (line {statement.line})"]
    return [Item(data, comments + marker_notes(deck, i, j))]


def marker_notes(deck: Deck, *markers: Marker) -> list[str]:
    """The markers' own comments and placement, once each (their lines count as used)."""
    notes = []
    for marker in markers:
        statement = marker.statement
        if statement.line not in deck.used:
            deck.used.add(statement.line)
            notes += [*statement.comments, " ".join(t.strip() for t in statement.text)
                      + f" (line {statement.line})"]
    return notes


def _local(deck: Deck, marker: Marker):
    return deck.parts[marker.part].body_frame


def _dp1(deck, i, j, axis_i, axis_j, suffix):
    return {"type": "dp1", "body_i": deck.part_name(j),
            "a_i": tidy(_local(deck, j).to_local_vector(j.frame.axis(axis_j))),
            "body_j": deck.part_name(i),
            "a_j": tidy(_local(deck, i).to_local_vector(i.frame.axis(axis_i))), "f": "0",
            "_suffix": suffix}


def _dp2(deck, i, j, axis_j, suffix):
    """I origin stays in the plane through J's origin normal to J's axis `axis_j`."""
    return {"type": "dp2", "body_i": deck.part_name(j),
            "a_i": tidy(_local(deck, j).to_local_vector(j.frame.axis(axis_j))),
            "s_i": tidy(_local(deck, j).to_local_point(j.frame.origin)),
            "body_j": deck.part_name(i),
            "s_j": tidy(_local(deck, i).to_local_point(i.frame.origin)), "f": "0",
            "_suffix": suffix}


# JPRIM type -> rows as (builder, args); ATPOINT is a spherical joint
JPRIMS = {
    "INLINE": [(_dp2, (0, "x")), (_dp2, (1, "y"))],
    "INPLANE": [(_dp2, (2, "z"))],
    "ORIENTATION": [(_dp1, (0, 2, "zx")), (_dp1, (1, 2, "zy")), (_dp1, (1, 0, "xy"))],
    "PARALLEL_AXES": [(_dp1, (2, 0, "x")), (_dp1, (2, 1, "y"))],
    "PERPENDICULAR": [(_dp1, (2, 2, "z"))],
    "ATPOINT": [],
}


def jprim(deck: Deck, statement: Statement) -> list[Item]:
    kind = _joint_type(deck, statement, JPRIMS, "JPRIM")
    if kind is None:
        return []
    i, j = deck.marker(statement, "I"), deck.marker(statement, "J")
    name = deck.name_for(statement, f"jprim_{statement.ident}")
    comments = [*statement.comments, f"JPRIM/{statement.ident} {kind} (line {statement.line})"]
    if kind == "ATPOINT":
        data = {"name": name, "type": "spherical", "body_i": deck.part_name(i),
                "body_j": deck.part_name(j), "at": tidy(i.frame.origin)}
        return [Item(data, comments + marker_notes(deck, i, j))]
    comments = comments + marker_notes(deck, i, j)
    items = []
    for builder, args in JPRIMS[kind]:
        row = builder(deck, i, j, *args)
        suffix = row.pop("_suffix")
        items.append(Item({"name": f"{name}_{suffix}", **row}, comments if not items else []))
    return items


def gcon(deck: Deck, statement: Statement) -> list[Item]:
    """GCON whose FUNCTION is a*DM(P, Q) + b: a distance constraint of length -b/a."""
    argument = statement.find("FUNCTION")
    try:
        if argument is None:
            raise NotTranslated("no FUNCTION")
        form = affine(function_text(argument))
        (measure, coefficient), = form.coefficients.items() or [(None, 0.0)]
        if measure is None or measure.name != "dm" or len(measure.markers) != 2:
            raise NotTranslated("only a*DM(P, Q) + b is translated (a distance)")
    except (NotTranslated, ValueError) as error:
        deck.reader.warn(statement, f"GCON not translated: {error}", where=argument)
        return []
    j, i = (deck.marker_by_id(statement, m) for m in measure.markers)
    length = -form.constant / coefficient * deck.units.length
    data = {"name": deck.name_for(statement, f"gcon_{statement.ident}"), "type": "distance",
            "body_i": deck.part_name(i), "body_j": deck.part_name(j),
            "at_i": tidy(i.frame.origin), "at_j": tidy(j.frame.origin), "length": length}
    comments = [*statement.comments,
                f"GCON/{statement.ident}: {function_text(argument)} (line {statement.line})",
                *marker_notes(deck, i, j)]
    return [Item(data, comments)]
