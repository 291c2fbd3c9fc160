"""Scalars, vectors and the base class of the format's pydantic models (schema/spec.py), and the
items every section may hold: orientations and `repeat` (their classes in spec_items, made when
a document first has one)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

import importlib
from collections.abc import Callable
from functools import partial
from typing import Annotated, Any, Literal, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    StrictFloat,
    StrictInt,
    StrictStr,
    Tag,
    ValidationError,
    WrapValidator,
    model_validator,
)
from pydantic_core import PydanticCustomError, core_schema

from casmech.core import pydantic_plugins

pydantic_plugins.stand_aside()  # (before the first validator is built)


def _scalar(value: Any, handler: Any) -> Any:
    try:
        return handler(value)
    except ValidationError:
        raise PydanticCustomError("scalar_type", "expected a number or an expression") from None


def _version(value: Any) -> Any:
    if type(value) is not int or value != 1:  # not True, not 1.0
        raise PydanticCustomError("format_version", "unsupported format version")
    return value


Version = Annotated[Literal[1], BeforeValidator(_version)]
_SCALAR = Annotated[Union[StrictInt, StrictFloat, StrictStr], WrapValidator(_scalar)]  # noqa: UP007


class _ScalarType:
    """Scalar's core schema, generated once and reused by every field that takes a Scalar,
    instead of once per field when a process builds the model's validator."""

    schema = None

    @classmethod
    def __get_pydantic_core_schema__(cls, source, handler):
        if cls.schema is None:
            cls.schema = handler.generate_schema(_SCALAR)
        return cls.schema


Scalar = Annotated[Union[StrictInt, StrictFloat, StrictStr], _ScalarType]  # noqa: UP007
Vector = Annotated[tuple[Scalar, ...], Field(min_length=3, max_length=3)]
Vector4 = Annotated[tuple[Scalar, ...], Field(min_length=4, max_length=4)]
Vector6 = Annotated[tuple[Scalar, ...], Field(min_length=6, max_length=6)]
Matrix = Annotated[tuple[Vector, ...], Field(min_length=3, max_length=3)]
Name = StrictStr


def _inertia_shape(value: Any) -> str:
    if isinstance(value, list | tuple):
        if len(value) == 6:
            return "full"
        if any(isinstance(item, list | tuple) for item in value):
            return "matrix"
    return "principal"


Inertia = Annotated[
    Union[  # noqa: UP007
        Annotated[Vector, Tag("principal")],
        Annotated[Vector6, Tag("full")],
        Annotated[Matrix, Tag("matrix")],
    ],
    Discriminator(_inertia_shape),
]


class Spec(BaseModel):
    # defer_build: a class's validator is built when first used, so a run builds the document's
    # one validator (ModelSpec's, which holds the nested classes), not one per class at import
    model_config = ConfigDict(extra="forbid", frozen=True, defer_build=True)

    @model_validator(mode="before")
    @classmethod
    def _empty_is_absent(cls, data: Any) -> Any:
        """An optional key written without a value (`joints:`) takes its default."""
        if not isinstance(data, dict):
            return data
        fields = cls.model_fields
        return {
            key: value
            for key, value in data.items()
            if value is not None or key not in fields or fields[key].is_required()
        }


class Deferred:
    """`Annotated[SomeSpec, Deferred()]`: the items of that class are validated by the class's own
    validator, built when the first such item is validated, instead of a copy of its schema
    inside the schema of every class that holds it; a document builds only the classes it uses
    (a union of every joint type, `joints: [spherical ...]`: only the spherical joint's).
    `Annotated[Spec, Deferred(build, tag)]`: the class itself is made (or its module imported)
    by `build()` when first used, its `type` being `tag` if it has one (`build` keeps what it
    made: spec_joints.joint_class_of; spec._problem).

    The errors are the class's own, under the holder's location, as if inlined. A class with a
    `type` field shows it to the holder, so that a union of such classes is discriminated on
    `type`. The JSON Schema is the class's own (a `$ref` to its definition)."""

    def __init__(self, build: Callable[[], type] | None = None, tag: str | None = None):
        self.build, self.tag = build, tag

    def spec(self, source: Any) -> Any:
        """The class: `source` (the annotated class), or the one `build` makes."""
        return source if self.build is None else self.build()

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        build = self.build
        if build is None:
            def validate(value: Any, _inner: Any) -> Any:
                return source.__pydantic_validator__.validate_python(value)

            field = source.model_fields.get("type")
            tag = None if field is None else field.annotation
        else:
            def validate(value: Any, _inner: Any) -> Any:
                return build().__pydantic_validator__.validate_python(value)

            tag = None if self.tag is None else Literal[self.tag]
        shown = {} if tag is None else {
            "type": core_schema.typed_dict_field(handler.generate_schema(tag))}
        # (a reference of its own, so that the JSON Schema of a field holding it gives the field
        # no title, as for a class inlined)
        shown_schema = core_schema.typed_dict_schema(shown, ref=f"casmech.deferred:{id(self)}")
        return core_schema.no_info_wrap_validator_function(
            validate, shown_schema, serialization=core_schema.simple_ser_schema("any"),
            metadata={"deferred": partial(self.spec, source)})

    @staticmethod
    def __get_pydantic_json_schema__(schema: Any, handler: Any) -> Any:
        spec = schema["metadata"]["deferred"]()
        return handler.generate_json_schema.generate_inner(spec.__pydantic_core_schema__)


# ------------------------------------------------------------ orientation, repeat (spec_items)
ITEMS = "casmech.core.spec_items"  # Orientation (with AxisAngle) and Repeat


def item(name: str) -> type[Spec]:
    """A class of spec_items (the module imported on the first call)."""
    return getattr(importlib.import_module(ITEMS), name)


# an orientation, validated by its class's own validator, made when a document first has one
OrientationField = Annotated[Spec, Deferred(partial(item, "Orientation"))]
# (a Repeat likewise)
Repeats = Annotated[
    Union[  # noqa: UP007
        Annotated[Spec, Deferred(partial(item, "Repeat")), Tag("one")],
        Annotated[tuple[Annotated[Spec, Deferred(partial(item, "Repeat"))], ...],
                  Field(min_length=1), Tag("nested")],
    ],
    Discriminator(lambda v: "nested" if isinstance(v, list | tuple) else "one"),
]


def __getattr__(name: str) -> type[Spec]:
    """The classes of spec_items by name (spec_base.Orientation, ...)."""
    if name in ("AxisAngle", "Orientation", "Repeat"):
        return item(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
