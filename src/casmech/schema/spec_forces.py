"""`forces:` items (schema/spec.py): spring-dampers, loads, the bushing, contact elements."""

from __future__ import annotations

from typing import Annotated, Literal, Union

from pydantic import (
    Field,
)

from casmech.schema.spec_base import Name, Orientation, Repeats, Scalar, Spec, Vector


# ------------------------------------------------------------------------------------ forces
class TSDA(Spec):
    name: Name
    type: Literal["tsda"]
    body_i: Name
    at_i: Vector
    body_j: Name
    at_j: Vector
    stiffness: Scalar = 0
    free_length: Scalar | None = None
    damping: Scalar = 0
    actuator: Scalar = "0"
    repeat: Repeats | None = None


class RSDA(Spec):
    name: Name
    type: Literal["rsda"]
    joint: Name
    stiffness: Scalar = 0
    free_angle: Scalar = 0
    damping: Scalar = 0
    actuator: Scalar = "0"
    repeat: Repeats | None = None


class PointForce(Spec):
    name: Name
    type: Literal["force"]
    body: Name
    at: Vector | None = None  # default: the body's centre of mass
    value: Vector
    frame: Literal["global", "body"] = "global"
    repeat: Repeats | None = None


class Torque(Spec):
    name: Name
    type: Literal["torque"]
    body: Name
    value: Vector
    frame: Literal["global", "body"] = "global"
    repeat: Repeats | None = None


class Bushing(Spec):
    """6-DOF linear spring-damper between a frame on body_i and one on body_j (docs/forces.md).

    Both frames are at the global point `at` with `orientation` (default: global axes) at t = 0;
    vectors are components along the I frame's x, y, z: force = -K d - C d_dot + preload.
    """

    name: Name
    type: Literal["bushing"]
    body_i: Name
    body_j: Name
    at: Vector
    orientation: Orientation | None = None
    stiffness: Vector = (0, 0, 0)
    damping: Vector = (0, 0, 0)
    rotational_stiffness: Vector = (0, 0, 0)
    rotational_damping: Vector = (0, 0, 0)
    preload_force: Vector = (0, 0, 0)
    preload_torque: Vector = (0, 0, 0)
    repeat: Repeats | None = None


# Flat views of a bushing's coefficients under the compiler's names (compiler/bushing.py params
# stiffness0..5 = stiffness then rotational_stiffness, ...), so that optimal/symbolic.py, which
# re-evaluates `getattr(spec, key)` for every params key of a force, gives sensitivities to them.
BUSHING_PARAMS = {"stiffness": ("stiffness", "rotational_stiffness"),
                  "damping": ("damping", "rotational_damping"),
                  "preload": ("preload_force", "preload_torque")}


def _component(vector: str, index: int) -> property:
    return property(lambda self: getattr(self, vector)[index])


for _key, _vectors in BUSHING_PARAMS.items():
    for _n in range(6):
        setattr(Bushing, f"{_key}{_n}", _component(_vectors[_n // 3], _n % 3))

# contact (compiler/contact.py, schema/contact.py; docs/forces.md#contact)
class NormalLaw(Spec):
    """hunt_crossley: F = k d^n (1 + alpha d_dot), alpha giving restitution e at v_in
    (schema/contact.py); linear: F = k d + c d_dot."""

    law: Literal["hunt_crossley", "linear"] = "hunt_crossley"
    stiffness: Scalar
    exponent: Scalar | None = None  # hunt_crossley: default 1.5 (Hertz); linear: always 1
    restitution: Scalar | None = None  # hunt_crossley: e at impact_velocity, default 1
    impact_velocity: Scalar = 1  # hunt_crossley: the v_in the damping is scaled by
    damping: Scalar | None = None  # linear: c, default 0


class Friction(Spec):
    """Regularized Coulomb friction: mu from 0 at slip 0 up to `static` at stiction_velocity,
    down to `dynamic` at transition_velocity, then constant (Adams' STEP curve)."""

    static: Scalar
    dynamic: Scalar | None = None  # default: static
    stiction_velocity: Scalar = 1e-3
    transition_velocity: Scalar | None = None  # default: 2 stiction_velocity


class Plane(Spec):
    at: Vector = (0, 0, 0)  # a point of the plane, global at t = 0
    normal: Vector = (0, 0, 1)  # its outward normal (towards the other body), global at t = 0


class ContactBase(Spec):
    name: Name
    body_j: Name
    normal: NormalLaw
    friction: Friction | None = None
    repeat: Repeats | None = None


class SpherePlane(ContactBase):
    type: Literal["sphere_plane"]
    body_i: Name = "ground"  # carries the plane
    plane: Plane = Plane()
    radius: Scalar | None = None  # default: body_j's sphere geometry
    center: Vector | None = None  # global at t = 0; default: that sphere's centre


class SphereSphere(ContactBase):
    type: Literal["sphere_sphere"]
    body_i: Name
    radius_i: Scalar | None = None  # default: the body's sphere geometry
    radius_j: Scalar | None = None
    center_i: Vector | None = None  # global at t = 0; default: that sphere's centre
    center_j: Vector | None = None


class PointsPlane(ContactBase):
    type: Literal["points_plane"]
    body_i: Name = "ground"
    plane: Plane = Plane()
    points: tuple[Vector, ...] | None = None  # global at t = 0; default: body_j's box corners


class CapsulePlane(ContactBase):
    type: Literal["capsule_plane"]
    body_i: Name = "ground"
    plane: Plane = Plane()
    radius: Scalar | None = None  # default: body_j's cylinder geometry
    ends: Annotated[tuple[Vector, ...], Field(min_length=2, max_length=2)] | None = None


CONTACTS = (SpherePlane, SphereSphere, PointsPlane, CapsulePlane)
FORCES = (TSDA, RSDA, PointForce, Torque, Bushing, *CONTACTS)
Force = Annotated[Union[FORCES], Field(discriminator="type")]  # noqa: UP007
