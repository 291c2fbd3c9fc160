"""The model format (docs/format.md) as pydantic v2 models, one class per YAML mapping.

Frozen, `extra="forbid"`; joints and forces are unions discriminated on `type`, inertia and
geometry items on their shape. Every scalar is a number or an expression string (evaluated in
`semantic`); `spec_errors.validate` turns pydantic's errors into Diagnostics.
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, Union

from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Discriminator,
    Field,
    StrictBool,
    StrictFloat,
    StrictInt,
    StrictStr,
    Tag,
    ValidationError,
    WrapValidator,
    create_model,
    model_validator,
)
from pydantic.fields import FieldInfo
from pydantic_core import PydanticCustomError

from casmech.joint_types import REGISTRY, JointType, on_change


def _scalar(value: Any, handler: Any) -> Any:
    try:
        return handler(value)
    except ValidationError:
        raise PydanticCustomError("scalar_type", "expected a number or an expression") from None


def _version(value: Any) -> Any:
    if type(value) is not int or value != 1:  # not True, not 1.0
        raise PydanticCustomError("format_version", "unsupported format version")
    return value


Version = Annotated[Literal[1], BeforeValidator(_version)]
Scalar = Annotated[Union[StrictInt, StrictFloat, StrictStr], WrapValidator(_scalar)]  # noqa: UP007
Vector = Annotated[tuple[Scalar, ...], Field(min_length=3, max_length=3)]
Vector4 = Annotated[tuple[Scalar, ...], Field(min_length=4, max_length=4)]
Vector6 = Annotated[tuple[Scalar, ...], Field(min_length=6, max_length=6)]
Matrix = Annotated[tuple[Vector, ...], Field(min_length=3, max_length=3)]
Name = StrictStr


def _inertia_shape(value: Any) -> str:
    if isinstance(value, list | tuple):
        if len(value) == 6:
            return "full"
        if any(isinstance(item, list | tuple) for item in value):
            return "matrix"
    return "principal"


Inertia = Annotated[
    Union[  # noqa: UP007
        Annotated[Vector, Tag("principal")],
        Annotated[Vector6, Tag("full")],
        Annotated[Matrix, Tag("matrix")],
    ],
    Discriminator(_inertia_shape),
]


class Spec(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    @model_validator(mode="before")
    @classmethod
    def _empty_is_absent(cls, data: Any) -> Any:
        """An optional key written without a value (`joints:`) takes its default."""
        if not isinstance(data, dict):
            return data
        fields = cls.model_fields
        return {
            key: value
            for key, value in data.items()
            if value is not None or key not in fields or fields[key].is_required()
        }


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


Repeats = Annotated[
    Union[  # noqa: UP007
        Annotated[Repeat, Tag("one")],
        Annotated[tuple[Repeat, ...], Field(min_length=1), Tag("nested")],
    ],
    Discriminator(lambda v: "nested" if isinstance(v, list | tuple) else "one"),
]


# ---------------------------------------------------------------------------------- geometry
class Placement(Spec):
    offset: Vector | None = None
    orientation: Orientation | None = None


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
    scale: Scalar = 1


GEOMETRY_KINDS = ("box", "cylinder", "sphere", "mesh")


def _geometry_kind(value: Any) -> str | None:
    kinds = [kind for kind in GEOMETRY_KINDS if isinstance(value, dict) and kind in value]
    return kinds[0] if len(kinds) == 1 else None


Geometry = Annotated[
    Union[  # noqa: UP007
        Annotated[BoxItem, Tag("box")],
        Annotated[CylinderItem, Tag("cylinder")],
        Annotated[SphereItem, Tag("sphere")],
        Annotated[MeshItem, Tag("mesh")],
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
    orientation: Orientation | None = None
    velocity: Vector | None = None
    angular_velocity: Vector | None = None
    geometry: tuple[Geometry, ...] = ()
    repeat: Repeats | None = None


# ------------------------------------------------------------------------------------ joints
class Table(Spec):
    """A function of t from a CSV table (casmech.schema.tables; docs/motors.md)."""

    table: StrictStr  # CSV file with a `t` column, path relative to the model file's folder
    column: StrictStr
    interpolation: Literal["linear", "cubic"] = "cubic"
    periodic: StrictBool = False


def _time_function_kind(value: Any) -> str:
    return "table" if isinstance(value, dict | Table) else "scalar"


TimeFunction = Annotated[  # an expression of t, or a data table
    Union[Annotated[Scalar, Tag("scalar")], Annotated[Table, Tag("table")]],  # noqa: UP007
    Discriminator(_time_function_kind),
]


class Driver(Spec):
    """Which keys a joint type allows is checked in semantic (E408)."""

    angle: TimeFunction | None = None
    displacement: TimeFunction | None = None


class Motor(Spec):
    """One mode per motion (casmech.schema.motors checks the keys against the joint type:
    revolute angle | speed | torque, translational displacement | velocity | force, cylindrical
    one of each). Unknown keys are reported there too, with the keys the joint type allows."""

    model_config = ConfigDict(extra="allow", frozen=True,
                              json_schema_extra={"additionalProperties": False})

    angle: TimeFunction | None = None
    speed: TimeFunction | None = None
    torque: TimeFunction | None = None
    displacement: TimeFunction | None = None
    velocity: TimeFunction | None = None
    force: TimeFunction | None = None


class Reactions(Spec):
    """How a joint's reaction columns are written (casmech.runtime.reaction_frames): the frame
    of their components and the point the torque is taken about (global at t = 0, carried by
    body_i; default the joint point)."""

    frame: Literal["global", "body_i", "body_j", "joint"] = "global"
    point: Vector | None = None


class JointBase(Spec):
    name: Name
    body_i: Name
    body_j: Name
    repeat: Repeats | None = None
    reactions: Reactions | None = None


class Composite(JointBase):
    driver: Driver | None = None
    motor: Motor | None = None
    # joint formulation: keep this joint as a loop-closure constraint, never a tree joint
    cut: StrictBool = False


class Limit(Spec):
    """A joint stop (compiler/limits.py): a one-sided spring-damper in the joint coordinate
    (revolute: the angle, translational and cylindrical: the slide) outside [lower, upper]."""

    lower: Scalar | None = None
    upper: Scalar | None = None
    stiffness: Scalar
    damping: Scalar = 0


class Basic(JointBase):
    f: TimeFunction = "0"


def joint_class(entry: JointType) -> type[Spec]:
    """The YAML class of a joint type, from its registry entry: `type`, its vector keys, its
    optional scalars, and `limit` when the type has a stop."""
    fields: dict[str, Any] = {"type": (Literal[entry.name], ...)}
    fields |= {key: (Vector, ...) for key in entry.vectors}
    fields |= {key: (Scalar | None, None) for key in entry.options}
    if entry.limit is not None:
        fields["limit"] = (Limit | None, None)
    return create_model(entry.class_name, __base__=Basic if entry.basic else Composite,
                        __module__=__name__, **fields)


JOINT_CLASSES: dict[str, type[Spec]] = {}  # joint type -> its class (joint_types.REGISTRY's)
_BUILT_FROM: dict[str, JointType] = {}  # joint type -> the entry its class was built from


def _joint_union():
    """The `joints:` item: a union of the registered types' classes, discriminated on `type`."""
    for name in set(JOINT_CLASSES) - set(REGISTRY):
        del JOINT_CLASSES[name], _BUILT_FROM[name]
    for name, entry in REGISTRY.items():
        if _BUILT_FROM.get(name) is not entry:
            JOINT_CLASSES[name], _BUILT_FROM[name] = joint_class(entry), entry
    classes = tuple(JOINT_CLASSES[name] for name in REGISTRY)
    return Annotated[Union[classes], Field(discriminator="type")]  # noqa: UP007


