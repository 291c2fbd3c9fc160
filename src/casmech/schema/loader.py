"""YAML text -> plain data plus a source map (path -> file:line:col).

The document is built from the parser's event stream (libyaml's when PyYAML has it), without
recursion, so that every value and every mapping key keeps its location and the input is
bounded before it costs time or memory (limits below, each error E006 at its place):

- values are read as YAML 1.2 reads them: a plain `1:30`, `0x10`, `010`, `1_000`, `yes`/`on`,
  or a date, which YAML 1.1 (PyYAML) turns silently into 90, 16, 8, 1000, true or a date, is
  E004 with the spelling to use (all of them are reported, then reading stops); a tag
  (`!!python/...`, `!custom`) is E005; `!!str` is text;
- mapping keys are taken verbatim as strings (so `on:` or `1:` stay the names that were
  written); duplicate keys are reported (E002) and the first value is kept;
- syntax errors (E001), a top level that is not a mapping (E003) and limits (E006) are fatal.
"""

from __future__ import annotations

import functools
import math
import re
from dataclasses import field
from typing import Any

import yaml

from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source, UsageError
from casmech.schema import files

Path = tuple[str | int, ...]

# Limits of the YAML layer (E006). A model of the gallery is 3-5 kB with at most 8 levels of
# nesting and a few hundred values; a 1000-body model written out in full is 80 kB.
MAX_MODEL_BYTES = files.MAX_MODEL_BYTES  # the whole file
MAX_DEPTH = 32  # nested mappings and lists: the format uses at most 10; keeps every recursive
#                 walk of the data (validation, repeat, components) far from Python's limit
MAX_VALUES = 400_000  # values after alias expansion: a 2 MiB model written out holds ~300 000
#                       (~100 MB with their source map); a "billion laughs" of nested aliases
#                       stops here instead of filling memory

_PARSER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)  # libyaml when PyYAML was built with it
_LIBYAML_DEPTH = "exceeded maximum nesting depth"  # libyaml's own nesting limit (load_document)
_RESOLVER = yaml.resolver.Resolver()  # YAML 1.1's implicit types: to recognise the surprises
_CORE = "tag:yaml.org,2002:"
_TEXT_TAGS = {"!", f"{_CORE}str"}  # tags that only say "text"
_COLLECTION_TAGS = {f"{_CORE}map", f"{_CORE}seq"}
_BOOL = {"true": True, "True": True, "TRUE": True, "false": False, "False": False,
         "FALSE": False}
_INTEGER = re.compile(r"[-+]?(0|[1-9][0-9]*)\Z")
_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?\Z")
_SPECIAL = {".inf": math.inf, ".Inf": math.inf, ".INF": math.inf, ".nan": math.nan,
            ".NaN": math.nan, ".NAN": math.nan}


def format_path(path: Path) -> str:
    """('joints', 0, 'driver', 'angle') -> 'joints[0].driver.angle'."""
    text = ""
    for step in path:
        text += f"[{step}]" if isinstance(step, int) else f".{step}" if text else str(step)
    return text


@record
class ScalarText:
    """Where a string scalar's characters are: `start` is the source of its first character when
    the text maps 1:1 onto the file (single line, no escapes), else None."""

    start: Source | None


@record(frozen=False)
class SourceMap:
    """Where each value, key and scalar of a document was written (path -> file:line:col),
    and the values written as null."""

    values: dict[Path, Source] = field(default_factory=dict)
    keys: dict[Path, Source] = field(default_factory=dict)
    scalars: dict[Path, ScalarText] = field(default_factory=dict)
    nulls: frozenset[Path] = frozenset()  # values written as null or ~ (not left empty)


@record
class Document:
    """A YAML document read: its data, file, text, source map and reading's findings."""

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


def _source(file: str, mark) -> Source:
    return Source(file, mark.line + 1, mark.column + 1)


