"""`forces:` items (schema/spec.py): one class per registered force element type, the `spec`
of its casmech.elements.force_types entry (the built-in ones are in casmech.elements.forces)."""

from __future__ import annotations

from typing import Annotated, Union

from pydantic import Field

from casmech.core.spec_base import Deferred
from casmech.elements.force_types import REGISTRY


def _force_union():
    """The `forces:` item: a union of the registered types' classes, discriminated on `type`,
    each validated by its own validator (spec_base.Deferred)."""
    classes = tuple(Annotated[entry.spec, Deferred()] for entry in REGISTRY.values())
    return Annotated[Union[classes], Field(discriminator="type")]  # noqa: UP007


Force = _force_union()


def rebuild():
    """The union after a force element type was (un)registered (schema/spec.py rebuilds its
    users)."""
    global Force
    Force = _force_union()
    return Force


def __getattr__(name: str) -> type:
    """A force element type's class by its name (spec.TSDA, spec.Bushing, ...)."""
    found = [entry.spec for entry in REGISTRY.values() if entry.spec.__name__ == name]
    if not found:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return found[0]
