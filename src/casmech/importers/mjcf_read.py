"""Reading an MJCF file: XML elements with their file, line and column, `<include>` expanded.

Parsed with the standard library's expat, as URDF is (importers/urdf_read.py): a DOCTYPE or
entity declaration is refused (E102) before any entity is expanded. `<include file="..."/>`
is replaced by the children of the included file's `<mujoco>` element (MuJoCo's rule: the
path is relative to the main file's folder); an included file must be in that folder or below
(or an allowed folder, `--allow-dir`; E305), is read with the same 16 MiB bound, may not be
included twice (E103), and includes nest at most MAX_DEPTH deep; elements nest at most
MAX_NESTING deep (E105). Every element keeps the file it came from, so errors name the included
file's line.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

import numpy as np

from casmech.errors import Diagnostic, ModelError, Source
from casmech.importers.source import read_source

HINT = "see MuJoCo's XML reference (mujoco.readthedocs.io, XML Reference)"
MAX_DEPTH = 8  # nested <include> levels
MAX_NESTING = 200  # nested elements (a chain of 200 bodies); the tree is walked recursively


@dataclass(eq=False)
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


def located(file: str, line: int, col: int, code: str, message: str, expected: str | None,
            path: str = "", got: str | None = None, hint: str | None = HINT) -> ModelError:
    return ModelError([Diagnostic(code, path, message, Source(file, line, col),
                                  expected=expected, got=got, hint=hint)])


class _Refused(Exception):
    pass


class _Deep(Exception):
    def __init__(self, element: Element):
        self.element = element


def parse_xml(text: str, file: str) -> Element:
    """The root element of an XML text (E102 with the line and column of a syntax error)."""
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
                      "an MJCF file (<mujoco model=\"...\"> with <worldbody>)",
                      hint="check for a missing quote, '>' or closing tag before this point"
                      ) from None
    except _Deep as deep:
        raise located(file, deep.element.line, deep.element.col, "E105", f"elements nest more "
                      f"than {MAX_NESTING} levels deep", "a shallower tree of bodies",
                      hint="casmech reads MJCF trees up to this depth") from None
    except _Refused:
        raise located(file, parser.CurrentLineNumber, parser.CurrentColumnNumber + 1, "E102",
                      "a DOCTYPE or entity declaration: MJCF uses none, and casmech does not "
                      "expand entities", "<mujoco ...> without <!DOCTYPE>") from None
    return roots[0]


def _mujoco(path: Path, file: str, where: Element | None) -> Element:
    root = parse_xml(read_source(path), file)
    if root.tag != "mujoco":
        raise located(file, root.line, root.col, "E102", f"the root element is <{root.tag}>, "
                      "not <mujoco>", "<mujoco model=\"...\">",
                      hint="an MJCF model (or a file it includes) starts with <mujoco>")
    return root


def read_mjcf(path: Path) -> Element:
    """The `<mujoco>` element of an MJCF file with every `<include>` replaced by the included
    file's elements."""
    root = _mujoco(path, str(path), None)
    seen = {path.resolve()}
    _expand(root, path, seen, 1)
    return root


def _expand(element: Element, main: Path, seen: set[Path], depth: int) -> None:
    children = []
    for child in element.children:
        if child.tag != "include":
            _expand(child, main, seen, depth)
            children.append(child)
            continue
        children += _included(child, main, seen, depth)
    element.children = children


def _included(include: Element, main: Path, seen: set[Path], depth: int) -> list[Element]:
    from casmech.schema import files

    name = include.attrib.get("file")
    if not name:
        raise located(include.file, include.line, include.col, "E100", "<include> has no "
                      "'file' attribute", 'file="other.xml"', "include")
    if depth > MAX_DEPTH:
        raise located(include.file, include.line, include.col, "E105", f"includes nest more "
                      f"than {MAX_DEPTH} levels deep", "a shallower include tree", "include",
                      got=name)
    try:
        path = files.resolve(str(main), name)
    except files.NotAllowed as error:
        raise located(include.file, include.line, include.col, "E305", f"included file "
                      f"'{name}': {error.reason}", "a file in the model's folder or below",
                      "include", hint=error.hint) from None
    except FileNotFoundError:
        raise located(include.file, include.line, include.col, "E300", f"included file "
                      f"'{name}' not found (relative to {main.parent})", "an existing file",
                      "include") from None
    if path in seen:
        raise located(include.file, include.line, include.col, "E103", f"'{name}' is "
                      "included twice (or includes itself)", "each file included once",
                      "include")
    seen.add(path)
    root = _mujoco(path, str(path), include)
    _expand(root, main, seen, depth + 1)
    return root.children


@dataclass
class Reader:
    """Located access to an MJCF document's elements; collects warnings."""

    file: str
    root: Element
    warnings: list[Diagnostic] = field(default_factory=list)

    @classmethod
    def read(cls, path: Path) -> Reader:
        return cls(str(path), read_mjcf(path))

    def error(self, element: Element, path: str, message: str, expected: str | None,
              code: str = "E102", got: str | None = None, hint: str | None = HINT
              ) -> ModelError:
        return located(element.file, element.line, element.col, code, message, expected,
                       path, got, hint)

    def warn(self, element: Element, path: str, message: str, code: str = "E101",
             hint: str | None = None) -> None:
        self.warnings.append(Diagnostic(code, path, message, Source(element.file, element.line,
                                                                     element.col),
                                        hint=hint, severity="warning"))

    def numbers(self, element: Element, attrib: dict[str, str], key: str, path: str,
                sizes: tuple[int, ...], default=None) -> np.ndarray | None:
        """The numbers of attribute `key` (from `attrib`, the element's own attributes with
        its defaults), as many as one of `sizes`; `default` when absent."""
        if key not in attrib:
            return None if default is None else np.array(default, float)
        text = attrib[key]
        try:
            values = np.array([float(word) for word in text.split()], float)
        except ValueError:
            values = None
        if values is None or values.size not in sizes or not np.all(np.isfinite(values)):
            counts = " or ".join(str(n) for n in sizes)
            raise self.error(element, f"{path}.{key}", f"'{key}' of <{element.tag}> must be "
                             f"{counts} finite number{'s' if max(sizes) > 1 else ''}",
                             f"{counts} numbers separated by spaces", got=repr(text))
        return values

    def number(self, element: Element, attrib: dict[str, str], key: str, path: str,
               default: float | None = None) -> float | None:
        values = self.numbers(element, attrib, key, path, (1,),
                              None if default is None else (default,))
        return None if values is None else float(values[0])

    def choice(self, element: Element, attrib: dict[str, str], key: str, path: str,
               options: tuple[str, ...], default: str) -> str:
        value = attrib.get(key, default)
        if value not in options:
            raise self.error(element, f"{path}.{key}", f"'{key}' of <{element.tag}> must be one "
                             f"of {', '.join(options)}", ", ".join(options), got=repr(value))
        return value