# ------------------------------------------------------------------------------- scalars
# YAML 1.1 spelling -> what to write instead (E004)
SURPRISES = {
    "int": "YAML 1.1 reads this as an integer in another base or with separators ('1:30' is "
           "90, '0x10' 16, '010' 8, '1_000' 1000); write the decimal number, or quote it",
    "float": "YAML 1.1 reads this as a sexagesimal or separated number ('1:30.5' is 90.5); "
             "write the decimal number, or quote it",
    "bool": "YAML 1.1 reads yes/no/on/off as true/false; write true or false (or quote it "
            "for text)",
    "timestamp": "YAML reads this as a date; casmech has no dates: write a number or an "
                 "expression, or quote it for text",
}


class Fatal(Exception):
    """A finding that stops reading the document."""

    def __init__(self, diagnostic: Diagnostic):
        super().__init__(diagnostic.message)
        self.diagnostic = diagnostic


@functools.lru_cache(maxsize=8192)  # a large model repeats its numbers (0.0, 1.0, sizes)
def plain_value(text: str) -> tuple[Any, str | None]:
    """(value, None) of a plain scalar read as YAML 1.2 reads it, or (text, kind) of a YAML 1.1
    spelling that reads differently there (a key of SURPRISES)."""
    kind = _RESOLVER.resolve(yaml.ScalarNode, text, (True, False))[len(_CORE):]
    if kind == "null":
        return None, None
    if kind == "bool":
        return (_BOOL[text], None) if text in _BOOL else (text, "bool")
    if kind == "int":
        return (int(text), None) if _INTEGER.match(text) else (text, "int")
    if kind == "float":
        if text in _SPECIAL:
            return _SPECIAL[text], None
        return (float(text), None) if _FLOAT.match(text) else (text, "float")
    if kind == "timestamp":
        return text, "timestamp"
    return text, None


# ------------------------------------------------------------------------------- builder
_DISCARD = "\0discarded"  # key of a value that is read but kept nowhere (after a bad key)


class _Node:
    """A mapping or list being built (one entry of the builder's explicit stack)."""

    __slots__ = ("value", "path", "anchor", "starts", "counted", "key", "seen", "is_key")

    def __init__(self, value, path: Path, anchor, starts, counted: int, is_key: bool):
        self.value, self.path, self.anchor = value, path, anchor
        self.starts, self.counted, self.is_key = starts, counted, is_key
        self.key: str | None = None  # a mapping's key waiting for its value
        self.seen: dict[str, Source] = {}  # a mapping's keys -> where first written


@record(frozen=False)
class _Anchor:
    """A YAML anchor: its value, path, the source-map entries written under it and its size."""

    value: Any
    path: Path
    ranges: tuple[tuple[int, int], ...]  # entries of each source-map log written under it
    size: int  # values under it, itself included


@record
class _Copy:
    """A source-map log entry standing for the entries an alias repeats: log[start:stop], each
    path with its first `prefix` parts replaced by `path`. Expanded once the document is read
    (`_expanded`), so an alias refused by MAX_VALUES costs nothing to copy."""

    path: Path
    prefix: int
    start: int
    stop: int


def _expanded(log: list) -> list:
    """The (path, entry) pairs of a log with its alias copies written out, in reading order."""
    out: list = []
    stack = [(0, len(log), (), 0)]  # (next, stop, new prefix, old prefix length)
    while stack:
        k, stop, new, old = stack.pop()
        while k < stop:
            path, entry = (log[k].path, log[k]) if isinstance(log[k], _Copy) else log[k]
            path = (*new, *path[old:]) if old or new else path
            k += 1
            if isinstance(entry, _Copy):
                stack.append((k, stop, new, old))
                k, stop, new, old = entry.start, entry.stop, path, entry.prefix
            else:
                out.append((path, entry))
    return out


