"""The machinery behind casmech.core.options: option fields (default, meaning, range, choices),
their values read from YAML, the command line and Python, and their description.

An options object is a frozen dataclass whose fields are made by `option` (a value) or
`nested` (another options dataclass). Keys are dotted paths of field names
(`solver.assembly.tolerance`); `lookup` also takes a key without its leading `solver.` (the
command line's `--option max_step=1e-3`). `with_values` returns a new object with values
replaced and the problems found (unknown key with a did-you-mean, wrong type, out of range),
each with its path, for the schema (located errors), the command line and the API (usage
errors) alike.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Iterator, Mapping, Sequence
from functools import cache
from typing import Any

from casmech.core.records import record
from casmech.errors import did_you_mean

SOLVER = "solver"  # the nested options a YAML `analysis:` block writes under `solver:`


@record
class Meaning:
    """What an option field is: its meaning, unit, range and choices."""

    doc: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    open_low: bool = False  # low itself is outside the range
    choices: Sequence[str] | None = None  # a tuple, or a live core.registry.Names

    def range_text(self) -> str:
        """'0 < x <= 1', 'x >= 1', '' (no range), or the choices."""
        if self.choices:
            return " | ".join(self.choices)
        below = "<" if self.open_low else "<="
        if self.low is not None and self.high is not None:
            return f"{self.low:g} {below} x <= {self.high:g}"
        if self.low is not None:
            return f"x {'>' if self.open_low else '>='} {self.low:g}"
        return f"x <= {self.high:g}" if self.high is not None else ""


def option(default: Any, doc: str, *, unit: str = "", low: float | None = None,
           high: float | None = None, open_low: bool = False,
           choices: Sequence[str] | None = None) -> Any:
    """A field holding one value: its default (written here only) and its meaning."""
    return dataclasses.field(default=default, metadata={"meaning": Meaning(
        doc, unit, low, high, open_low, choices)})


def nested(kind: type, doc: str) -> Any:
    """A field holding another options dataclass (its defaults)."""
    return dataclasses.field(default_factory=kind, metadata={"meaning": Meaning(doc)})


@record
class Problem:
    """A value that cannot be set: `path` the keys inside the options object; `code` the
    diagnostic code (E101 unknown key, E102 wrong type, E409 out of range)."""

    path: tuple[str, ...]
    code: str
    message: str
    expected: str | None = None
    got: str | None = None
    hint: str | None = None

    @property
    def key(self) -> str:
        return ".".join(self.path)

    def line(self) -> str:
        """One line for the command line and the API."""
        parts = [f"option {self.key}: {self.message}"]
        if self.expected:
            parts.append(f"expected {self.expected}")
        if self.hint:
            parts.append(self.hint)
        return "; ".join(parts)


@cache
def fields(kind: type) -> dict[str, tuple[dataclasses.Field, Any]]:
    """name -> (field, its type) of an options dataclass."""
    hints = typing.get_type_hints(kind)
    return {f.name: (f, hints[f.name]) for f in dataclasses.fields(kind)}


def meaning(kind: type, name: str) -> Meaning:
    return fields(kind)[name][0].metadata["meaning"]


def is_options(kind: Any) -> bool:
    return isinstance(kind, type) and dataclasses.is_dataclass(kind)


def leaves(kind: type, prefix: tuple[str, ...] = ()) -> Iterator[tuple[tuple[str, ...], Any]]:
    """(path, type) of every value field, nested ones included, in field order."""
    for name, (_, hint) in fields(kind).items():
        if is_options(hint):
            yield from leaves(hint, (*prefix, name))
        else:
            yield (*prefix, name), hint


def keys(kind: type) -> list[str]:
    """Every key of an options class, dotted."""
    return [".".join(path) for path, _ in leaves(kind)]


def lookup(kind: type, key: str) -> tuple[str, ...] | None:
    """The path of a key (a nested mapping's key, a field, or a key inside `solver:` given
    without it), or None."""
    path = tuple(key.split("."))
    tried = [path] + ([(SOLVER, *path)] if path[0] != SOLVER and SOLVER in fields(kind) else [])
    for candidate in tried:
        node = kind
        for step in candidate:
            if not is_options(node) or step not in fields(node):
                break
            node = fields(node)[step][1]
        else:
            return candidate
    return None


def flat(values: Mapping[str, Any], prefix: tuple[str, ...] = ()
         ) -> Iterator[tuple[tuple[str, ...], Any]]:
    """(path, value) of a mapping whose values may be mappings again (nested options)."""
    for key, value in values.items():
        if isinstance(value, Mapping):
            yield from flat(value, (*prefix, *str(key).split(".")))
        else:
            yield (*prefix, *str(key).split(".")), value


def _optional(hint: Any) -> tuple[Any, bool]:
    """(the type inside `X | None`, whether None is allowed)."""
    args = typing.get_args(hint)
    if typing.get_origin(hint) in (typing.Union, types.UnionType) and type(None) in args:
        inner = [a for a in args if a is not type(None)]
        return inner[0], True
    return hint, False


TRUE, FALSE = ("true", "yes", "on", "1"), ("false", "no", "off", "0")
NONE = ("none", "null", "auto")


def _convert(hint: Any, value: Any, text: bool) -> Any:
    """value as the field's type (text: a command-line string); ValueError with what was
    expected."""
    inner, optional = _optional(hint)
    if value is None or (text and optional and str(value).strip().lower() in NONE):
        if optional:
            return None
        raise ValueError("a value (this option has no 'none')")
    if inner is bool:
        if isinstance(value, bool):
            return value
        if text and str(value).strip().lower() in TRUE + FALSE:
            return str(value).strip().lower() in TRUE
        raise ValueError("true or false")
    if inner in (int, float):
        number = value
        if text and isinstance(value, str):
            try:
                number = float(value)
            except ValueError:
                number = None
        if isinstance(number, bool) or not isinstance(number, (int, float)):
            raise ValueError("an integer" if inner is int else "a number")
        if not math.isfinite(number):
            raise ValueError("a finite number")
        if inner is int:
            if number != int(number):
                raise ValueError("an integer")
            return int(number)
        return float(number)
    if inner is str:
        if not isinstance(value, str):
            raise ValueError("a string")
        return value
    if typing.get_origin(inner) is tuple:  # names: a list, or comma-separated text
        items = value.split(",") if text and isinstance(value, str) else value
        if isinstance(items, str) or not isinstance(items, (list, tuple)) or not all(
                isinstance(item, str) for item in items):
            raise ValueError("a list of names")
        return tuple(item.strip() for item in items)
    raise ValueError(f"a value of type {inner}")  # pragma: no cover (no such field)


def _range_problem(meaning: Meaning, value: Any) -> str | None:
    if value is None or isinstance(value, (bool, tuple)):
        return None
    if meaning.choices is not None:
        return None if value in meaning.choices else "not one of the choices"
    if not isinstance(value, (int, float)):
        return None
    below = meaning.low is not None and (value < meaning.low or (meaning.open_low
                                                                 and value == meaning.low))
    above = meaning.high is not None and value > meaning.high
    return "out of range" if below or above else None


def _shown(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else repr(value) if isinstance(
        value, str) else str(value)


def check_value(kind: type, path: tuple[str, ...], value: Any, text: bool = False
                ) -> tuple[Any, Problem | None]:
    """(the value as the field at `path` holds it, None) or (None, the problem)."""
    node = kind
    for step in path[:-1]:
        node = fields(node)[step][1]
    field_meaning = meaning(node, path[-1])
    hint = fields(node)[path[-1]][1]
    got = value if not isinstance(value, str) or text else f"'{value}'"
    try:
        converted = _convert(hint, value, text)
    except ValueError as error:
        return None, Problem(path, "E102", "wrong type", expected=str(error), got=str(got))
    why = _range_problem(field_meaning, converted)
    if why is not None:
        expected = field_meaning.range_text()
        hint_text = (did_you_mean(str(converted), field_meaning.choices)
                     if field_meaning.choices else None)
        return None, Problem(path, "E409", why, expected=expected, got=_shown(converted),
                             hint=hint_text)
    return converted, None


def _reach(kind: type, path: tuple[str, ...]) -> tuple[Any, int]:
    """The deepest options class the leading keys of `path` name, and how many they are."""
    node, depth = kind, 0
    for step in path[:-1]:
        if not is_options(node) or step not in fields(node):
            break
        node, depth = fields(node)[step][1], depth + 1
    return node, depth


def unknown(kind: type, key: str, path: tuple[str, ...] | None = None) -> Problem:
    """The problem of a key no field has: what its parent (the deepest options object the
    key reaches, under `solver` too for a key given without it) holds, and a did-you-mean
    among those names, or else the whole key whose last name is close."""
    path = given = tuple(key.split(".")) if path is None else path
    node, depth = _reach(kind, path)
    if path[0] != SOLVER and SOLVER in fields(kind):
        inner, reached = _reach(kind, (SOLVER, *path))
        if reached - 1 >= depth and (reached > 1 or path[0] not in fields(kind)):
            node, depth, path = inner, reached, (SOLVER, *path)
    names = list(fields(node)) if is_options(node) else []
    close = did_you_mean(path[depth], names) if depth < len(path) else None
    if close is None:  # a key of another level: by its last name, the whole key proposed
        import difflib  # (on use: only a mistake needs it)

        full = {}
        for known in reversed(keys(kind)):
            full[known.split(".")[-1]] = known
        match = difflib.get_close_matches(path[-1], list(full), n=1, cutoff=0.6)
        close = f"did you mean '{full[match[0]]}'?" if match else None
    where = ".".join(path[:depth])
    expected = (f"one of {', '.join(names)}" + (f" (under {where})" if where else "")
                if names else "a key of docs/analyses.md#options")
    return Problem(given, "E101", "unknown option", expected=expected, hint=close)


def with_values(options: Any, values: Mapping[str, Any], text: bool = False
                ) -> tuple[Any, list[Problem]]:
    """`options` with `values` (nested mappings or dotted keys; text: command-line strings)
    replaced, and the problems of those that could not be."""
    kind, changes, problems = type(options), {}, []
    for given, value in flat(values):
        key = ".".join(given)
        path = lookup(kind, key)
        if path is None or (is_options(_leaf_type(kind, path)) and not isinstance(value, Mapping)):
            problems.append(unknown(kind, key, given) if path is None else Problem(
                given, "E102", "wrong type", expected="a mapping of its options",
                got=str(value)))
            continue
        converted, problem = check_value(kind, path, value, text)
        if problem is not None:
            problems.append(problem)
        else:
            changes[path] = converted
    return replaced(options, changes), problems


def _leaf_type(kind: type, path: tuple[str, ...]) -> Any:
    node = kind
    for step in path:
        node = fields(node)[step][1]
    return node


def replaced(options: Any, changes: Mapping[tuple[str, ...], Any]) -> Any:
    """A copy of `options` with the values at the given paths replaced."""
    if not changes:
        return options
    here = {path[0]: value for path, value in changes.items() if len(path) == 1}
    deeper: dict[str, dict] = {}
    for path, value in changes.items():
        if len(path) > 1:
            deeper.setdefault(path[0], {})[path[1:]] = value
    for name, inner in deeper.items():
        here[name] = replaced(getattr(options, name), inner)
    return dataclasses.replace(options, **here)


def values(options: Any) -> dict[str, Any]:
    """Every value of an options object as a nested dict (JSON-serialisable: tuples as
    lists)."""
    out = {}
    for name in fields(type(options)):
        value = getattr(options, name)
        out[name] = values(value) if dataclasses.is_dataclass(value) else (
            list(value) if isinstance(value, tuple) else value)
    return out
