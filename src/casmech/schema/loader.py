"""YAML text -> plain data plus a source map (path -> file:line:col).

PyYAML composes the node tree with its SafeLoader; we build the Python data ourselves so that every
value and every mapping key keeps its location. Mapping keys are taken verbatim as strings (so
`on:` or `1:` stay the names that were written). Duplicate keys are reported (E002) and the first
value is kept; syntax errors (E001) and a top level that is not a mapping (E003) are fatal.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import yaml

from casmech.errors import Diagnostic, ModelError, Source, UsageError

Path = tuple[str | int, ...]

# tags whose scalars become Python values; any other scalar (str, timestamp, custom tag) stays text
_CONSTRUCTED = {f"tag:yaml.org,2002:{name}" for name in ("int", "float", "bool", "null")}
_CONSTRUCTOR = yaml.constructor.SafeConstructor()


def format_path(path: Path) -> str:
    """('joints', 0, 'driver', 'angle') -> 'joints[0].driver.angle'."""
    text = ""
    for step in path:
        text += f"[{step}]" if isinstance(step, int) else f".{step}" if text else str(step)
    return text


@dataclass(frozen=True)
class ScalarText:
    """Where a string scalar's characters are: `start` is the source of its first character when
    the text maps 1:1 onto the file (single line, no escapes), else None."""

    start: Source | None


@dataclass
class SourceMap:
    values: dict[Path, Source] = field(default_factory=dict)
    keys: dict[Path, Source] = field(default_factory=dict)
    scalars: dict[Path, ScalarText] = field(default_factory=dict)


@dataclass(frozen=True)
class Document:
    data: dict[str, Any]
    file: str
    text: str
    source_map: SourceMap
    diagnostics: tuple[Diagnostic, ...] = ()

    def locate(self, path: Path) -> Source:
        """The source of the value at `path`, or of its nearest known ancestor."""
        for end in range(len(path), -1, -1):
            source = self.source_map.values.get(tuple(path[:end]))
            if source is not None:
                return source
        return Source(self.file, 1, 1)

    def locate_key(self, path: Path) -> Source:
        """The source of the mapping key naming `path` (falls back to `locate`)."""
        return self.source_map.keys.get(tuple(path)) or self.locate(path)

    def source_in_scalar(self, path: Path, offset: int) -> Source:
        """The source of character `offset` of the string scalar at `path`."""
        scalar = self.source_map.scalars.get(tuple(path))
        if scalar is None or scalar.start is None:
            return self.locate(path)
        return Source(scalar.start.file, scalar.start.line, scalar.start.col + offset)


def _source(file: str, mark: yaml.Mark) -> Source:
    return Source(file, mark.line + 1, mark.column + 1)


class _Builder:
    def __init__(self, file: str, text: str):
        self.file = file
        self.text = text
        self.map = SourceMap()
        self.diagnostics: list[Diagnostic] = []

    def build(self, node: yaml.Node, path: Path) -> Any:
        self.map.values[path] = _source(self.file, node.start_mark)
        if isinstance(node, yaml.MappingNode):
            return self.mapping(node, path)
        if isinstance(node, yaml.SequenceNode):
            return [self.build(item, (*path, i)) for i, item in enumerate(node.value)]
        if node.tag in _CONSTRUCTED:
            return _CONSTRUCTOR.construct_object(node)
        self.map.scalars[path] = ScalarText(self.scalar_start(node))
        return node.value

    def scalar_start(self, node: yaml.ScalarNode) -> Source | None:
        start, end = node.start_mark, node.end_mark
        quote = 1 if node.style in ("'", '"') else 0
        raw = self.text[start.index + quote : end.index - quote]
        if start.line != end.line or node.style not in (None, "'", '"') or raw != node.value:
            return None
        return Source(self.file, start.line + 1, start.column + 1 + quote)

    def mapping(self, node: yaml.MappingNode, path: Path) -> dict[str, Any]:
        data: dict[str, Any] = {}
        for key_node, value_node in node.value:
            key_source = _source(self.file, key_node.start_mark)
            if not isinstance(key_node, yaml.ScalarNode):
                self.error("E102", path, key_source, "a mapping key must be a name")
                continue
            key = key_node.value
            child = (*path, key)
            if key in data:
                first = self.map.keys[child]
                self.error(
                    "E002",
                    child,
                    key_source,
                    f"duplicate key '{key}' (first at line {first.line})",
                    hint="remove one of them; the first value is used",
                )
                continue
            self.map.keys[child] = key_source
            data[key] = self.build(value_node, child)
        return data

    def error(self, code: str, path: Path, source: Source, message: str, **extra: str) -> None:
        self.diagnostics.append(Diagnostic(code, format_path(path), message, source, **extra))


def _syntax_error(error: yaml.YAMLError, file: str, text: str) -> Diagnostic:
    mark = getattr(error, "problem_mark", None)
    if mark is not None:
        source = _source(file, mark)
    elif isinstance(error, yaml.reader.ReaderError):
        before = text[: error.position]
        source = Source(file, before.count("\n") + 1, len(before) - before.rfind("\n"))
    else:
        source = Source(file, 1, 1)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    context = getattr(error, "context", None)
    message = f"{problem} ({context})" if context else problem
    return Diagnostic("E001", "", message, source)


def load_document(text: str, file: str = "<string>") -> Document:
    """Parse YAML text into a Document; raises ModelError for E001 and E003."""
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.YAMLError as error:
        raise ModelError([_syntax_error(error, file, text)]) from None
    if not isinstance(root, yaml.MappingNode):
        got = "an empty document" if root is None else f"a {_node_kind(root)}"
        source = Source(file, 1, 1) if root is None else _source(file, root.start_mark)
        message = "a model file must be a mapping of keys (casmech, name, bodies, ...)"
        raise ModelError([Diagnostic("E003", "", message, source, "a mapping", got)])
    builder = _Builder(file, text)
    data = builder.build(root, ())
    return Document(data, file, text, builder.map, tuple(builder.diagnostics))


def _node_kind(node: yaml.Node) -> str:
    return "list" if isinstance(node, yaml.SequenceNode) else "scalar"


def load_file(path: str) -> Document:
    """Read and parse a model file; an unreadable file is a UsageError, bad UTF-8 is E001."""
    try:
        with open(path, encoding="utf-8") as stream:
            text = stream.read()
    except UnicodeDecodeError as error:
        message = f"the file is not UTF-8 text ({error.reason})"
        raise ModelError([Diagnostic("E001", "", message, Source(str(path), 1, 1))]) from None
    except FileNotFoundError:
        raise UsageError(f"no such file: {path}") from None
    except OSError as error:
        raise UsageError(f"cannot read model file {path}: {error.strerror or error}") from None
    return load_document(text, str(path))
