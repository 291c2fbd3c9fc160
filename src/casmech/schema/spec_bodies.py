"""`bodies:` items (schema/spec.py): mass, inertia, pose, velocities, geometry."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

import importlib
from functools import partial
from typing import Annotated, Any, Union

from pydantic import Discriminator, Tag

from casmech.core.spec_base import (
    Deferred,
    Inertia,
    Name,
    OrientationField,
    Repeats,
    Scalar,
    Spec,
    Vector,
)


# ---------------------------------------------------------------------------------- geometry
class Placement(Spec):
    offset: Vector | None = None
    orientation: OrientationField | None = None


class BoxItem(Placement):
    box: Vector


SHAPES = "casmech.schema.spec_shapes"  # the other items' classes: Cylinder(Item), SphereItem, ...


def shape(name: str) -> type[Spec]:
    """A class of spec_shapes (the module imported on the first call)."""
    return getattr(importlib.import_module(SHAPES), name)


GEOMETRY_KINDS = ("box", "cylinder", "sphere", "mesh")


def _geometry_kind(value: Any) -> str | None:
    kinds = [kind for kind in GEOMETRY_KINDS if isinstance(value, dict) and kind in value]
    return kinds[0] if len(kinds) == 1 else None


# a box inlined (most bodies' item), the other kinds validated by their classes' own validators,
# made when a document first has one (spec_base.Deferred), as an orientation
Geometry = Annotated[
    Union[  # noqa: UP007
        Annotated[BoxItem, Tag("box")],
        Annotated[Spec, Deferred(partial(shape, "CylinderItem")), Tag("cylinder")],
        Annotated[Spec, Deferred(partial(shape, "SphereItem")), Tag("sphere")],
        Annotated[Spec, Deferred(partial(shape, "MeshItem")), Tag("mesh")],
    ],
    Discriminator(
        _geometry_kind,
        custom_error_type="geometry_kind",
        custom_error_message="a geometry item needs exactly one of box, cylinder, sphere, mesh",
    ),
]


class Body(Spec):
    name: Name
    mass: Scalar
    inertia: Inertia
    position: Vector
    orientation: OrientationField | None = None
    velocity: Vector | None = None
    angular_velocity: Vector | None = None
    geometry: tuple[Geometry, ...] = ()
    repeat: Repeats | None = None


def __getattr__(name: str) -> type[Spec]:
    """The classes of spec_shapes by name (spec.CylinderItem, ...)."""
    if name in ("Cylinder", "CylinderItem", "SphereItem", "MeshItem"):
        return shape(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
