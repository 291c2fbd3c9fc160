"""core.spec_base.Deferred against pydantic's own inlined schema: a holder whose items are
validated by their classes' own validators gives the same values, errors (type, location,
input, context) and JSON Schema as the same holder with the classes inlined."""

from functools import partial
from typing import Annotated, Literal, Union

import pytest
from pydantic import Field, Tag, ValidationError

from casmech.core.spec_base import Deferred, Spec, Vector


class Inner(Spec):
    x: int


class First(Spec):
    type: Literal["first"]
    at: Vector
    inner: Inner | None = None


class Second(Spec):
    type: Literal["second"]
    name: str


MADE: list[str] = []


def _made(cls):
    MADE.append(cls.__name__)
    return cls


def holder(kind: str):
    """The same holder with its item classes inlined, deferred, or made on first use."""
    members = {
        "inlined": (First, Second),
        "deferred": (Annotated[First, Deferred()], Annotated[Second, Deferred()]),
        "made": tuple(Annotated[Spec, Deferred(partial(_made, cls), tag), Tag(tag)]
                      for cls, tag in ((First, "first"), (Second, "second"))),
    }[kind]
    inner = Inner if kind == "inlined" else Annotated[Inner, Deferred()]

    class Holder(Spec):
        items: tuple[Annotated[Union[members], Field(discriminator="type")], ...] = ()  # noqa: UP007
        extra: inner | None = None

    return Holder


BAD = [
    {"items": [{"type": "first", "at": [1, 2]}]},
    {"items": [{"type": "first", "at": [1, 2, "t"], "inner": {"x": "no", "y": 1}}]},
    {"items": [{"type": "third"}, {}, "text", [1], {"type": "second", "name": 3, "k": 1}]},
    {"items": [{"type": "second", "name": "a"}], "extra": {"x": []}},
    {"extra": "text", "other": 1},
]


@pytest.mark.parametrize("data", BAD)
def test_the_errors_of_inlined_classes(data):
    errors = {}
    for kind in ("inlined", "deferred", "made"):
        with pytest.raises(ValidationError) as raised:
            holder(kind).model_validate(data)
        errors[kind] = raised.value.errors(include_url=False)
    assert errors["deferred"] == errors["inlined"]
    assert errors["made"] == errors["inlined"]


def test_values_and_json_schema_of_inlined_classes():
    good = {"items": [{"type": "first", "at": [1, 2, "3 m"], "inner": {"x": 4}},
                      {"type": "second", "name": "b"}], "extra": {"x": 1}}
    inlined = holder("inlined")
    expected = inlined.model_validate(good)
    MADE.clear()
    for kind in ("deferred", "made"):
        held = holder(kind)
        value = held.model_validate(good)
        assert [type(item) for item in value.items] == [First, Second]
        assert value.items == expected.items and value.extra == expected.extra
        schema = held.model_json_schema()
        assert schema == inlined.model_json_schema()
    assert sorted(set(MADE)) == ["First", "Second"]


def test_a_class_made_on_first_use_is_made_only_when_an_item_has_its_type():
    MADE.clear()
    held = holder("made")
    held.model_validate({"items": [{"type": "second", "name": "b"}]})
    assert MADE == ["Second"]
