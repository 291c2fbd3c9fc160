"""`repeat` and `{expr}` names: one copy of a list item per value of an integer index.

    bodies/joints/forces/instances item:  repeat: {index: i, from: 1, to: N}   (or a list of
    such ranges: nested, the later bounds may use the earlier indices)

In a copy, the index is a number in every expression (`(i-1)*L` becomes `(3-1)*L`) and
`{expr}` in names and references (`link{i-1}.bar`) is an integer expression of the parameters
and the indices; `{expr}` works in items without `repeat` too. The copies form a new Document
whose source map points every copy at the lines of its original item, so later findings are
located in the file as written; `relabel` turns their paths back to the written item and says
for which index values they were found.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import field, replace
from typing import Any

from casmech.core import traced
from casmech.core.expressions import CONSTANTS, ExpressionError, tokenize
from casmech.core.expressions import parse as parse_expression
from casmech.core.records import record
from casmech.errors import Diagnostic, Source, did_you_mean
from casmech.schema.checker import NAME, RESERVED
from casmech.schema.loader import Document, Path, ScalarText, SourceMap, format_path

SECTIONS = ("bodies", "joints", "forces", "instances")
NAME_KEYS = frozenset({"name", "body_i", "body_j", "body", "joint"})  # `{expr}` substituted
TEXT_KEYS = NAME_KEYS | {"type", "frame", "component", "mesh", "axis", "file"}  # not expressions
BRACES = re.compile(r"\{([^{}]*)\}")
MAX_COPIES = 10_000  # copies of one item: a bound gone wrong should not hang the loader
MAX_ITEMS = 20_000  # bodies, joints, forces and instances of a whole model, the members of
#                    instances (and theirs) included: bounds the time to check and compile
#                    (docs/decisions/hostile-input.md)
INTEGRAL = 1e-9  # |x - round(x)| accepted as an integer
TOO_MANY = (f"the model has more than {MAX_ITEMS} bodies, joints, forces and instances (the "
            "members of instances included)")
TOO_MANY_HINT = "a model this large takes too long to check and compile"


@record
class ExpandedDocument(Document):
    """A Document whose repeated items are expanded; locations map back to the written file."""

    origin: Document | None = None
    items: Mapping[tuple[str, int], tuple[int, Mapping[str, int]]] = field(default_factory=dict)
    spans: Mapping[Path, tuple[tuple[int, int, int], ...]] = field(default_factory=dict)

    def source_in_scalar(self, path: Path, offset: int) -> Source:
        """Offsets in a substituted expression map back through the substitutions."""
        delta = 0
        for start, new_length, old_length in self.spans.get(tuple(path), ()):
            if offset < start:
                break
            if offset < start + new_length:
                return super().source_in_scalar(path, start - delta)
            delta += new_length - old_length
        return super().source_in_scalar(path, offset - delta)


@record(frozen=False)
class Budget:
    """Items a whole model may still make (shared by the documents of its components)."""

    left: int = MAX_ITEMS

    def spend(self, count: int) -> bool:
        self.left -= count
        return self.left >= 0

    @property
    def exhausted(self) -> bool:
        return self.left < 0


class _Findings:
    def __init__(self, document: Document):
        self.doc = document
        self.found: list[Diagnostic] = []

    def error(self, code: str, path: Path, message: str, source=None, **extra) -> None:
        source = source or self.doc.locate(path)
        self.found.append(Diagnostic(code, format_path(path), message, source, **extra))


def integer(report: _Findings, path: Path, value: Any, env: Mapping[str, float],
            offset: int = 0, what: str = "value") -> int | None:
    """An integer expression (text at `offset` of the scalar at `path`, or a YAML number)."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        report.error("E102", path, f"{what} must be an integer expression", got=repr(value))
        return None
    text = str(value)
    try:
        expr = parse_expression(text)
    except ExpressionError as error:
        source = report.doc.source_in_scalar(path, offset + error.offset)
        report.error(error.code, path, error.message, source, hint=error.hint)
        return None
    unknown = [(n, o) for n, o, _ in expr.names_with_offsets() if n not in env]
    for name, at in unknown:
        source = report.doc.source_in_scalar(path, offset + at)
        hint = did_you_mean(name, [*env, *CONSTANTS])
        report.error("E201", path, f"unknown symbol '{name}'", source, hint=hint)
    if unknown:
        return None
    result = expr.evaluate(env, "numpy")
    if traced.is_traced(result):  # a count is structure: no derivative through it
        symbolic = [name for name in expr.symbols if traced.is_traced(env.get(name))]
        report.error("E103", path, f"{what} cannot depend on a symbolic parameter "
                     f"({', '.join(sorted(symbolic))}): counts and names are the model's "
                     "structure", report.doc.source_in_scalar(path, offset),
                     hint="take other parameters as the variables")
        return None
    number = float(traced.value(result))
    if not math.isfinite(number) or abs(number - round(number)) > INTEGRAL:
        source = report.doc.source_in_scalar(path, offset)
        report.error("E103", path, f"{what} must be an integer", source, got=f"{text} = {number:g}")
        return None
    return int(round(number))