class _Builder:
    """Data and source map from parser events: an explicit stack, so nesting costs no
    recursion; an alias counts the whole size of what it stands for against MAX_VALUES."""

    def __init__(self, file: str, text: str):
        self.file, self.text = file, text
        self.logs: tuple[list, list, list] = ([], [], [])  # (path, entry) of values, keys,
        self.diagnostics: list[Diagnostic] = []              # scalars, in reading order
        self.nulls: list[Path] = []
        self.anchors: dict[str, _Anchor] = {}
        self.count = 0
        self.stack: list[_Node] = []
        self.root: Any = None
        self.root_kind: str | None = None
        self.root_mark = None

    # -- reporting
    def fatal(self, code: str, mark, message: str, **extra) -> Fatal:
        return Fatal(Diagnostic(code, "", message, _source(self.file, mark), **extra))

    def error(self, code: str, path: Path, source: Source, message: str, **extra: str) -> None:
        self.diagnostics.append(Diagnostic(code, format_path(path), message, source, **extra))

    # -- where the next value goes
    def slot(self) -> Path | None:
        """The path of the value the next event starts; None when it is a mapping key."""
        if not self.stack:
            return ()
        top = self.stack[-1]
        if isinstance(top.value, list):
            return (*top.path, len(top.value))
        return None if top.key is None else (*top.path, top.key)

    def marks(self) -> tuple[int, ...]:
        values, keys, scalars = self.logs
        return len(values), len(keys), len(scalars)

    def ranges(self, starts: tuple[int, ...]) -> tuple[tuple[int, int], ...]:
        return tuple((start, len(log)) for start, log in zip(starts, self.logs, strict=True))

    def counted(self, size: int, mark) -> None:
        self.count += size
        if self.count > MAX_VALUES:
            raise self.fatal("E006", mark, f"the document holds more than {MAX_VALUES} values "
                             "(after expanding aliases)", hint="a model needs far fewer; "
                             "aliases (*name) of aliases multiply the values they stand for")

    def place(self, value: Any) -> None:
        """Put a finished value into its parent (or make it the root)."""
        if not self.stack:
            self.root = value
            return
        top = self.stack[-1]
        if isinstance(top.value, list):
            top.value.append(value)
            return
        if top.key != _DISCARD:
            top.value[top.key] = value
        top.key = None

    def bad_key(self, mark) -> None:
        """A list, mapping or alias written as a mapping key: reported, it and its value
        dropped."""
        top = self.stack[-1]
        self.error("E102", top.path, _source(self.file, mark), "a mapping key must be a name")
        top.key = _DISCARD

    def refuse_tag(self, tag: str, mark) -> None:
        raise self.fatal("E005", mark, f"YAML tag '{_tag(tag)}' is not part of the casmech "
                         "format", expected="plain values: numbers, text, lists, mappings",
                         hint="remove the tag")

    # -- events
    def scalar(self, event) -> None:
        if event.tag is not None and event.tag not in _TEXT_TAGS and \
                not any(event.implicit):
            self.refuse_tag(event.tag, event.start_mark)
        path = self.slot()
        source = _source(self.file, event.start_mark)
        if path is None:
            self.key(event.value, (*self.stack[-1].path, event.value), source)
            return
        self.counted(1, event.start_mark)
        if not self.stack:
            self.root_kind, self.root_mark = "scalar", event.start_mark
        starts = self.marks() if event.anchor is not None else None
        self.logs[0].append((path, source))
        value = self.scalar_value(event, path, source)
        if event.anchor is not None:
            self.anchors[event.anchor] = _Anchor(value, path, self.ranges(starts), 1)
        self.place(value)

    def scalar_value(self, event, path: Path, source: Source) -> Any:
        if event.tag is not None or not event.implicit[0] or event.style:
            self.logs[2].append((path, ScalarText(self.scalar_start(event))))
            return event.value
        value, surprise = plain_value(event.value)
        if surprise is not None:
            self.error("E004", path, source, f"'{event.value}' reads differently in YAML 1.1 "
                       "and YAML 1.2", hint=SURPRISES[surprise])
            return event.value
        if isinstance(value, str):
            self.logs[2].append((path, ScalarText(self.scalar_start(event))))
        elif value is None and event.value:
            self.nulls.append(path)
        return value

    def key(self, key: str, child: Path, source: Source) -> None:
        top = self.stack[-1]
        if key in top.seen:
            self.error("E002", child, source, f"duplicate key '{key}' (first at line "
                       f"{top.seen[key].line})", hint="remove one of them; the first value "
                       "is used")
            top.key = _DISCARD
            return
        top.seen[key] = source
        self.logs[1].append((child, source))
        top.key = key

    def start(self, event, kind: type) -> None:
        if event.tag is not None and event.tag not in _COLLECTION_TAGS and not event.implicit:
            self.refuse_tag(event.tag, event.start_mark)
        if len(self.stack) >= MAX_DEPTH:
            raise self.fatal("E006", event.start_mark, f"lists and mappings nested more than "
                             f"{MAX_DEPTH} deep", expected=f"at most {MAX_DEPTH} levels",
                             hint="the model format nests at most 10 levels")
        path = self.slot()
        is_key = path is None
        if is_key:
            self.bad_key(event.start_mark)
            path = (*self.stack[-1].path, _DISCARD)
        self.counted(1, event.start_mark)
        if not self.stack:
            self.root_kind = "list" if kind is list else "mapping"
            self.root_mark = event.start_mark
        starts = self.marks() if event.anchor is not None else None  # read by end()
        self.logs[0].append((path, _source(self.file, event.start_mark)))
        self.stack.append(_Node(kind(), path, event.anchor, starts, self.count - 1, is_key))

    def end(self) -> None:
        node = self.stack.pop()
        if node.is_key:  # its value follows, and is dropped with it
            return
        if node.anchor is not None:
            self.anchors[node.anchor] = _Anchor(node.value, node.path, self.ranges(node.starts),
                                                self.count - node.counted)
        self.place(node.value)

    def alias(self, event) -> None:
        anchor = self.anchors.get(event.anchor)
        if anchor is None:
            raise self.fatal("E001", event.start_mark, f"found undefined alias '{event.anchor}'",
                             hint="an alias (*name) must follow its anchor (&name), outside it")
        path = self.slot()
        if path is None:
            self.bad_key(event.start_mark)
            return
        self.counted(anchor.size, event.start_mark)
        prefix = len(anchor.path)
        for log, (start, stop) in zip(self.logs, anchor.ranges, strict=True):
            if stop > start:
                log.append(_Copy(path, prefix, start, stop))
        self.place(anchor.value)

    def scalar_start(self, event) -> Source | None:
        start, end = event.start_mark, event.end_mark
        quote = 1 if event.style in ("'", '"') else 0
        raw = self.text[start.index + quote : end.index - quote]
        if start.line != end.line or event.style not in (None, "", "'", '"') \
                or raw != event.value:
            return None
        return Source(self.file, start.line + 1, start.column + 1 + quote)

    def source_map(self) -> SourceMap:
        # (with no alias, no log holds a copy to write out)
        values, keys, scalars = (dict(_expanded(log) if self.anchors else log)
                                 for log in self.logs)
        return SourceMap(values, keys, scalars, frozenset(self.nulls))


