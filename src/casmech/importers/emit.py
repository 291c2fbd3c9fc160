"""An imported model as casmech YAML text, with the source's comments kept as YAML comments.

The importers fill an `Imported` (sections of items, each item with the comment lines that stood
above it in the source); `to_yaml` writes it in the order of docs/format.md. Every key and
value goes through PyYAML's serializer (numbers in the shortest text that reads back to the same
float, strings quoted whenever YAML would read them as anything else, vectors in flow style);
comments are split at every YAML line break and stripped of characters YAML does not allow, so
no text of the source can become a key of the model (a `comment` holding
"\\nforces:\\n  - ..." stays a comment). The model's name is made an identifier.
"""

from __future__ import annotations

import math
import re
from dataclasses import field
from pathlib import Path
from typing import Any

import yaml

from casmech.core.records import record
from casmech.errors import Diagnostic

LINE_BREAKS = re.compile("\r\n|[\r\n\x85\u2028\u2029]")  # every line break YAML knows
NOT_PRINTABLE = re.compile("[^\x09\x20-\x7e\xa0-\ud7ff\ue000-\ufffd\U00010000-\U0010ffff]")
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


@record(frozen=False)
class Item:
    data: dict[str, Any]
    comments: list[str] = field(default_factory=list)


@record(frozen=False)
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
    mesh_folder: Path | None = None  # meshes are named outside the YAML's folder, under this


class _Dumper(yaml.SafeDumper):
    """Floats as Python's repr (the shortest text that reads back to the same double); numpy
    numbers as Python numbers."""


def _float(dumper: yaml.SafeDumper, value: float) -> yaml.ScalarNode:
    if not math.isfinite(value):
        return dumper.represent_float(value)
    text = repr(float(value))
    if "e" in text and "." not in text.split("e")[0]:  # 1e-05: YAML 1.1 needs 1.0e-05
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return dumper.represent_scalar("tag:yaml.org,2002:float", text)


def _flat(value) -> bool:
    return not isinstance(value, dict) and (not isinstance(value, list | tuple)
                                            or all(_flat(item) for item in value))


def _text(dumper: yaml.SafeDumper, value: str) -> yaml.ScalarNode:
    """Text with a line break or an unprintable character is double-quoted (escaped): in a
    plain or single-quoted scalar a reader folds NEL, LS and PS into spaces."""
    style = '"' if LINE_BREAKS.search(value) or NOT_PRINTABLE.search(value) or \
        "\ufeff" in value else None
    return dumper.represent_scalar("tag:yaml.org,2002:str", value, style=style)


_Dumper.add_representer(str, _text)
_Dumper.add_representer(float, _float)
_Dumper.add_representer(dict, lambda d, v: d.represent_mapping(
    "tag:yaml.org,2002:map", v.items(), flow_style=False))  # mappings in block style
for _sequence in (list, tuple):  # lists of numbers (vectors, matrices) in flow style
    _Dumper.add_representer(_sequence, lambda d, v: d.represent_sequence(
        "tag:yaml.org,2002:seq", list(v), flow_style=_flat(v)))
try:  # numpy scalars from the importers' arithmetic
    import numpy as np

    _Dumper.add_multi_representer(np.floating, lambda d, v: _float(d, float(v)))
    _Dumper.add_multi_representer(np.integer, lambda d, v: d.represent_int(int(v)))
    _Dumper.add_multi_representer(np.bool_, lambda d, v: d.represent_bool(bool(v)))
except ImportError:  # pragma: no cover - numpy is a dependency
    pass


def dump(value: Any) -> str:
    """YAML text of a value: mappings in block style, lists of numbers in flow style."""
    return yaml.dump(value, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=10_000)


def comment_lines(comments: list[str], indent: str) -> list[str]:
    """Each comment as `#` lines: split at every line break, unprintable characters escaped."""
    lines = []
    for comment in comments:
        for part in LINE_BREAKS.split(str(comment)):
            part = NOT_PRINTABLE.sub(lambda m: m.group().encode("unicode_escape").decode(),
                                     part)
            lines.append(f"{indent}#{' ' + part if part else ''}".rstrip())
    return lines


def identifier(name: str, fallback: str = "imported") -> str:
    """`name` as a model name: characters other than letters, digits and _ become _."""
    text = re.sub(r"\W", "_", str(name), flags=re.ASCII).strip("_") or fallback
    return text if NAME.match(text) else f"m_{text}"


def _indented(text: str, indent: str) -> list[str]:
    return [indent + line if line else line for line in text.rstrip("\n").split("\n")]


def _item(item: Item) -> list[str]:
    return comment_lines(item.comments, "  ") + _indented(dump([item.data]), "  ")


def _section(title: str, items: list[Item]) -> list[str]:
    if not items:
        return []
    lines = ["", f"{title}:"]
    for item in items:
        lines += _item(item)
    return lines


def _parameters(parameters: list[tuple[str, Any, str]]) -> list[str]:
    lines = ["", "parameters:"]
    for name, value, note in parameters:
        lines += comment_lines([note] if note else [], "  ")
        lines += _indented(dump({name: value}), "  ")
    return lines


def to_yaml(model: Imported) -> str:
    lines = comment_lines(model.header, "")
    lines += dump({"casmech": 1, "name": identifier(model.name),
                   "description": str(model.description)}).rstrip("\n").split("\n")
    if model.parameters:
        lines += _parameters(model.parameters)
    if model.gravity is not None:
        lines += ["", *comment_lines(model.gravity_comments, ""),
                  *dump({"gravity": list(model.gravity)}).rstrip("\n").split("\n")]
    lines += _section("bodies", model.bodies) or ["", "bodies: []"]  # a model may have none
    lines += _section("joints", model.joints)
    lines += _section("forces", model.forces)
    if model.analysis is not None:
        lines += [""] + comment_lines(model.analysis.comments, "")
        lines += dump({"analysis": dict(model.analysis.data)}).rstrip("\n").split("\n")
    if model.trailer:
        lines += [""] + comment_lines(model.trailer, "")
    return "\n".join(lines) + "\n"