# ------------------------------------------------------------------------------ ranges
def _ranges(given: Any) -> list[dict]:
    return list(given) if isinstance(given, list) else [given]


def _index_ok(report: _Findings, path: Path, name: str, taken: Mapping[str, float]) -> bool:
    where = (*path, "index")
    if not NAME.match(name) or name in RESERVED:
        report.error("E303", where, f"invalid index name '{name}'",
                     expected="a name (letters, digits, '_') that is not t, pi, e or a function")
        return False
    if name in taken:
        report.error("E301", where, f"the index '{name}' is also a parameter or an outer index",
                     hint="choose another index name")
        return False
    return True


def bindings(report: _Findings, path: Path, given: Any,
             parameters: Mapping[str, float]) -> list[dict[str, int]] | None:
    """Every combination of index values of an item's `repeat` (nested ranges in order)."""
    combos: list[dict[str, int]] = [{}]
    levels = _ranges(given)
    for level, item in enumerate(levels):
        where = (*path, "repeat", level) if isinstance(given, list) else (*path, "repeat")
        name = item["index"]
        if not _index_ok(report, where, name, {**parameters, **combos[0]}):
            return None
        grown = []
        for outer in combos:
            env = {**parameters, **outer}
            low = integer(report, (*where, "from"), item["from"], env, what="repeat bound")
            high = integer(report, (*where, "to"), item["to"], env, what="repeat bound")
            if low is None or high is None:
                return None
            if len(grown) + max(0, high - low + 1) > MAX_COPIES:  # counted before made
                report.error("E105", (*where, "to"), f"repeat makes more than {MAX_COPIES} "
                             "copies of one item", got=f"from {low} to {high}"
                             + (f" for each of {len(combos)} outer copies" if outer else ""),
                             hint="check the bounds (`to` is inclusive)")
                return None
            grown += [{**outer, name: value} for value in range(low, high + 1)]
        combos = grown
    return combos


# ------------------------------------------------------------------------------ copies
def _value_text(value: int) -> str:
    return str(value) if value >= 0 else f"({value})"


def substitute_indices(text: str, values: Mapping[str, int]):
    """(text with each index name replaced by its value, spans (start, new, old length))."""
    try:
        tokens = tokenize(text)
    except ExpressionError:
        return text, ()
    out, spans, last = [], [], 0
    for token in tokens:
        if token.kind == "name" and token.text in values:
            out.append(text[last:token.offset])
            new = _value_text(values[token.text])
            start = sum(map(len, out))
            out.append(new)
            spans.append((start, len(new), len(token.text)))
            last = token.offset + len(token.text)
    out.append(text[last:])
    return "".join(out), tuple(spans)


def substitute_braces(report: _Findings, path: Path, text: str, env: Mapping[str, float]):
    """`link{i-1}` -> `link2`; None when an expression is wrong (reported)."""
    pieces, last = [], 0
    for match in BRACES.finditer(text):
        value = integer(report, path, match.group(1), env, match.start(1), "a name's {expr}")
        if value is None:
            return None
        pieces += [text[last:match.start()], str(value)]
        last = match.end()
    return "".join(pieces) + text[last:]


class _Copier:
    def __init__(self, report: _Findings, parameters: Mapping[str, float]):
        self.report = report
        self.parameters = parameters
        self.spans: dict[Path, tuple] = {}
        self.ok = True

    def copy(self, value: Any, path: Path, new: Path, values: Mapping[str, int]) -> Any:
        if isinstance(value, dict):
            return {k: self.copy(v, (*path, k), (*new, k), values)
                    for k, v in value.items() if not (len(path) == 2 and k == "repeat")}
        if isinstance(value, list):
            return [self.copy(v, (*path, k), (*new, k), values) for k, v in enumerate(value)]
        if not isinstance(value, str):
            return value
        key = path[-1]
        if key in NAME_KEYS:
            text = substitute_braces(self.report, path, value, {**self.parameters, **values})
            self.ok = self.ok and text is not None
            return value if text is None else text
        if key in TEXT_KEYS or not values:
            return value
        text, spans = substitute_indices(value, values)
        if spans:
            self.spans[new] = spans
        return text


def _remap(source_map: SourceMap, moves: Mapping[tuple[str, int], int]) -> SourceMap:
    """Entries of item (section, j) copied to every (section, k) with moves[(section, k)] = j."""
    by_origin: dict[tuple[str, int], list[int]] = {}
    for (section, k), j in moves.items():
        by_origin.setdefault((section, j), []).append(k)
    result = SourceMap()
    for table in ("values", "keys", "scalars"):
        target = getattr(result, table)
        for path, entry in getattr(source_map, table).items():
            if len(path) >= 2 and path[0] in SECTIONS and isinstance(path[1], int):
                for k in by_origin.get((path[0], path[1]), ()):
                    target[(path[0], k, *path[2:])] = entry
            else:
                target[path] = entry
    return result