Joint = _joint_union()


def __getattr__(name: str) -> type[Spec]:
    """A joint type's class by its name (spec.Revolute, spec.DP1, ...)."""
    found = [cls for cls in JOINT_CLASSES.values() if cls.__name__ == name]
    if not found:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return found[0]


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


# ---------------------------------------------------------------------------------- analysis
class Analysis(Spec):
    type: Literal["kinematics", "dynamics", "inverse_dynamics", "statics", "assembly",
                  "modal"] = "dynamics"
    t_end: Scalar = 1.0
    output_step: Scalar = 0.01
    rtol: Scalar = 1e-8
    atol: Scalar = 1e-10
    # dynamics: r-p or r-omega DAE, joint coordinates (casmech.compiler.tree), or auto (the
    # fastest the model allows)
    formulation: Literal["rp", "romega", "joint", "auto"] = "auto"
    # dynamics: keep the constraints by the stabilized index-2 DAE (ggl) or by projecting the
    # index-1 DAE's state back when it drifts (projection); see casmech.compiler.dae
    stabilization: Literal["ggl", "projection"] = "ggl"
    # dynamics in joint coordinates of a tree: CVODES's Adams (non-stiff) or BDF (stiff) method,
    # or auto (by the stiffness of the ODE at t0; see casmech.runtime.joint_dynamics)
    method: Literal["auto", "adams", "bdf"] = "auto"


# ----------------------------------------------------------------------------------- events
class Event(Spec):
    """An event: where `when` (an expression of the results columns, joint coordinates, t and
    parameters) crosses zero in `direction`; `action` stop ends the run there, log records it
    (docs/format.md#events, casmech.schema.events)."""

    name: Name
    when: Scalar
    direction: Literal["rising", "falling", "both"] = "both"
    action: Literal["stop", "log"] = "log"


# ------------------------------------------------------- estimation and optimal control (issue 7)
Pair = Annotated[tuple[Scalar, ...], Field(min_length=2, max_length=2)]


