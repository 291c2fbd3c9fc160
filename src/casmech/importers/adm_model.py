"""The objects of an Adams dataset the translator needs: units, parts, markers, with their global
frames at t = 0, plus number reading with located errors.

A part's body frame in casmech is its CM marker's frame (the IP inertias are about its axes);
ground is the global frame.
"""

from __future__ import annotations

import re
from dataclasses import field

import numpy as np

from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source, did_you_mean
from casmech.importers.adm_frames import (
    IDENTITY,
    SYSTEMS,
    TABLES,
    Frame,
    Units,
    euler_313,
    from_points,
)
from casmech.importers.adm_parser import Argument, Dataset, Statement, Value

_NUMBER = re.compile(r"^([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([dDrR]?)$")
_VIEW_NAME = re.compile(r"adams_view_name\s*=\s*'([^']+)'")


class Reader:
    """Reads argument values, collecting warnings; raises ModelError for unreadable values."""

    def __init__(self, file: str):
        self.file = file
        self.warnings: list[Diagnostic] = []

    def source(self, line: int, col: int) -> Source:
        return Source(self.file, line, col)

    def fail(self, value: Value | Argument, path: str, message: str, expected: str, hint: str,
             code: str = "E102", got: str | None = None) -> ModelError:
        return ModelError([Diagnostic(code, path, message, self.source(value.line, value.col),
                                      expected=expected, got=got, hint=hint)])

    def warn(self, statement: Statement, message: str, code: str = "E103",
             where: Argument | None = None, hint: str | None = None) -> None:
        line, col = (where.line, where.col) if where else (statement.line, 1)
        self.warnings.append(Diagnostic(code, statement.label, message, self.source(line, col),
                                        got=" ".join(t.strip() for t in statement.text)[:160],
                                        hint=hint, severity="warning"))

    def number(self, value: Value, path: str, angle: bool = False) -> float:
        match = _NUMBER.match(value.text)
        if match is None or (match.group(2) and not angle):
            raise self.fail(value, path, f"'{value.text}' is not a number", "a number such as "
                            "2, -0.5 or 1.0E-3" + (" (angles: 90D for degrees)" if angle else ""),
                            "Adams numbers have no units; angles take a D suffix for degrees")
        number = float(match.group(1))
        return np.deg2rad(number) if match.group(2).upper() == "D" else number

    def numbers(self, statement: Statement, key: str, count: int | None = None,
                angle: bool = False) -> list[float] | None:
        argument = statement.find(key)
        if argument is None:
            return None
        path = f"{statement.label}.{key}"
        if count is not None and len(argument.values) != count:
            raise self.fail(argument, path, f"{key} takes {count} values", f"{count} numbers "
                            "separated by commas", "e.g. QP = 0, 0, 1",
                            got=f"{len(argument.values)} values")
        values = [self.number(v, path, angle) for v in argument.values]
        if angle and any(v != 0 and not _NUMBER.match(x.text).group(2)
                         for v, x in zip(values, argument.values, strict=True)):
            self.warn(statement, f"{key} has an angle without a D suffix: read as radians "
                      "(Adams's rule)", where=argument, hint="write 90D for degrees")
        return values

    def ident(self, statement: Statement, key: str, required: bool = True) -> int | None:
        argument = statement.find(key)
        if argument is None:
            if not required:
                return None
            raise ModelError([Diagnostic(
                "E100", statement.label, f"{statement.label} needs {key} = <id>",
                self.source(statement.line, 1), expected=f"{key} = <marker or part id>",
                hint=f"add ', {key} = ...' on a continuation line")])
        value = argument.values[0]
        if not value.text.isdigit():
            raise self.fail(value, f"{statement.label}.{key}", f"'{value.text}' is not an id",
                            "a whole number", "ids are the numbers after the slash")
        return int(value.text)


def view_name(statement: Statement, fallback: str) -> str:
    """The adams_view_name in the statement's comments (Adams/View writes one), else fallback."""
    for comment in reversed(statement.comments):
        match = _VIEW_NAME.search(comment)
        if match:
            name = re.sub(r"\W", "_", match.group(1).split(".")[0]).lower()
            return name if re.match(r"[a-z_]", name) else f"_{name}"
    return fallback


@record(frozen=False)
class Part:
    statement: Statement
    name: str
    frame: Frame  # the part frame (LPRF), global
    ground: bool
    body_frame: Frame = IDENTITY  # CM marker frame (global); ground: identity


@record(frozen=False)
class Marker:
    statement: Statement
    part: int
    local: Frame
    frame: Frame = IDENTITY  # global, set once parts are placed


