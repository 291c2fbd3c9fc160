"""Pydantic's validation errors -> Diagnostics (E100-E104, E410), never a raw pydantic dump.

Each error's location is walked through the spec's annotations: union tags (joint and force
`type`s, inertia and geometry shapes) are dropped so that paths read `joints[2].axis`, as in the
source map, and the innermost model gives the allowed keys for "did you mean" hints.
"""

from __future__ import annotations

from types import UnionType
from typing import Annotated, Any, Union, get_args, get_origin

from pydantic import BaseModel, Tag, ValidationError
from pydantic_core import ErrorDetails

from casmech.core.spec_base import Deferred
from casmech.elements.joint_types import REGISTRY, initial_keys, listed
from casmech.errors import Diagnostic, did_you_mean
from casmech.schema.loader import Document, Path, format_path
from casmech.schema.spec import GEOMETRY_KINDS, ModelSpec


def _strip(annotation: Any) -> Any:
    """The type under Annotated: a class made when first used (spec_base.Deferred) is made."""
    while get_origin(annotation) is Annotated:
        annotation, *metadata = get_args(annotation)
        for meta in metadata:
            if isinstance(meta, Deferred):
                annotation = meta.spec(annotation)
    return annotation


def _tag(member: Any) -> str | None:
    """The tag of a union member: its Tag metadata or the Literal of its `type` field."""
    tags = [meta.tag for meta in get_args(member)[1:] if isinstance(meta, Tag)]
    if tags:
        return tags[0]
    fields = getattr(_strip(member), "model_fields", {})
    tags = list(get_args(fields["type"].annotation)) if "type" in fields else []
    return tags[0] if tags else None


def _union_members(annotation: Any) -> dict[str | None, Any]:
    return {_tag(member): member for member in get_args(annotation)}


def _step(annotation: Any, step: str | int) -> tuple[Any, bool]:
    """The annotation one step down `loc`, and whether the step is part of the YAML path."""
    annotation = _strip(annotation)
    origin = get_origin(annotation)
    if origin in (Union, UnionType):
        members = _union_members(annotation)
        if isinstance(step, str) and step in members:
            return members[step], False
        present = [m for m in get_args(annotation) if m is not type(None)]
        return _step(present[0], step) if len(present) == 1 else (Any, True)
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        field = annotation.model_fields.get(str(step))
        return (field.annotation if field else Any), True
    args = get_args(annotation)
    return {tuple: args[:1], list: args[:1], dict: args[1:]}.get(origin, (Any,))[0], True


def _walk(loc: tuple[str | int, ...]) -> tuple[Path, type[BaseModel], Any]:
    """YAML path, innermost model, and annotation of a pydantic error location."""
    path: list[str | int] = []
    annotation: Any = ModelSpec
    model: type[BaseModel] = ModelSpec
    for step in loc:
        inner = _strip(annotation)
        if get_origin(inner) in (Union, UnionType):  # an optional mapping: its model
            present = [m for m in get_args(inner) if m is not type(None)]
            inner = _strip(present[0]) if len(present) == 1 else inner
        if isinstance(inner, type) and issubclass(inner, BaseModel):
            model = inner
        annotation, in_path = _step(annotation, step)
        path.extend([step] if in_path else [])
    return tuple(path), model, _strip(annotation)


def _describe(value: Any) -> str:
    kinds = {
        bool: lambda v: str(v).lower(),
        type(None): lambda v: "nothing (null)",
        dict: lambda v: "a mapping",
        list: lambda v: f"a list of {len(v)} item{'' if len(v) == 1 else 's'}",
        str: lambda v: f"'{v}'",
    }
    return kinds.get(type(value), repr)(value)


EXPECTED = {
    "scalar_type": "a number or an expression string",
    "string_type": "a string",
    "tuple_type": "a list",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "dict_type": "a mapping",
}
HINTS = {
    "inertia": "inertia is [Ixx, Iyy, Izz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] or a 3x3 list",
    "euler_parameters": "Euler parameters are [e0, e1, e2, e3]",
}