class Estimate(Spec):
    """Fit parameters to measurements: `casmech optimize` (see casmech.optimal.estimate)."""

    parameters: Annotated[tuple[Name, ...], Field(min_length=1)]
    data: StrictStr  # CSV with a `t` column and measured results columns (path from the model)
    outputs: tuple[StrictStr, ...] | None = None  # default: every column of data but t
    weights: dict[StrictStr, Scalar] = Field(default_factory=dict)  # column -> weight (1)
    bounds: dict[StrictStr, Pair] = Field(default_factory=dict)  # parameter -> [low, high]


class Control(Spec):
    joint: Name
    type: Literal["torque", "force"] = "torque"
    bounds: Pair | None = None


class TerminalCost(Spec):
    weight: Scalar
    target: Scalar = 0


class Objective(Spec):
    effort: Scalar = 1  # weight of the integral of u^T u
    time: Scalar = 0  # weight of the final time (with free_time)
    terminal: dict[StrictStr, TerminalCost] = Field(default_factory=dict)  # column -> cost


class OptimalControl(Spec):
    """An optimal control problem on the model: `casmech optimize` (casmech.optimal.ocp)."""

    horizon: Scalar
    intervals: StrictInt = 30
    transcription: Literal["collocation", "shooting"] = "collocation"
    controls: Annotated[tuple[Control, ...], Field(min_length=1)]
    objective: Objective = Field(default_factory=Objective)
    terminal: dict[StrictStr, Scalar] = Field(default_factory=dict)  # column -> value at the end
    path: dict[StrictStr, Pair] = Field(default_factory=dict)  # column -> [low, high] at nodes
    free_time: Pair | None = None  # [low, high] of a free final time; horizon is its guess
    initial_guess: Literal["simulation", "interpolation"] = "simulation"  # casmech.optimal.guess
    elements: StrictInt = 1  # collocation elements per control interval
    stabilized: StrictBool = False  # collocation: Phi = 0 and Phi_q q_dot = nu at its points


# ---------------------------------------------------------- parameter studies (issue 18)
Number = Union[StrictInt, StrictFloat]  # noqa: UP007


class Study(Spec):
    """A parameter study: `casmech sweep` (casmech.study; docs/sweeps.md). Values are numbers
    or the command line's texts ("0.8:1.2:5", "100,200,400", "2,0.05"), checked by
    casmech.study.block with located errors."""

    grid: dict[StrictStr, StrictStr | Number | tuple[Number, ...]] = Field(default_factory=dict)
    samples: StrictInt = 0
    normal: dict[StrictStr, StrictStr | tuple[Number, ...]] = Field(default_factory=dict)
    uniform: dict[StrictStr, StrictStr | tuple[Number, ...]] = Field(default_factory=dict)
    seed: StrictInt = 0
    keep: tuple[StrictStr, ...] = ()


# ------------------------------------------------------ components and instances (issue 6)
class Instance(Spec):
    """One use of a component: its parameters (expressions of the user's parameters) and the
    placement of its frame (docs/components.md)."""

    name: Name
    component: Name
    parameters: dict[StrictStr, Scalar] = Field(default_factory=dict)
    position: Vector | None = None
    orientation: Orientation | None = None
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
    joints: tuple[Joint, ...] = ()
    forces: tuple[Force, ...] = ()
    instances: tuple[Instance, ...] = ()


ComponentRef = Annotated[
    Union[  # noqa: UP007
        Annotated[ComponentFile, Tag("file")],
        Annotated[Component, Tag("inline")],
    ],
    Discriminator(lambda v: "file" if isinstance(v, dict) and "file" in v else "inline"),
]


class ModelSpec(Spec):
    """A whole model file."""

    casmech: Version
    name: StrictStr
    description: StrictStr = ""
    parameters: dict[StrictStr, Scalar] = Field(default_factory=dict)
    gravity: Vector = (0, 0, -9.81)
    bodies: tuple[Body, ...]
    joints: tuple[Joint, ...] = ()
    forces: tuple[Force, ...] = ()
    analysis: Analysis = Field(default_factory=Analysis)
    events: tuple[Event, ...] = ()
    estimate: Estimate | None = None
    ocp: OptimalControl | None = None
    study: Study | None = None
    components: dict[StrictStr, ComponentRef] = Field(default_factory=dict)
    instances: tuple[Instance, ...] = ()

    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        title="casmech model",
        json_schema_extra=lambda schema: _model_schema(schema),
    )


def _model_schema(schema: dict) -> None:
    """$schema; `bodies` may be left out when `instances` give the bodies (docs/components.md)."""
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    schema["required"] = [key for key in schema.get("required", []) if key != "bodies"]
    schema["anyOf"] = [{"required": ["bodies"]}, {"required": ["instances"]}]


def _joints_changed() -> None:
    """A joint type was (un)registered: rebuild the union and the classes that hold it."""
    global Joint
    Joint = _joint_union()
    for cls in (Component, ModelSpec):
        cls.model_fields["joints"] = FieldInfo.from_annotated_attribute(tuple[Joint, ...], ())
        cls.model_rebuild(force=True)


on_change(_joints_changed)
