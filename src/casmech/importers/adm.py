"""Adams/Solver dataset (.adm) -> casmech model (an `Imported`, written by emit.to_yaml).

Translated: UNITS, PART (GROUND; MASS, CM, IP, QG/REULER, VX..VZ global, WX..WZ in the CM
marker's axes), MARKER (QP, REULER, ZP/XP), JOINT (revolute, spherical, universal, Hooke,
cylindrical, translational, fixed, planar), JPRIM, GCON of a distance, SFORCE and SPRINGDAMPER
of the linear spring-damper forms (adm_forces), MOTION on a joint (adm_motion), BUSHING,
VFORCE, VTORQUE and GFORCE of functions of time (adm_loads), ACCGRAV. Every other statement or
argument is a warning naming its line; its text and comments are kept at the end of the YAML.

Conventions: casmech body frame = the CM marker's frame; IP = (xx, yy, zz[, xy, xz, yz]) about
the CM in its axes, Adams's products being +integral(x y dm), so the inertia matrix entries are
their negatives; SI units after conversion per UNITS; no ACCGRAV means no gravity.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.quaternions import from_matrix
from casmech.importers import adm_connections, adm_forces, adm_loads, adm_motion
from casmech.importers.adm_frames import tidy
from casmech.importers.adm_model import Deck, Part, Reader, read_markers, read_parts, read_units
from casmech.importers.adm_parser import Statement, Value, parse_adm
from casmech.importers.emit import Imported, Item
from casmech.importers.source import read_source

# statement -> arguments it may carry (anything else: a warning)
KNOWN = {
    "PART": {"GROUND", "MASS", "CM", "IP", "QG", "REULER", "ZG", "XG", "VX", "VY", "VZ", "WX",
             "WY", "WZ", "IM"},
    "MARKER": {"PART", "QP", "REULER", "ZP", "XP"},
    "JOINT": {"I", "J", *adm_connections.JOINTS},
    "JPRIM": {"I", "J", *adm_connections.JPRIMS},
    "GCON": {"I", "FUNCTION"},
    "SFORCE": {"I", "J", "FUNCTION", "TRANSLATIONAL", "ROTATIONAL"},
    "SPRINGDAMPER": {"I", "J", "K", "C", "LENGTH", "FORCE", "KT", "CT", "ANGLE", "TORQUE",
                     "TRANSLATIONAL", "ROTATIONAL"},
    "ACCGRAV": {"IGRAVITY", "JGRAVITY", "KGRAVITY", "IGRAV", "JGRAV", "KGRAV"},
    "UNITS": {"FORCE", "MASS", "LENGTH", "TIME", "SYSTEM"},
    "MOTION": {"JOINT", *adm_motion.KINDS, *adm_motion.MODES, "FUNCTION", "I", "J", "B1", "B2",
               "B3", "X", "Y", "Z"},
    "BUSHING": {"I", "J", "K", "C", "KT", "CT", "FORCE", "TORQUE"},
    **{name: {"I", "JFLOAT", "RM", *keys} for name, keys in adm_loads.COMPONENTS.items()},
}
OUTPUT_ONLY = {"GRAPHICS", "REQUEST", "OUTPUT", "RESULTS", "VARIABLE", "STRING"}


def _known_argument(name: str, key: str) -> bool:
    if name in ("JOINT", "JPRIM", "SFORCE", "SPRINGDAMPER", "MOTION") and len(key) >= 3:
        return any(k.startswith(key) for k in KNOWN[name])
    return key in KNOWN[name]


def _check_arguments(reader: Reader, statement: Statement) -> None:
    for argument in statement.arguments:
        if not _known_argument(statement.name, argument.key):
            reader.warn(statement, f"argument {argument.key} not translated", code="E101",
                        where=argument)


def _body(deck: Deck, part: Part) -> Item:
    reader, units, statement = deck.reader, deck.units, part.statement
    cm_id = reader.ident(statement, "CM", required=False)
    if cm_id is None:
        reader.warn(statement, "no CM marker: the part frame is taken as the CM frame")
        frame, cm_comments = part.frame, []
    else:
        cm = deck.marker(statement, "CM")
        frame, cm_comments = cm.frame, adm_connections.marker_notes(deck, cm)
    im = reader.ident(statement, "IM", required=False)
    if im is not None and im != cm_id:
        reader.warn(statement, "IM differs from CM: the IP inertias are used as if about the CM "
                    "marker", where=statement.find("IM"))
    part.body_frame = frame
    mass = reader.numbers(statement, "MASS", 1)
    if mass is None:
        raise reader.fail(statement.arguments[0] if statement.arguments else
                          _line(statement), statement.label, f"{statement.label} has no MASS",
                          "MASS = <positive number>", "casmech bodies need a positive mass",
                          code="E100")
    inertia = reader.numbers(statement, "IP") or [0.0, 0.0, 0.0]
    if len(inertia) not in (3, 6):
        raise reader.fail(statement.find("IP"), f"{statement.label}.IP", "IP takes 3 or 6 "
                          "values", "xx, yy, zz[, xy, xz, yz]", "see the Adams PART statement")
    inertia = [v * units.inertia * (1 if k < 3 else -1) for k, v in enumerate(inertia)]
    velocity = [(reader.numbers(statement, key, 1) or [0.0])[0] for key in ("VX", "VY", "VZ")]
    omega = [(reader.numbers(statement, key, 1) or [0.0])[0] for key in ("WX", "WY", "WZ")]
    data = {"name": part.name, "mass": mass[0] * units.mass, "inertia": inertia,
            "position": tidy(frame.origin),
            "orientation": {"euler_parameters": tidy(from_matrix(frame.rotation))}}
    if any(velocity):
        data["velocity"] = tidy(np.array(velocity) * units.velocity)
    if any(omega):  # Adams: about the CM marker's axes; casmech: global
        data["angular_velocity"] = tidy(frame.rotation @ np.array(omega) / units.time)
    where = f"PART/{statement.ident} (line {statement.line}), CM marker {cm_id}:"
    return Item(data, [*statement.comments, where, *cm_comments])


def _line(statement: Statement) -> Value:
    return Value(statement.label, statement.line, 1)


def _gravity(deck: Deck, statements: list[Statement]) -> list[float]:
    gravity = [0.0, 0.0, 0.0]
    for statement in statements:
        for k, axis in enumerate("IJK"):
            value = (deck.reader.numbers(statement, f"{axis}GRAVITY", 1)
                     or deck.reader.numbers(statement, f"{axis}GRAV", 1))
            if value is not None:
                gravity[k] = value[0] * deck.units.acceleration
    return gravity


def _by_name(statements: list[Statement]) -> dict[str, list[Statement]]:
    groups: dict[str, list[Statement]] = {}
    for statement in statements:
        groups.setdefault(statement.name, []).append(statement)
    return groups


def _trailer(deck: Deck, statements: list[Statement], trailing: list[str]) -> list[str]:
    lines = ["--- the rest of the Adams deck, not translated (text and comments kept) ---"]
    for statement in statements:
        if statement.line in deck.used:
            continue
        lines += statement.comments
        lines += [f"line {statement.line}: {statement.text[0].strip()}"]
        lines += [f"  {raw.strip()}" for raw in statement.text[1:]]
    return lines + trailing


def _ident(text: str) -> str:
    return str(int(text)) if text.strip().isdigit() else text.strip()


def _translate(deck: Deck, model: Imported, groups: dict[str, list[Statement]]) -> None:
    for part in deck.parts.values():
        if not part.ground:
            model.bodies.append(_body(deck, part))
            deck.used.add(part.statement.line)
    connections = [("JOINT", adm_connections.joint), ("JPRIM", adm_connections.jprim),
                   ("GCON", adm_connections.gcon)]
    joints = {}  # JOINT id -> (its item, its statement), for MOTION
    for name, translate in connections:
        for statement in groups.get(name, []):
            items = translate(deck, statement)
            model.joints += items
            deck.used.update([statement.line] if items else [])
            if name == "JOINT" and items:
                joints[_ident(statement.ident)] = (items[0], statement)
    for statement in groups.get("MOTION", []):
        if adm_motion.motion(deck, statement, joints):
            deck.used.add(statement.line)
    for name, translate in (("SFORCE", adm_forces.sforce),
                            ("SPRINGDAMPER", adm_forces.springdamper),
                            ("BUSHING", adm_loads.bushing),
                            *((key, adm_loads.vector_force) for key in adm_loads.COMPONENTS)):
        for statement in groups.get(name, []):
            items = translate(deck, model, statement, model.joints)
            model.forces += items
            deck.used.update([statement.line] if items else [])


def _header(path: Path, dataset, units_statements: list[Statement]) -> list[str]:
    lines = [f"Imported by `casmech import` from the Adams/Solver dataset {path.name}.",
             f"Title line: {dataset.title}",
             "Body frames are the parts' CM marker frames (IP about their axes); units "
             "converted to SI per UNITS.",
             "Comments come from the deck ('!' lines), next to what they describe; statements "
             "not translated are listed at the end."]
    for statement in units_statements:
        lines += ["", *statement.comments, *(raw.strip() for raw in statement.text)]
    return lines + [""]


def import_adm(path: Path) -> Imported:
    """Translate the dataset at `path`; warnings (not errors) for what is not translated."""
    dataset = parse_adm(read_source(path), str(path))
    reader = Reader(str(path))
    groups = _by_name(dataset.statements)
    units = read_units(groups.get("UNITS", []), reader)
    deck = Deck(dataset, reader, units)
    read_parts(deck, groups.get("PART", []))
    read_markers(deck, groups.get("MARKER", []))
    model = Imported(name=path.stem, description=dataset.title,
                     header=_header(path, dataset, groups.get("UNITS", [])))
    for statement in dataset.statements:
        if statement.name in KNOWN:
            _check_arguments(reader, statement)
        elif statement.name in OUTPUT_ONLY:
            reader.warn(statement, f"{statement.name} not translated (output or graphics only)",
                        code="E101")
        else:
            reader.warn(statement, f"unknown statement {statement.name}", code="E101",
                        hint="translated: " + ", ".join(KNOWN))
    model.gravity = _gravity(deck, groups.get("ACCGRAV", []))
    model.gravity_comments = [c for s in groups.get("ACCGRAV", []) for c in s.comments]
    deck.used.update(s.line for s in (*groups.get("UNITS", []), *groups.get("ACCGRAV", [])))
    _translate(deck, model, groups)
    model.trailer = _trailer(deck, dataset.statements, dataset.trailing_comments)
    model.warnings = reader.warnings
    return model
