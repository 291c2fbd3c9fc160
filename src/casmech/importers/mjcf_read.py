"""Reading an MJCF file: XML elements with their file, line and column, `<include>` expanded.

Parsed by importers/xml_read.py, as URDF is: a DOCTYPE or entity declaration is refused (E102)
before any entity is expanded. `<include file="..."/>`
is replaced by the children of the included file's `<mujoco>` element (MuJoCo's rule: the
path is relative to the main file's folder); an included file must be in that folder or below
(or an allowed folder, `--allow-dir`; E305), is read with the same 16 MiB bound, may not be
included twice (E103), and includes nest at most MAX_DEPTH deep; elements nest at most
xml_read.MAX_NESTING deep (E105). Every element keeps the file it came from, so errors name
the included file's line.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.records import record
from casmech.errors import ModelError
from casmech.importers import xml_read
from casmech.importers.source import read_source
from casmech.importers.xml_read import Element, Format, finite_numbers, parse_xml

HINT = "see MuJoCo's XML reference (mujoco.readthedocs.io, XML Reference)"
MAX_DEPTH = 8  # nested <include> levels


MJCF = Format("MJCF", "an MJCF file (<mujoco model=\"...\"> with <worldbody>)",
              "<mujoco ...>", HINT)


def located(file: str, line: int, col: int, code: str, message: str, expected: str | None,
            path: str = "", got: str | None = None, hint: str | None = HINT) -> ModelError:
    return xml_read.located(file, line, col, code, message, expected, path, got, hint)


def _mujoco(path: Path, file: str, where: Element | None) -> Element:
    root = parse_xml(read_source(path), file, MJCF)
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


@record(frozen=False)
class Reader(xml_read.Reader):
    """Located access to an MJCF document's elements; collects warnings."""

    hint = HINT

    @classmethod
    def read(cls, path: Path) -> Reader:
        return cls(str(path), read_mjcf(path))

    def numbers(self, element: Element, attrib: dict[str, str], key: str, path: str,
                sizes: tuple[int, ...], default=None) -> np.ndarray | None:
        """The numbers of attribute `key` (from `attrib`, the element's own attributes with
        its defaults), as many as one of `sizes`; `default` when absent."""
        if key not in attrib:
            return None if default is None else np.array(default, float)
        text = attrib[key]
        values = finite_numbers(text)
        if values is None or values.size not in sizes:
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