def _tag(tag: str) -> str:
    return "!!" + tag[len(_CORE):] if tag.startswith(_CORE) else tag


def _events(builder: _Builder, text: str, parser=_PARSER) -> None:
    documents = 0
    for event in yaml.parse(text, Loader=parser):
        kind = type(event)
        if kind is yaml.ScalarEvent:
            builder.scalar(event)
        elif kind is yaml.MappingStartEvent:
            builder.start(event, dict)
        elif kind is yaml.SequenceStartEvent:
            builder.start(event, list)
        elif kind in (yaml.MappingEndEvent, yaml.SequenceEndEvent):
            builder.end()
        elif kind is yaml.AliasEvent:
            builder.alias(event)
        elif kind is yaml.DocumentStartEvent:
            documents += 1
            if documents > 1:
                raise builder.fatal("E001", event.start_mark, "expected a single document in "
                                    "the stream, but found another document",
                                    hint="a model file holds one YAML document (no second ---)")


def _syntax_error(error: yaml.YAMLError, file: str, text: str) -> Diagnostic:
    mark = getattr(error, "problem_mark", None)
    if mark is not None:
        source = _source(file, mark)
    elif isinstance(error, yaml.reader.ReaderError):
        source = _offset_source(file, text, error.position)
    else:
        source = Source(file, 1, 1)
    problem = getattr(error, "problem", None) or str(error).splitlines()[0]
    context = getattr(error, "context", None)
    message = f"{problem} ({context})" if context else problem
    return Diagnostic("E001", "", message, source)