def has_repeat(data: Mapping[str, Any]) -> bool:
    """Whether any list item uses `repeat` or a name uses `{expr}` (else nothing to expand)."""
    items = [item for section in SECTIONS if isinstance(data.get(section), list)
             for item in data[section] if isinstance(item, dict)]
    return any("repeat" in item or any(isinstance(item.get(k), str) and "{" in item[k]
                                       for k in NAME_KEYS) for item in items)


COMPOSED_KEYS = ("components", "instances")


def uses_composition(data: Mapping[str, Any]) -> bool:
    """Whether a document is composed (schema/components.py): components, instances, `repeat`
    or `{expr}` names."""
    return any(key in data for key in COMPOSED_KEYS) or has_repeat(data)


def too_many(document: Document) -> list[Diagnostic]:
    """E105 when the items written in a model without repeat or instances exceed MAX_ITEMS
    (at the item that goes past it)."""
    count = 0
    for section in SECTIONS:
        items = document.data.get(section)
        if not isinstance(items, list):
            continue
        if count + len(items) > MAX_ITEMS:
            path = (section, MAX_ITEMS - count)
            return [Diagnostic("E105", format_path(path), TOO_MANY, document.locate(path),
                               hint=TOO_MANY_HINT)]
        count += len(items)
    return []


def expand(document: Document, parameters: Mapping[str, float], budget: Budget | None = None):
    """(the expanded document, findings); the document must have passed validation. Every
    item made is spent from `budget` (E105 when it runs out)."""
    budget = Budget() if budget is None else budget
    report = _Findings(document)
    copier = _Copier(report, parameters)
    data = dict(document.data)
    items: dict[tuple[str, int], tuple[int, dict[str, int]]] = {}
    for section in SECTIONS:
        if not isinstance(data.get(section), list):
            continue
        copies = []
        for j, item in enumerate(data[section]):
            path = (section, j)
            combos = ([{}] if "repeat" not in item
                      else bindings(report, path, item["repeat"], parameters))
            if budget.exhausted:  # reported where it ran out
                return None, report.found
            if not budget.spend(len(combos or ())):
                report.error("E105", path, TOO_MANY, hint=TOO_MANY_HINT,
                             got=f"{len(combos)} copies" if "repeat" in item else None)
                return None, report.found
            for values in combos or ():
                items[(section, len(copies))] = (j, values)
                copies.append(copier.copy(item, path, (section, len(copies)), values))
        data[section] = copies
    if report.found or not copier.ok:
        return None, report.found
    moves = {key: j for key, (j, _) in items.items()}
    source_map = _remap(document.source_map, moves)
    for path in copier.spans:  # a substituted scalar maps 1:1 only through its spans
        scalar = source_map.scalars.get(path)
        source_map.scalars[path] = scalar or ScalarText(None)
    expanded = ExpandedDocument(data, document.file, document.text, source_map,
                                document.diagnostics, document, items, copier.spans)
    return expanded, []


ITEM_PATH = re.compile(r"^(bodies|joints|forces|instances)\[(\d+)\]")


def _written(diagnostic: Diagnostic, document: Document) -> tuple[Diagnostic, str | None]:
    """The finding on a copy named by the written item, and the copy's index values."""
    items = getattr(document, "items", {})
    match = ITEM_PATH.match(diagnostic.path)
    if not match or (match.group(1), int(match.group(2))) not in items:
        return diagnostic, None
    j, values = items[(match.group(1), int(match.group(2)))]
    path = f"{match.group(1)}[{j}]{diagnostic.path[match.end():]}"
    note = ", ".join(f"{name} = {value}" for name, value in values.items())
    return replace(diagnostic, path=path), note or None


def _notes(notes: list[str]) -> str:
    """'i = 2', 'i = 3' -> 'i = 2, 3'; several indices: 'i = 1, j = 2; i = 2, j = 0'."""
    shown = notes[:6] + (["..."] if len(notes) > 6 else [])
    single = all(note.count("=") == 1 for note in notes)
    if single and len({note.split(" =")[0] for note in notes}) == 1:
        return notes[0].split(" =")[0] + " = " + ", ".join(n.split("= ")[-1] for n in shown)
    return "; ".join(shown)


def relabel(found: list[Diagnostic], document: Document) -> list[Diagnostic]:
    """Findings on copies, named by the written item; the same finding on several copies of one
    item is reported once, with the index values of those copies."""
    groups: dict[Diagnostic, list[str]] = {}
    for diagnostic in found:
        written, note = _written(diagnostic, document)
        groups.setdefault(written, []).extend([note] if note else [])
    return [replace(d, message=f"{d.message} (for {_notes(notes)})") if notes else d
            for d, notes in groups.items()]
