"""XML elements with their file, line and column, for the importers of XML formats (URDF, MJCF).

Parsed with the standard library's expat (no third-party parser keeps the line of an element,
and casmech's errors need it). Neither format uses a document type: a DOCTYPE or entity
declaration is refused (E102) before any entity is expanded, so neither entity expansion nor
external entities can happen. Elements nest at most MAX_NESTING deep (E105): the importers walk
the tree recursively.
"""

from __future__ import annotations

from dataclasses import field
from xml.parsers import expat

import numpy as np

from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source

MAX_NESTING = 200  # nested elements (a chain of 200 bodies or links)


@record(frozen=False, eq=False)
class Element:
    """One XML element: tag, attributes, children, its file and where it starts (1-based)."""

    tag: str
    attrib: dict[str, str]
    file: str
    line: int
    col: int
    children: list[Element] = field(default_factory=list)

    def find(self, tag: str) -> Element | None:
        return next((child for child in self.children if child.tag == tag), None)

    def findall(self, tag: str) -> list[Element]:
        return [child for child in self.children if child.tag == tag]

    def iter(self, tag: str | None = None):
        if tag is None or self.tag == tag:
            yield self
        for child in self.children:
            yield from child.iter(tag)


@record
class Format:
    """What the errors of one XML format say: its name, what a file of it looks like, its
    root element and where its reference is."""

    name: str  # "URDF", "MJCF"
    expected: str  # what a well-formed file of the format is
    root: str  # the start tag without a DOCTYPE, e.g. '<robot ...>'
    hint: str  # where the format is specified


def located(file: str, line: int, col: int, code: str, message: str, expected: str | None,
            path: str = "", got: str | None = None, hint: str | None = None) -> ModelError:
    return ModelError([Diagnostic(code, path, message, Source(file, line, col),
                                  expected=expected, got=got, hint=hint)])


class _Refused(Exception):
    pass


class _Deep(Exception):
    def __init__(self, element: Element):
        self.element = element


def parse_xml(text: str, file: str, form: Format) -> Element:
    """The root element of an XML text (E102 with the line and column of a syntax error or a
    declaration, E105 past MAX_NESTING levels)."""
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag, attrib):
        element = Element(tag, attrib, file, parser.CurrentLineNumber,
                          parser.CurrentColumnNumber + 1)
        if len(stack) >= MAX_NESTING:
            raise _Deep(element)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def refuse(*_):
        raise _Refused

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    try:
        parser.Parse(text, True)
    except expat.ExpatError as error:
        raise located(file, error.lineno, error.offset + 1, "E102",
                      f"not well-formed XML: {expat.errors.messages[error.code]}",
                      form.expected,
                      hint="check for a missing quote, '>' or closing tag before this point"
                      ) from None
    except _Deep as deep:
        raise located(file, deep.element.line, deep.element.col, "E105", f"elements nest more "
                      f"than {MAX_NESTING} levels deep", "a shallower tree of bodies",
                      hint=f"casmech reads {form.name} trees up to this depth") from None
    except _Refused:
        raise located(file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "E102",
                      f"a DOCTYPE or entity declaration: {form.name} uses none, and casmech "
                      "does not expand entities", f"{form.root} without <!DOCTYPE>",
                      hint=form.hint) from None
    return roots[0]


def finite_numbers(text: str) -> np.ndarray | None:
    """The whitespace-separated numbers of an attribute; None unless all are finite numbers."""
    try:
        values = np.array([float(word) for word in text.split()], float)
    except ValueError:
        return None
    return values if np.all(np.isfinite(values)) else None


@record(frozen=False)
class Reader:
    """Located access to an XML document's elements; collects warnings (each format's reader
    adds its own accessors)."""

    file: str
    root: Element
    warnings: list[Diagnostic] = field(default_factory=list)
    hint = ""  # the format's reference, the default hint of its errors

    def error(self, element: Element, path: str, message: str, expected: str | None,
              code: str = "E102", got: str | None = None, hint: str | None = None
              ) -> ModelError:
        return located(element.file, element.line, element.col, code, message, expected,
                       path, got, self.hint if hint is None else hint)

    def warn(self, element: Element, path: str, message: str, code: str = "E101",
             hint: str | None = None) -> None:
        self.warnings.append(Diagnostic(code, path, message, Source(element.file, element.line,
                                                                     element.col),
                                        hint=hint, severity="warning"))