def _offset_source(file: str, text: str, position: int) -> Source:
    before = text[:position]
    return Source(file, before.count("\n") + 1, len(before) - before.rfind("\n"))


def too_large(file: str, size: int, limit: int, what: str = "the model file") -> Diagnostic:
    return Diagnostic("E006", "", f"{what} is larger than {limit >> 20} MiB "
                      f"({size} bytes)", Source(file, 1, 1), expected=f"at most {limit} bytes",
                      hint="split it into component files, or use `repeat` for many copies")


def load_document(text: str, file: str = "<string>") -> Document:
    """Parse YAML text into a Document; raises ModelError for E001, E003, E005 and E006."""
    if len(text) > MAX_MODEL_BYTES:
        raise ModelError([too_large(file, len(text), MAX_MODEL_BYTES)])
    builder = _Builder(file, text)
    try:
        try:
            _events(builder, text)
        except yaml.YAMLError as error:
            if _PARSER is yaml.SafeLoader or _LIBYAML_DEPTH not in str(error):
                raise
            # libyaml (as PyYAML 6.0.4 bundles it) refuses deep nesting itself, from a scanner
            # running ahead of the events; the pure-Python parser hands each event to the
            # builder, so MAX_DEPTH decides (E006, where it is exceeded) with either build
            builder = _Builder(file, text)
            _events(builder, text, yaml.SafeLoader)
    except Fatal as fatal:
        raise ModelError([fatal.diagnostic]) from None
    except yaml.YAMLError as error:
        raise ModelError([_syntax_error(error, file, text)]) from None
    except UnicodeEncodeError as error:  # a lone surrogate in text from the API
        source = _offset_source(file, text, error.start)
        raise ModelError([Diagnostic("E001", "", "the text holds a character that is not "
                                     "Unicode (a lone surrogate)", source)]) from None
    if any(d.code == "E004" for d in builder.diagnostics):  # values lost: nothing to check
        raise ModelError(sorted(builder.diagnostics, key=lambda d: (d.source.line,
                                                                    d.source.col)))
    if builder.root_kind != "mapping":
        kind = builder.root_kind
        got = "an empty document" if kind is None else f"a {kind}"
        source = Source(file, 1, 1) if kind is None else _source(file, builder.root_mark)
        message = "a model file must be a mapping of keys (casmech, name, bodies, ...)"
        raise ModelError([Diagnostic("E003", "", message, source, "a mapping", got)])
    return Document(builder.root, file, text, builder.source_map(),
                    tuple(builder.diagnostics))


def load_file(path: str) -> Document:
    """Read and parse a model file; an unreadable file is a UsageError, bad UTF-8 is E001, a
    file larger than MAX_MODEL_BYTES (or a device that never ends) is E006."""
    try:
        data = files.read_bounded(path, MAX_MODEL_BYTES)
    except files.TooLarge as error:
        raise ModelError([too_large(str(path), error.size, MAX_MODEL_BYTES)]) from None
    except FileNotFoundError:
        raise UsageError(f"no such file: {path}") from None
    except OSError as error:
        raise UsageError(f"cannot read model file {path}: {error.strerror or error}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        message = f"the file is not UTF-8 text ({error.reason})"
        before = data[:error.start].decode("utf-8", "replace")
        source = _offset_source(str(path), before, len(before))
        raise ModelError([Diagnostic("E001", "", message, source)]) from None
    return load_document(text, str(path))
