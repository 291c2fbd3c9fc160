"""Reading simEngine3D JSON with source locations, and its composite constraints.

`Located` parses the text with `json` (a syntax error is located by its line and column) and
then with casmech's YAML loader for a source map (JSON is YAML), so every later error names the
line of the offending value.
"""

from __future__ import annotations

import json
from dataclasses import field
from pathlib import Path
from typing import Any

import numpy as np

from casmech.core.expressions import ExpressionError, parse
from casmech.core.records import record
from casmech.errors import Diagnostic, ModelError, Source
from casmech.importers.source import read_source
from casmech.schema.loader import format_path, load_document


def rotation(p) -> np.ndarray:
    e0, e = p[0], np.asarray(p[1:], float)
    skew = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return (e0**2 - e @ e) * np.eye(3) + 2 * np.outer(e, e) + 2 * e0 * skew


@record(frozen=False)
class Located:
    file: str
    data: dict
    document: Any  # casmech.schema.loader.Document or None
    warnings: list[Diagnostic] = field(default_factory=list)

    @classmethod
    def read(cls, path: Path) -> Located:
        text = read_source(path)
        try:
            data = json.loads(text)
        except json.JSONDecodeError as error:
            raise ModelError([Diagnostic(
                "E102", "", f"not valid JSON: {error.msg}",
                Source(str(path), error.lineno, error.colno),
                expected="a JSON object as simEngine3D writes it ({\"bodies\": [...], ...})",
                hint="check for a missing comma, quote or bracket before this point")]) from None
        if not isinstance(data, dict):
            raise ModelError([Diagnostic("E102", "", "the file is not a JSON object",
                                         Source(str(path), 1, 1), expected="{...}",
                                         hint="simEngine3D files are one JSON object")])
        try:
            document = load_document(text.expandtabs(4), str(path))
        except ModelError:
            document = None  # valid JSON that PyYAML will not read: errors fall back to line 1
        return cls(str(path), data, document)

    def source(self, path) -> Source:
        return self.document.locate(tuple(path)) if self.document else Source(self.file, 1, 1)

    def line(self, path) -> int:
        return self.source(path).line

    def error(self, path, message: str, expected: str, code: str = "E102",
              got: str | None = None, hint: str | None = None) -> ModelError:
        return ModelError([Diagnostic(code, format_path(tuple(path)), message,
                                      self.source(path), expected=expected, got=got,
                                      hint=hint or "see the simEngine3D model format")])

    def warn(self, path, message: str, code: str = "E103", hint: str | None = None) -> None:
        self.warnings.append(Diagnostic(code, format_path(tuple(path)), message,
                                        self.source(path), hint=hint, severity="warning"))

    def pick(self, obj: dict, path, spellings, default: Any = ...) -> Any:
        for key in spellings:
            if key in obj:
                return obj[key]
        if default is ...:
            raise self.error(path, f"missing '{spellings[0]}'", f"a key '{spellings[0]}'",
                             "E100", hint=f"also accepted: {', '.join(spellings[1:])}"
                             if len(spellings) > 1 else None)
        return default

    def key_path(self, obj: dict, path, spellings) -> tuple:
        return (*path, next((s for s in spellings if s in obj), spellings[0]))

    def vector(self, obj: dict, path, spellings, size: int, default: Any = ...) -> np.ndarray:
        value = self.pick(obj, path, spellings, default)
        array = np.asarray(value, dtype=object).ravel()
        try:
            array = array.astype(float)
        except (TypeError, ValueError):
            array = None
        if array is None or array.size != size:
            raise self.error(self.key_path(obj, path, spellings), f"'{spellings[0]}' must be "
                             f"{size} numbers", f"a list of {size} numbers", got=str(value))
        return array

    def number(self, obj: dict, path, spellings) -> float:
        value = self.pick(obj, path, spellings)
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(self.key_path(obj, path, spellings), f"'{spellings[0]}' must be a "
                             "number", "a number", got=repr(value))
        return float(value)

    def inertia(self, obj: dict, path, spellings) -> list:
        value = np.asarray(self.pick(obj, path, spellings), dtype=float)
        if value.shape == (3, 3):
            return [[float(x) for x in row] for row in value]
        if value.shape in ((3,), (6,)):
            return [float(x) for x in value]
        raise self.error(self.key_path(obj, path, spellings), "inertia (jbar) must be a 3x3 "
                         "matrix, 3 principal moments or 6 entries", "[[..],[..],[..]]",
                         got=str(value.tolist()))

    def list(self, obj: dict, path, required: bool = True) -> list:
        value = obj.get(path[-1], None if required else [])
        if not isinstance(value, list):
            raise self.error(path, f"'{path[-1]}' must be a list", f"\"{path[-1]}\": [...]",
                             "E100" if value is None else "E102")
        return value

    def expression(self, text: str, path) -> None:
        try:
            parse(text)
        except ExpressionError as error:
            raise self.error(path, f"f(t) '{text}' is not an expression casmech reads: {error}",
                             "an expression of t, e.g. cos(pi/4*cos(2*t) + pi/2)", "E200",
                             hint="functions: sin cos tan exp log sqrt ..., power as **"
                             ) from None

    def known(self, obj: dict, keys) -> None:
        for key in obj:
            if key not in keys:
                self.warn((key,), f"key '{key}' not translated", code="E101")


# composite constraint -> (casmech type, axis keys needed)
COMPOSITES = {"spherical": ("spherical", ()), "sj": ("spherical", ()),
              "revolute": ("revolute", ("a_i",)), "rj": ("revolute", ("a_i",)),
              "universal": ("universal", ("a_i", "a_j")), "uj": ("universal", ("a_i", "a_j")),
              "cylindrical": ("cylindrical", ("a_i",)), "cj": ("cylindrical", ("a_i",)),
              "translational": ("translational", ("a_i",)), "tj": ("translational", ("a_i",))}


def composite_joint(at: Located, row: dict, path, kind: str, data: dict, frames,
                    keys) -> dict:
    """A composite joint from body-frame points/axes, placed at the initial pose."""
    if kind not in COMPOSITES:
        raise at.error((*path, "type"), f"unknown constraint type '{row.get('type')}'",
                       "DP1, DP2, D, CD or a composite: " + ", ".join(COMPOSITES), "E103")
    casmech_type, axes = COMPOSITES[kind]
    r_i, a_i = frames[data["body_i"]]
    r_j, a_j = frames[data["body_j"]]
    point_i = r_i + a_i @ at.vector(row, path, keys["s_i"], 3)
    point_j = r_j + a_j @ at.vector(row, path, keys["s_j"], 3, default=[np.nan] * 3)
    if np.all(np.isfinite(point_j)) and np.linalg.norm(point_j - point_i) > 1e-9:
        at.warn(path, "the joint points of body_i and body_j differ at t = 0 by "
                f"{np.linalg.norm(point_j - point_i):.3g}: casmech uses body_i's")
    data = {**data, "type": casmech_type, "at": [float(v) for v in point_i]}
    vectors = {"a_i": a_i @ at.vector(row, path, keys["a_i"], 3) if "a_i" in axes else None,
               "a_j": a_j @ at.vector(row, path, keys["a_j"], 3) if "a_j" in axes else None}
    if casmech_type == "universal":
        data.update(axis_i=vectors["a_i"].tolist(), axis_j=vectors["a_j"].tolist())
    elif axes:
        data["axis"] = vectors["a_i"].tolist()
    return data
