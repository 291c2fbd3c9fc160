"""The geometry items of a body other than a box (schema/spec_bodies.py): `cylinder:`,
`sphere:` and `mesh:`, imported when a document first has one (spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Literal

from pydantic import StrictStr

from casmech.core.spec_base import Scalar, Spec, Vector
from casmech.schema.spec_bodies import Placement


class Cylinder(Spec):
    radius: Scalar
    length: Scalar
    axis: Literal["x", "y", "z"] = "z"


class CylinderItem(Placement):
    cylinder: Cylinder


class SphereItem(Placement):
    sphere: Scalar


class MeshItem(Placement):
    mesh: StrictStr
    scale: Scalar | Vector = 1  # one factor (> 0), or one per axis (non-zero; < 0 mirrors)