# (parent key, key) of a choice -> the hint when the value written is not close to a choice
LITERAL_HINTS = {
    ("reactions", "frame"): "the frame of the joint's reaction columns: global (the default), "
                            "body_i, body_j, or joint (the joint's own axes, fixed to body_i)",
}


class _Error:
    """One pydantic error, located in the document."""

    def __init__(self, error: ErrorDetails, document: Document):
        self.error = error
        self.input = error.get("input")
        self.ctx = error.get("ctx", {})
        self.path, self.model, self.annotation = _walk(tuple(error["loc"]))
        self.document = document

    def diagnostic(self, code: str, message: str, path: Path | None = None, **extra: Any):
        path = self.path if path is None else path
        source = extra.pop("source", None) or self.document.locate(path)
        if "hint" not in extra:
            keys = [step for step in path if isinstance(step, str)]
            extra["hint"] = HINTS.get(keys[-1]) if keys else None
        return Diagnostic(code, format_path(path), message, source, **extra)


def _missing(e: _Error) -> Diagnostic:
    key = e.path[-1]
    return e.diagnostic(
        "E100", f"missing required key '{key}'", source=e.document.locate(e.path[:-1])
    )


def _initial_hint(kind: str) -> str:
    """Why a joint type has no `initial:` key, and the types that take one."""
    takers = [name for name in REGISTRY if initial_keys(name)]
    return (f"a {kind} joint takes no initial values; `initial:` is taken by {listed(takers)} "
            "joints (docs/format.md#initial-state): write it on one of those, or place the "
            "bodies in the file")


# (section, key) of an element's key its type does not take -> the hint, by the element's type
KEY_HINTS = {("joints", "initial"): _initial_hint}


def _extra(e: _Error) -> Diagnostic:
    allowed = [info.alias or name for name, info in e.model.model_fields.items()]  # as written
    hint = did_you_mean(e.path[-1], allowed) or f"allowed keys: {', '.join(allowed)}"
    kinds = get_args(e.model.model_fields["type"].annotation) if "type" in allowed else ()
    explain = KEY_HINTS.get((e.path[0], e.path[-1])) if len(e.path) == 3 else None
    if explain is not None and kinds:
        hint = explain(kinds[0])
    source = e.document.locate_key(e.path)
    return e.diagnostic("E101", f"unknown key '{e.path[-1]}'", source=source, hint=hint)


def _tags(e: _Error) -> list[str]:
    return [tag for tag in _union_members(e.annotation) if tag is not None]


def _bad_tag(e: _Error) -> Diagnostic:
    tag, tags = e.ctx.get("tag"), _tags(e)
    path, expected = (*e.path, "type"), " | ".join(tags)
    hint = did_you_mean(tag, tags)
    return e.diagnostic("E103", f"unknown type '{tag}'", path, expected=expected, hint=hint)


def _no_tag(e: _Error) -> Diagnostic:
    source = e.document.locate(e.path)
    return e.diagnostic(
        "E100",
        "missing required key 'type'",
        (*e.path, "type"),
        source=source,
        expected=" | ".join(_tags(e)),
    )


def _literal(e: _Error) -> Diagnostic:
    values = [str(value) for value in get_args(e.annotation)]
    keys = tuple(step for step in e.path if isinstance(step, str))[-2:]
    hint = did_you_mean(e.input, values) or LITERAL_HINTS.get(keys)
    expected, got = " | ".join(values), _describe(e.input)
    return e.diagnostic("E103", "invalid value", expected=expected, got=got, hint=hint)


def _version_error(e: _Error) -> Diagnostic:
    got = _describe(e.input)
    return e.diagnostic("E104", "unsupported format version", expected="1", got=got)


