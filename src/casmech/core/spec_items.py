"""The items of the format (core/spec_base.py) that a document may leave out wherever they
are taken: orientations and `repeat`, imported when a document first has one
(spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Annotated

from pydantic import Field

from casmech.core.spec_base import Matrix, Name, Scalar, Spec, Vector


# ------------------------------------------------------------------------------- orientation
class AxisAngle(Spec):
    axis: Vector
    angle: Scalar


class Orientation(Spec):
    """Exactly one form must be given (checked in semantic, E407)."""

    euler_parameters: Annotated[tuple[Scalar, ...], Field(min_length=4, max_length=4)] | None = None
    axis_angle: AxisAngle | None = None
    matrix: Matrix | None = None
    x_axis: Vector | None = None
    y_axis: Vector | None = None
    z_axis: Vector | None = None


# --------------------------------------------------------------- repeat (docs/components.md)
class Repeat(Spec):
    """One copy of the item per integer `index` from `from` to `to` (inclusive; none if to <
    from); the index is a number in the item's expressions and `{expr}` in its names."""

    index: Name
    from_: Scalar = Field(alias="from")
    to: Scalar
