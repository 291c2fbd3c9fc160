"""Reading a URDF file: XML elements with their source lines, and located attribute values.

The XML is parsed by importers/xml_read.py (expat, with lines; a DOCTYPE or entity declaration
is refused, E102, before any entity is expanded). The file is read with
importers.source.read_source's 16 MiB bound (E006).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from casmech.core.records import record
from casmech.errors import ModelError
from casmech.importers import xml_read
from casmech.importers.source import read_source
from casmech.importers.xml_read import Element, Format, finite_numbers, parse_xml

HINT = "see the URDF specification (wiki.ros.org/urdf/XML)"
URDF = Format("URDF", "a URDF file (<robot name=\"...\"> with <link> and <joint> elements)",
              "<robot ...>", HINT)


def located(file: str, line: int, col: int, code: str, message: str, expected: str | None,
            path: str = "", got: str | None = None, hint: str | None = HINT) -> ModelError:
    return xml_read.located(file, line, col, code, message, expected, path, got, hint)


@record(frozen=False)
class Reader(xml_read.Reader):
    """Located access to a URDF document's elements; collects warnings."""

    hint = HINT

    @classmethod
    def read(cls, path: Path) -> Reader:
        file = str(path)
        root = parse_xml(read_source(path), file, URDF)
        if root.tag != "robot":
            raise located(file, root.line, root.col, "E102", f"the root element is "
                          f"<{root.tag}>, not <robot>", "<robot name=\"...\">",
                          hint="a .xacro file must be expanded first: xacro robot.urdf.xacro "
                          "> robot.urdf")
        return cls(file, root)

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
        values = finite_numbers(text)
        if values is None or values.size != size:
            raise self.error(element, path, f"'{key}' of <{element.tag}> must be {size} finite "
                             f"number{'s' if size > 1 else ''}", f"{size} numbers separated "
                             "by spaces", got=repr(text))
        return values

    def number(self, element: Element | None, path: str, key: str,
               default: float | None = None) -> float:
        return float(self.numbers(element, path, key, 1,
                                  None if default is None else (default,))[0])
