"""Reading a URDF file: XML elements with their source lines, and located attribute values.

The XML is parsed by the standard library's expat (no third-party parser keeps the line of an
element, and casmech's errors need it). A URDF has no DOCTYPE: a document type or entity
declaration is refused (E102) before any entity is expanded, so neither entity expansion nor
external entities can happen. The file is read with importers.source.read_source's 16 MiB bound
(E006).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from casmech.errors import Diagnostic, ModelError, Source
from casmech.importers.source import read_source

HINT = "see the URDF specification (wiki.ros.org/urdf/XML)"


@dataclass
class Element:
    """One XML element: tag, attributes, children, where it starts (1-based line and column)."""

    tag: str
    attrib: dict[str, str]
    line: int
    col: int
    children: list[Element] = field(default_factory=list)

    def find(self, tag: str) -> Element | None:
        return next((child for child in self.children if child.tag == tag), None)

    def findall(self, tag: str) -> list[Element]:
        return [child for child in self.children if child.tag == tag]


class _Refused(Exception):
    def __init__(self, message: str):
        self.message = message


def parse_xml(text: str, file: str) -> Element:
    """The root element of an XML text (E102 with the line and column of a syntax error)."""
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag, attrib):
        element = Element(tag, attrib, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def refuse(*_):
        raise _Refused("a DOCTYPE or entity declaration: URDF uses none, and casmech does not "
                       "expand entities")

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    try:
        parser.Parse(text, True)
    except expat.ExpatError as error:
        raise located(file, error.lineno, error.offset + 1, "E102",
                      f"not well-formed XML: {expat.errors.messages[error.code]}",
                      "a URDF file (<robot name=\"...\"> with <link> and <joint> elements)",
                      hint="check for a missing quote, '>' or closing tag before this point"
                      ) from None
    except _Refused as refused:
        raise located(file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "E102",
                      refused.message, "<robot ...> without <!DOCTYPE>") from None
    return roots[0]


def located(file: str, line: int, col: int, code: str, message: str, expected: str | None,
            path: str = "", got: str | None = None, hint: str | None = HINT) -> ModelError:
    return ModelError([Diagnostic(code, path, message, Source(file, line, col),
                                  expected=expected, got=got, hint=hint)])


@dataclass
class Reader:
    """Located access to a URDF document's elements; collects warnings."""

    file: str
    root: Element
    warnings: list[Diagnostic] = field(default_factory=list)

    @classmethod
    def read(cls, path: Path) -> Reader:
        file = str(path)
        root = parse_xml(read_source(path), file)
        if root.tag != "robot":
            raise located(file, root.line, root.col, "E102", f"the root element is "
                          f"<{root.tag}>, not <robot>", "<robot name=\"...\">",
                          hint="a .xacro file must be expanded first: xacro robot.urdf.xacro "
                          "> robot.urdf")
        return cls(file, root)

    def source(self, element: Element) -> Source:
        return Source(self.file, element.line, element.col)

    def error(self, element: Element, path: str, message: str, expected: str | None,
              code: str = "E102", got: str | None = None, hint: str | None = HINT
              ) -> ModelError:
        return located(self.file, element.line, element.col, code, message, expected, path,
                       got, hint)

    def warn(self, element: Element, path: str, message: str, code: str = "E101",
             hint: str | None = None) -> None:
        self.warnings.append(Diagnostic(code, path, message, self.source(element), hint=hint,
                                        severity="warning"))

    def text(self, element: Element, path: str, key: str, default: str | None = None) -> str:
        value = element.attrib.get(key, default)
        if value is None:
            raise self.error(element, path, f"<{element.tag}> has no '{key}' attribute",
                             f'{key}="..."', code="E100")
        return value

    def numbers(self, element: Element | None, path: str, key: str, size: int,
                default: tuple[float, ...] | None = None) -> np.ndarray:
        """`size` finite numbers from the attribute `key` (whitespace-separated)."""
        if element is None or key not in element.attrib:
            if default is None:
                raise self.error(element, path, f"<{element.tag}> has no '{key}' attribute",
                                 f'{key}="{" ".join(["0"] * size)}"', code="E100")
            return np.array(default, float)
        text = element.attrib[key]
        try:
            values = np.array([float(word) for word in text.split()], float)
        except ValueError:
            values = None
        if values is None or values.size != size or not np.all(np.isfinite(values)):
            raise self.error(element, path, f"'{key}' of <{element.tag}> must be {size} finite "
                             f"number{'s' if size > 1 else ''}", f"{size} numbers separated "
                             "by spaces", got=repr(text))
        return values

    def number(self, element: Element | None, path: str, key: str,
               default: float | None = None) -> float:
        return float(self.numbers(element, path, key, 1,
                                  None if default is None else (default,))[0])