def _geometry(e: _Error) -> Diagnostic:
    if not isinstance(e.input, dict):
        return e.diagnostic("E102", "wrong type", expected="a mapping", got=_describe(e.input))
    present = [kind for kind in GEOMETRY_KINDS if kind in e.input]
    if present:
        return e.diagnostic(
            "E410",
            f"several shapes in one geometry item: {', '.join(present)}",
            hint="write one geometry item per shape",
        )
    unknown = [key for key in e.input if key not in ("offset", "orientation")]
    hint = did_you_mean(unknown[0], GEOMETRY_KINDS) if unknown else None
    return e.diagnostic(
        "E100", "missing required key: one of box, cylinder, sphere, mesh", hint=hint
    )


def _length(e: _Error) -> Diagnostic | None:
    """Every list of the format has a fixed length (3, 4 or 6 items)."""
    count = e.ctx.get("min_length", e.ctx.get("max_length"))
    if isinstance(e.input, list | tuple) and len(e.input) == count:
        return None  # pydantic counts only the valid items; the bad ones are reported already
    expected, got = f"a list of {count} items", _describe(e.input)
    return e.diagnostic("E102", "wrong number of items", expected=expected, got=got)


def _wrong_type(e: _Error) -> Diagnostic:
    expected = EXPECTED.get(e.error["type"], e.error["msg"])
    return e.diagnostic("E102", "wrong type", expected=expected, got=_describe(e.input))


TRANSLATE = {
    "missing": _missing,
    "extra_forbidden": _extra,
    "union_tag_invalid": _bad_tag,
    "union_tag_not_found": _no_tag,
    "literal_error": _literal,
    "format_version": _version_error,
    "geometry_kind": _geometry,
    "too_short": _length,
    "too_long": _length,
}


def _admits_none(annotation: Any) -> bool:
    annotation = _strip(annotation)
    return get_origin(annotation) in (Union, UnionType) and type(None) in get_args(annotation)


def _child(parent: Any, step: str | int) -> Any:
    """One step down the validated model along a YAML path (None: not there)."""
    if isinstance(parent, BaseModel):
        names = {info.alias or name: name for name, info in type(parent).model_fields.items()}
        return getattr(parent, names[step]) if step in names else None
    if isinstance(parent, dict):
        return parent.get(step)
    if isinstance(parent, tuple | list) and isinstance(step, int) and step < len(parent):
        return parent[step]
    return None


def _written_null(model: ModelSpec, document: Document, path: Path) -> Diagnostic | None:
    """E102 for a key written as `null`/`~` that takes no null: an empty value (`joints:`)
    means "the default", an explicit null is a mistake (`joints: null` is not "no joints")."""
    parent: Any = model
    for step in path[:-1]:
        parent = _child(parent, step)
    if not isinstance(parent, BaseModel):
        return None  # a mapping of names (component parameters: `m: ~` has no default)
    fields = {info.alias or name: info for name, info in type(parent).model_fields.items()}
    info = fields.get(str(path[-1]))
    if info is None or _admits_none(info.annotation):
        return None
    return Diagnostic("E102", format_path(path), "wrong type", document.locate(path),
                      expected="a value (leave it empty, or remove the key, for the default)",
                      got="null")


def validate(document: Document) -> tuple[ModelSpec | None, list[Diagnostic]]:
    """The ModelSpec of a document, or None and the structural diagnostics."""
    try:
        model = ModelSpec.model_validate(document.data)
    except ValidationError as error:
        found = (
            TRANSLATE.get(item["type"], _wrong_type)(_Error(item, document))
            for item in error.errors(include_url=False)
        )
        return None, [diagnostic for diagnostic in found if diagnostic is not None]
    nulls = [_written_null(model, document, path) for path in sorted(
        document.source_map.nulls, key=lambda p: document.locate(p).line)]
    nulls = [diagnostic for diagnostic in nulls if diagnostic is not None]
    return (None, nulls) if nulls else (model, [])
