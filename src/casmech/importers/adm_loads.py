"""Adams BUSHING, VFORCE, VTORQUE and GFORCE statements -> casmech bushing, force, torque.

BUSHING (I, J, K, C, KT, CT, FORCE, TORQUE): Adams applies to the I marker the force
-K x - C v + FORCE (and the torque likewise), x being I's displacement from J in J's axes.
casmech's bushing applies A_I(-K d - C d_dot + F0) to body_j, d being J's displacement from I in
I's axes; so casmech's I frame is Adams's J marker and casmech's body_j the I marker's part
(both frames at the J marker's origin and axes at t = 0). The rotational deflection is
casmech's rotation vector where Adams uses three small angles: the same to first order
(docs/forces.md).

VFORCE/VTORQUE/GFORCE (I, JFLOAT, RM, FX=..\\ FY=..\\ ... TZ=..): a force at the I marker's
origin on its part (and a torque), components along the RM marker's axes. Translated when the
components are functions of TIME, JFLOAT is on the ground (the reaction goes to the ground) and
RM is on the ground (written in global components) or on the I marker's part (body
components); else a warning.
"""

from __future__ import annotations

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers.adm_connections import marker_notes
from casmech.importers.adm_frames import tidy
from casmech.importers.adm_functions import NotTranslated, time_function
from casmech.importers.adm_model import Deck, Marker
from casmech.importers.adm_parser import Statement
from casmech.importers.emit import Item

FORCES = ("FX", "FY", "FZ")
TORQUES = ("TX", "TY", "TZ")
COMPONENTS = {"VFORCE": FORCES, "VTORQUE": TORQUES, "GFORCE": FORCES + TORQUES}
SAME = 1e-9  # [m], |sin|: markers that coincide at t = 0


def bushing(deck: Deck, model, statement: Statement, joints) -> list[Item]:
    i, j = deck.marker(statement, "I"), deck.marker(statement, "J")
    units, reader = deck.units, deck.reader
    factors = {"K": ("stiffness", units.stiffness), "C": ("damping", units.damping),
               "KT": ("rotational_stiffness", units.torque),
               "CT": ("rotational_damping", units.torque * units.time),
               "FORCE": ("preload_force", units.force), "TORQUE": ("preload_torque",
                                                                   units.torque)}
    data = {"name": deck.name_for(statement, f"bushing_{statement.ident}"), "type": "bushing",
            "body_i": deck.part_name(j), "body_j": deck.part_name(i),
            "at": tidy(j.frame.origin)}
    if not np.allclose(j.frame.rotation, np.eye(3), rtol=0, atol=1e-15):
        data["orientation"] = {"euler_parameters": tidy(from_matrix(j.frame.rotation))}
    for key, (name, factor) in factors.items():
        values = reader.numbers(statement, key, 3)
        if values is not None and any(values):
            data[name] = tidy(np.array(values) * factor)
    if np.linalg.norm(i.frame.origin - j.frame.origin) > SAME * max(
            1.0, np.max(np.abs(j.frame.origin))) or not np.allclose(
            i.frame.rotation, j.frame.rotation, rtol=0, atol=SAME):
        reader.warn(statement, "the I and J markers differ at t = 0: casmech's bushing starts "
                    "undeflected, with both frames at the J marker",
                    hint="Adams would start with the deflection between them")
    return [Item(data, [*statement.comments, f"BUSHING/{statement.ident} (line "
                        f"{statement.line}): casmech body_i is the J marker's part",
                        *marker_notes(deck, i, j)])]


def components(statement: Statement, keys) -> dict[str, str]:
    """KEY -> expression text of `FX = e1\\ FY = e2\\ ...` (absent keys: '0')."""
    text = " ".join(f"{a.key} = " + ", ".join(v.text for v in a.values)
                    for a in statement.arguments if a.key in keys)
    found = {}
    for piece in text.split("\\"):
        key, eq, expression = piece.partition("=")
        key = key.strip().upper()
        if eq and key in keys:
            found[key] = expression.strip()
    return {key: found.get(key, "0") for key in keys}


def _vector(texts: list[str], matrix: np.ndarray, units, scale: float) -> list:
    """matrix @ [f1, f2, f3] as numbers when the components are numbers, else expressions."""
    values = [time_function(text, units.time) for text in texts]
    try:
        return tidy(matrix @ np.array([float(v) for v in values]) * scale)
    except ValueError:
        pass
    rows = []
    for row in np.reshape(tidy(matrix * scale), (3, 3)):
        terms = [f"{float(c)!r} * ({v})" for c, v in zip(row, values, strict=True) if c != 0]
        rows.append(" + ".join(terms) or "0")
    return rows


def _frame(deck: Deck, i: Marker, rm: Marker) -> tuple[np.ndarray, str]:
    """(matrix from RM components to the written ones, frame key)."""
    if deck.parts[rm.part].ground:
        return rm.frame.rotation, "global"
    if rm.part == i.part:
        return deck.parts[i.part].body_frame.rotation.T @ rm.frame.rotation, "body"
    raise NotTranslated("RM is on a third part (casmech forces have global or body "
                        "components)")


def vector_force(deck: Deck, model, statement: Statement, joints) -> list[Item]:
    """VFORCE, VTORQUE, GFORCE: a force at I (and/or a torque on I's part)."""
    units, keys = deck.units, COMPONENTS[statement.name]
    try:
        i = deck.marker(statement, "I")
        jfloat = deck.marker(statement, "JFLOAT")
        rm = deck.marker(statement, "RM")
        if not deck.parts[jfloat.part].ground:
            raise NotTranslated("JFLOAT is not on the ground (casmech's force has no reaction "
                                "on a second part)")
        matrix, frame = _frame(deck, i, rm)
        texts = components(statement, keys)
        body = deck.part_name(i)
        name = deck.name_for(statement, f"{statement.name.lower()}_{statement.ident}")
        items = []
        if keys[0] == "FX":
            value = _vector([texts[k] for k in FORCES], matrix, units, units.force)
            items.append({"name": name, "type": "force", "body": body,
                          "at": tidy(i.frame.origin), "value": value, "frame": frame})
        if keys[-1] == "TZ":
            value = _vector([texts[k] for k in TORQUES], matrix, units, units.torque)
            torque = deck.name_for(statement, f"{name}_torque") if items else name
            items.append({"name": torque, "type": "torque", "body": body, "value": value,
                          "frame": frame})
    except NotTranslated as error:
        deck.reader.warn(statement, f"{statement.name} not translated: {error}")
        return []
    comments = [*statement.comments, f"{statement.label} (line {statement.line}): components "
                f"along RM/{rm.statement.ident}'s axes, written in {frame} components",
                *marker_notes(deck, i, jfloat, rm)]
    return [Item(data, comments if k == 0 else []) for k, data in enumerate(items)]
