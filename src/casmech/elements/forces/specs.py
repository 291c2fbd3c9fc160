"""The YAML classes (pydantic, casmech.core.spec_base.Spec) of the built-in force element types:
springs (tsda, rsda), loads (force, torque), the bushing and the contacts. The registry
(casmech.elements.force_types) names each by a function that imports this module when the
schema first needs the class, so that a model without force elements makes none of them; the
checks, lowering and laws are in the types' own modules."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Annotated, Literal

from pydantic import Field, StrictBool

from casmech.core.spec_base import Name, OrientationField, Repeats, Scalar, Spec, Vector


# ----------------------------------------------------------- springs (elements/forces/springs.py)
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
    allow_negative: StrictBool = False  # a negative stiffness or damping is meant
    repeat: Repeats | None = None


class RSDA(Spec):
    name: Name
    type: Literal["rsda"]
    joint: Name
    stiffness: Scalar = 0
    free_angle: Scalar = 0
    damping: Scalar = 0
    actuator: Scalar = "0"
    allow_negative: StrictBool = False  # a negative stiffness or damping is meant
    repeat: Repeats | None = None


# ------------------------------------------------------------ loads (elements/forces/loads.py)
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


# -------------------------------------------------------- the bushing (elements/forces/bushing.py)
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
    orientation: OrientationField | None = None
    stiffness: Vector = (0, 0, 0)
    damping: Vector = (0, 0, 0)
    rotational_stiffness: Vector = (0, 0, 0)
    rotational_damping: Vector = (0, 0, 0)
    preload_force: Vector = (0, 0, 0)
    preload_torque: Vector = (0, 0, 0)
    allow_negative: StrictBool = False  # a negative stiffness or damping is meant
    repeat: Repeats | None = None


# --------------------------------------------------- contacts (elements/forces/contact_spec.py)
class NormalLaw(Spec):
    """hunt_crossley: F = k d^n (1 + alpha d_dot), alpha giving restitution e at v_in
    (hunt_crossley_damping); linear: F = k d + c d_dot."""

    law: Literal["hunt_crossley", "linear"] = "hunt_crossley"
    stiffness: Scalar
    exponent: Scalar | None = None  # hunt_crossley: default 1.5 (Hertz); linear: always 1
    restitution: Scalar | None = None  # hunt_crossley: e at impact_velocity, default 1
    impact_velocity: Scalar = 1  # hunt_crossley: the v_in the damping is scaled by
    damping: Scalar | None = None  # linear: c, default 0


class Friction(Spec):
    """model smooth: regularized Coulomb friction, mu from 0 at slip 0 up to `static` at
    stiction_velocity, down to `dynamic` at transition_velocity, then constant (Adams' STEP
    curve); model exact: Coulomb's stick (|F_t| <= static N, the point held) and slip
    (dynamic N against the slip), switched at located events in dynamics."""

    model: Literal["smooth", "exact"] = "smooth"
    static: Scalar
    dynamic: Scalar | None = None  # default: static
    stiction_velocity: Scalar = 1e-3
    transition_velocity: Scalar | None = None  # default: 2 stiction_velocity


class Plane(Spec):
    at: Vector = (0, 0, 0)  # a point of the plane, global at t = 0
    normal: Vector = (0, 0, 1)  # its outward normal (towards the other body), global at t = 0


# a contact's plane when it names none: made on use, so that importing builds no validator
DEFAULT_PLANE = Field(default_factory=Plane,
                      json_schema_extra={"default": {"at": [0, 0, 0], "normal": [0, 0, 1]}})


class ContactBase(Spec):
    name: Name
    body_j: Name
    normal: NormalLaw
    friction: Friction | None = None
    repeat: Repeats | None = None


class SpherePlane(ContactBase):
    type: Literal["sphere_plane"]
    body_i: Name = "ground"  # carries the plane
    plane: Plane = DEFAULT_PLANE
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
    plane: Plane = DEFAULT_PLANE
    points: tuple[Vector, ...] | None = None  # global at t = 0; default: body_j's box corners


class CapsulePlane(ContactBase):
    type: Literal["capsule_plane"]
    body_i: Name = "ground"
    plane: Plane = DEFAULT_PLANE
    radius: Scalar | None = None  # default: body_j's cylinder geometry
    ends: Annotated[tuple[Vector, ...], Field(min_length=2, max_length=2)] | None = None
