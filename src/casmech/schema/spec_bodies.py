"""`bodies:` items (schema/spec.py): mass, inertia, pose, velocities, geometry."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Annotated, Any, Literal, Union

from pydantic import (
    Discriminator,
    StrictStr,
    Tag,
)

from casmech.core.spec_base import (
    Deferred,
    Inertia,
    Name,
    Orientation,
    Repeats,
    Scalar,
    Spec,
    Vector,
)


# ---------------------------------------------------------------------------------- geometry
class Placement(Spec):
    offset: Vector | None = None
    orientation: Annotated[Orientation, Deferred()] | None = None


class Cylinder(Spec):
    radius: Scalar
    length: Scalar
    axis: Literal["x", "y", "z"] = "z"


class BoxItem(Placement):
    box: Vector


class CylinderItem(Placement):
    cylinder: Cylinder


class SphereItem(Placement):
    sphere: Scalar


class MeshItem(Placement):
    mesh: StrictStr
    scale: Scalar | Vector = 1  # one factor (> 0), or one per axis (non-zero; < 0 mirrors)


GEOMETRY_KINDS = ("box", "cylinder", "sphere", "mesh")


def _geometry_kind(value: Any) -> str | None:
    kinds = [kind for kind in GEOMETRY_KINDS if isinstance(value, dict) and kind in value]
    return kinds[0] if len(kinds) == 1 else None


# a box inlined (most bodies' item), the other kinds validated by their classes' own validators,
# built when a document first has one (spec_base.Deferred), as an orientation
Geometry = Annotated[
    Union[  # noqa: UP007
        Annotated[BoxItem, Tag("box")],
        Annotated[CylinderItem, Deferred(), Tag("cylinder")],
        Annotated[SphereItem, Deferred(), Tag("sphere")],
        Annotated[MeshItem, Deferred(), Tag("mesh")],
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
    orientation: Annotated[Orientation, Deferred()] | None = None
    velocity: Vector | None = None
    angular_velocity: Vector | None = None
    geometry: tuple[Geometry, ...] = ()
    repeat: Repeats | None = None
