"""`forces:` items (schema/spec.py): one class per registered force element type, the `spec`
of its casmech.elements.force_types entry (the built-in ones are in casmech.elements.forces)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from functools import partial
from typing import Annotated, Union

from pydantic import Field, Tag

from casmech.core.spec_base import Deferred, Spec
from casmech.elements.force_types import REGISTRY, spec_of


def _force_union():
    """The `forces:` item: a union of the registered types' classes, discriminated on `type`,
    each made (force_types.spec_of) and validated by its own validator when a document first
    holds one (spec_base.Deferred)."""
    classes = tuple(Annotated[Spec, Deferred(partial(spec_of, entry), name), Tag(name)]
                    for name, entry in REGISTRY.items())
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
    if name.startswith("__"):  # (the import system asks for `__path__`)
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    found = [spec_of(entry) for entry in REGISTRY.values()]
    found = [cls for cls in found if cls.__name__ == name]
    if not found:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return found[0]
