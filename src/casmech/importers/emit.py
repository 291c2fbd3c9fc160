"""An imported model as casmech YAML text, with the source's comments kept as YAML comments.

The importers fill an `Imported` (sections of items, each item with the comment lines that stood
above it in the source); `to_yaml` writes it in the order of MODEL_FORMAT.md. Numbers are written
with repr (shortest text that reads back to the same float), strings as expressions unquoted
when they are plain, vectors in flow style.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from typing import Any

from casmech.errors import Diagnostic

_PLAIN = re.compile(r"^[A-Za-z_][A-Za-z0-9_ .]*$")


@dataclass
class Item:
    data: dict[str, Any]
    comments: list[str] = field(default_factory=list)


@dataclass
class Imported:
    name: str
    description: str
    header: list[str]  # comment lines at the top (where the model came from)
    parameters: list[tuple[str, Any, str]] = field(default_factory=list)  # name, value, comment
    gravity: list[float] | None = None
    gravity_comments: list[str] = field(default_factory=list)
    bodies: list[Item] = field(default_factory=list)
    joints: list[Item] = field(default_factory=list)
    forces: list[Item] = field(default_factory=list)
    analysis: Item | None = None
    trailer: list[str] = field(default_factory=list)  # comments of what was not translated
    warnings: list[Diagnostic] = field(default_factory=list)


def scalar(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return repr(value)
    text = str(value)
    if _PLAIN.match(text) and text.lower() not in {"true", "false", "null", "yes", "no", "on",
                                                    "off"}:
        return text
    return json.dumps(text)


def flow(value: Any) -> str:
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k}: {flow(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(flow(v) for v in value) + "]"
    return scalar(value)


def comment_lines(comments: list[str], indent: str) -> list[str]:
    return [f"{indent}#{' ' + c if c else ''}".rstrip() for c in comments]


def _item(item: Item) -> list[str]:
    lines = comment_lines(item.comments, "  ")
    for k, (key, value) in enumerate(item.data.items()):
        lead = "  - " if k == 0 else "    "
        if isinstance(value, dict) and any(isinstance(v, dict) for v in value.values()):
            lines.append(f"{lead}{key}:")
            lines += [f"      {sub}: {flow(v)}" for sub, v in value.items()]
        else:
            lines.append(f"{lead}{key}: {flow(value)}")
    return lines


def _section(title: str, items: list[Item]) -> list[str]:
    if not items:
        return []
    lines = ["", f"{title}:"]
    for item in items:
        lines += _item(item)
    return lines


def to_yaml(model: Imported) -> str:
    lines = comment_lines(model.header, "")
    lines += ["casmech: 1", f"name: {scalar(model.name)}",
              f"description: {json.dumps(model.description)}"]
    if model.parameters:
        lines += ["", "parameters:"]
        lines += [f"  {name}: {scalar(value)}" + (f"  # {note}" if note else "")
                  for name, value, note in model.parameters]
    if model.gravity is not None:
        lines += ["", *comment_lines(model.gravity_comments, ""),
                  f"gravity: {flow(model.gravity)}"]
    lines += _section("bodies", model.bodies)
    lines += _section("joints", model.joints)
    lines += _section("forces", model.forces)
    if model.analysis is not None:
        lines += [""] + comment_lines(model.analysis.comments, "") + ["analysis:"]
        lines += [f"  {key}: {scalar(value)}" for key, value in model.analysis.data.items()]
    if model.trailer:
        lines += [""] + comment_lines(model.trailer, "")
    return "\n".join(lines) + "\n"