@record(frozen=False)
class Deck:
    dataset: Dataset
    reader: Reader
    units: Units
    parts: dict[int, Part] = field(default_factory=dict)
    markers: dict[int, Marker] = field(default_factory=dict)
    used: set[int] = field(default_factory=set)  # statement lines translated
    names: set[str] = field(default_factory=lambda: {"ground"})  # casmech names given so far

    def name_for(self, statement: Statement, fallback: str) -> str:
        """A unique casmech name: the adams_view_name if any, else `fallback` (numbered on a
        clash, since casmech names are unique across bodies, joints and forces)."""
        name = view_name(statement, fallback)
        if name in self.names:
            name = fallback
        base, k = name, 2
        while name in self.names:
            name, k = f"{base}_{k}", k + 1
        self.names.add(name)
        return name

    def marker(self, statement: Statement, key: str) -> Marker:
        ident = self.reader.ident(statement, key)
        if ident not in self.markers:
            argument = statement.find(key)
            raise self.reader.fail(argument.values[0], f"{statement.label}.{key}",
                                   f"MARKER/{ident} is not defined", "the id of a MARKER "
                                   "statement in this file", did_you_mean(
                                       str(ident), [str(m) for m in self.markers])
                                   or "define it with MARKER/id, PART = ...", code="E300")
        return self.markers[ident]

    def marker_by_id(self, statement: Statement, ident: int) -> Marker:
        """A marker named inside a FUNCTION (located at the statement)."""
        if ident not in self.markers:
            raise self.reader.fail(Value(str(ident), statement.line, 1), statement.label,
                                   f"MARKER/{ident} is not defined", "the id of a MARKER "
                                   "statement in this file", "check the FUNCTION's markers",
                                   code="E300")
        return self.markers[ident]

    def part_name(self, marker: Marker) -> str:
        return self.parts[marker.part].name


def read_units(statements: list[Statement], reader: Reader) -> Units:
    chosen = {"FORCE": "NEWTON", "MASS": "KILOGRAM", "LENGTH": "METER", "TIME": "SECOND"}
    for statement in statements:
        for argument in statement.arguments:
            text = argument.values[0].text.upper() if argument.values else ""
            if argument.key == "SYSTEM" and text in SYSTEMS:
                chosen.update(zip(("FORCE", "MASS", "LENGTH", "TIME"), SYSTEMS[text], strict=True))
            elif argument.key in TABLES and text in TABLES[argument.key]:
                chosen[argument.key] = text
            else:
                reader.warn(statement, f"UNITS argument {argument.key} = {text} not translated",
                            where=argument, hint="known: FORCE, MASS, LENGTH, TIME with "
                            "Adams unit names, SYSTEM = MKS|MMKS|CGS|IPS|FPS")
    return Units(**{key.lower(): TABLES[key][chosen[key]] for key in TABLES})


def placement(statement: Statement, reader: Reader, units: Units, position: str,
              z_key: str, x_key: str) -> Frame:
    """QP/QG + REULER or z/x points of a MARKER or PART, in its parent frame."""
    origin = np.array(reader.numbers(statement, position, 3) or [0.0, 0, 0]) * units.length
    angles = reader.numbers(statement, "REULER", 3, angle=True)
    z_point = reader.numbers(statement, z_key, 3)
    if angles is not None:
        return Frame(origin, euler_313(*angles))
    if z_point is None:
        return Frame(origin, np.eye(3))
    x_point = reader.numbers(statement, x_key, 3)
    rotation = from_points(origin, np.array(z_point) * units.length,
                           None if x_point is None else np.array(x_point) * units.length)
    if rotation is None:
        argument = statement.find(z_key)
        raise reader.fail(argument, f"{statement.label}.{z_key}", "the axis points coincide "
                          "with the origin or with each other", "a point on +z away from the "
                          "origin, and one in the x/z half-plane off the z axis",
                          "check the coordinates", code="E103")
    return Frame(origin, rotation)


def read_parts(deck: Deck, statements: list[Statement]) -> None:
    reader = deck.reader
    for statement in statements:
        ident = int(statement.ident) if statement.ident.isdigit() else None
        if ident is None:
            raise reader.fail(Value(statement.ident, statement.line, 1), statement.label,
                              "a PART needs a numeric id", "PART/<id>", "e.g. PART/2, MASS = 1")
        ground = statement.find("GROUND") is not None
        name = "ground" if ground else deck.name_for(statement, f"part_{statement.ident}")
        frame = placement(statement, reader, deck.units, "QG", "ZG", "XG")
        deck.parts[ident] = Part(statement, name, frame, ground)


def read_markers(deck: Deck, statements: list[Statement]) -> None:
    reader = deck.reader
    for statement in statements:
        part = reader.ident(statement, "PART")
        if part not in deck.parts:
            argument = statement.find("PART")
            raise reader.fail(argument.values[0], f"{statement.label}.PART",
                              f"PART/{part} is not defined", "the id of a PART statement",
                              did_you_mean(str(part), [str(p) for p in deck.parts])
                              or "define the part with PART/id", code="E300")
        local = placement(statement, reader, deck.units, "QP", "ZP", "XP")
        marker = Marker(statement, part, local, deck.parts[part].frame.compose(local))
        deck.markers[int(statement.ident)] = marker
