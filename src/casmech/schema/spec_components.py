"""Components and instances (schema/spec.py, docs/components.md): the classes of the
`components:` and `instances:` sections, imported when a document first has one of them
(spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from pydantic import Field, StrictStr

from casmech.core.spec_base import Name, OrientationField, Repeats, Scalar, Spec, Vector
from casmech.schema import spec
from casmech.schema.spec_bodies import Body


class Instance(Spec):
    """One use of a component: its parameters (expressions of the user's parameters) and the
    placement of its frame (docs/components.md)."""

    name: Name
    component: Name
    parameters: dict[StrictStr, Scalar] = Field(default_factory=dict)
    position: Vector | None = None
    orientation: OrientationField | None = None
    repeat: Repeats | None = None


class ComponentFile(Spec):
    """A component defined by another model file (path relative to this file)."""

    file: StrictStr


class Component(Spec):
    """An inline component: a model body; a parameter without a value must be given by every
    instance."""

    description: StrictStr = ""
    parameters: dict[StrictStr, Scalar | None] = Field(default_factory=dict)
    bodies: tuple[Body, ...] = ()
    joints: tuple[spec.Joint, ...] = ()  # (the registered joint and force types' unions:
    forces: tuple[spec.Force, ...] = ()  # spec rebuilds them on a change)
    instances: tuple[Instance, ...] = ()
