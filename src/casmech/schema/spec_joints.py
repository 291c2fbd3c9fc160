"""`joints:` items (schema/spec.py): the keys every joint has, drivers, motors, tables, limits,
and one class per registered joint type, built from its casmech.elements.joint_types entry."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

import importlib
from functools import partial
from typing import Annotated, Any, Literal, Union

from pydantic import (
    Discriminator,
    Field,
    StrictBool,
    StrictStr,
    Tag,
    create_model,
)

from casmech.core.spec_base import (
    Deferred,
    Name,
    OrientationField,
    Repeats,
    Scalar,
    Spec,
    Vector,
)
from casmech.elements.coordinate_kinds import REGISTRY as KINDS
from casmech.elements.joint_types import REGISTRY, JointType, initial_keys


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


DRIVER_DOC = "Which keys a joint type allows is checked in semantic (E408)."
MOTOR_DOC = """One mode per motion (casmech.schema.motors checks the keys against the joint type:
revolute angle | speed | torque, translational displacement | velocity | force, cylindrical
one of each). Unknown keys are reported there too, with the keys the joint type allows."""


def driver_class() -> type[Spec]:
    """`driver:`: one key per registered coordinate kind (casmech.elements.coordinate_kinds)."""
    fields: dict[str, Any] = {name: (TimeFunction | None, None) for name in KINDS}
    return create_model("Driver", __base__=Spec, __module__=__name__, __doc__=DRIVER_DOC,
                        **fields)


def motor_class() -> type[Spec]:
    """`motor:`: the registered coordinate kinds' motor modes, kind by kind."""
    fields: dict[str, Any] = {mode: (TimeFunction | None, None) for kind in KINDS.values()
                              for mode in kind.motor}
    return create_model("Motor", __base__=block("MotorBase"), __module__=__name__,
                        __doc__=MOTOR_DOC, **fields)


# the blocks a joint may have, most joints leave out: made (or their module imported) when first
# asked for, and validated by their classes' own validators (spec_base.Deferred)
BLOCKS = "casmech.schema.spec_joint_blocks"  # Reactions, Limit, JointFriction, MotorBase
_MADE: dict[str, type[Spec]] = {}  # Driver and Motor as made for the current coordinate kinds


def block(name: str) -> type[Spec]:
    """The class of a joint's block: Driver, Motor (made for the registered coordinate kinds),
    or a class of spec_joint_blocks."""
    if name in ("Driver", "Motor"):
        if name not in _MADE:
            _MADE[name] = (driver_class if name == "Driver" else motor_class)()
        return _MADE[name]
    return getattr(importlib.import_module(BLOCKS), name)


def _block(name: str) -> Any:
    """The annotation of a field holding a joint's block, or None."""
    return Annotated[Spec, Deferred(partial(block, name))] | None


class JointBase(Spec):
    name: Name
    body_i: Name
    body_j: Name
    repeat: Repeats | None = None
    reactions: _block("Reactions") = None


class Composite(JointBase):
    driver: _block("Driver") = None  # (made again when a coordinate kind is (un)registered)
    motor: _block("Motor") = None
    # joint formulation: keep this joint as a loop-closure constraint, never a tree joint
    cut: StrictBool = False


def kinds_changed() -> None:
    """A coordinate kind was (un)registered: Driver, Motor and the `initial:` classes made
    again when next asked for, and every joint class built again by the next `rebuild`."""
    _MADE.clear()
    _INITIAL.clear()
    _BUILT_FROM.clear()


class Basic(JointBase):
    f: TimeFunction = "0"


# `initial:` keys that are not scalars (a spherical joint's relative rotation and rate)
INITIAL_FORMS: dict[str, Any] = {"orientation": OrientationField, "angular_velocity": Vector}


def initial_class(entry: JointType) -> type[Spec] | None:
    """The class of a joint type's `initial:` (schema/initial.py), or None when it has none."""
    keys = initial_keys(entry.name)
    if not keys:
        return None
    fields = {key: (INITIAL_FORMS.get(key, Scalar) | None, None) for key in keys}
    return create_model(f"{entry.class_name}Initial", __base__=Spec, __module__=__name__,
                        **fields)


_INITIAL: dict[str, tuple[JointType, type[Spec]]] = {}  # joint type -> (entry, its `initial:`)


def initial_class_of(entry: JointType) -> type[Spec]:
    """The `initial:` class of a joint type's entry, made when first asked for (and again
    after a coordinate kind changed: kinds_changed)."""
    made = _INITIAL.get(entry.name)
    if made is None or made[0] is not entry:
        _INITIAL[entry.name] = made = (entry, initial_class(entry))
    return made[1]


class CouplingBase(Spec):
    """A coupling of other joints' coordinates (joint_types.Couples): no bodies of its own."""

    name: Name
    repeat: Repeats | None = None
    reactions: _block("Reactions") = None


def coupling_class(entry: JointType) -> type[Spec]:
    """The YAML class of a coupling: the keys naming its joints (or `joints:` and
    `coefficients:` lists) and its scalars."""
    couples = entry.couples
    fields: dict[str, Any] = {"type": (Literal[entry.name], ...)}
    if couples.joints:
        fields |= {key: (Name, ...) for key in couples.joints}
    else:
        fields |= {"joints": (tuple[Name, ...], ...), "coefficients": (tuple[Scalar, ...], ...),
                   "offset": (Scalar, 0)}
    fields |= {key: (Scalar, ...) for key in couples.scalars}
    return create_model(entry.class_name, __base__=CouplingBase, __module__=__name__, **fields)


def joint_class(entry: JointType) -> type[Spec]:
    """The YAML class of a joint type, from its registry entry: `type`, its vector keys, its
    optional scalars, `limit` and `friction` when the type has a stop and `initial` when it
    has initial values (a coupling: coupling_class)."""
    if entry.couples is not None:
        return coupling_class(entry)
    fields: dict[str, Any] = {"type": (Literal[entry.name], ...)}
    fields |= {key: (Vector, ...) for key in entry.vectors}
    fields |= {key: (Scalar | None, None) for key in entry.options}
    if entry.limit is not None:
        fields["limit"] = (_block("Limit"), None)
        fields["friction"] = (_block("JointFriction"), None)
    if initial_keys(entry.name):
        fields["initial"] = (
            Annotated[Spec, Deferred(partial(initial_class_of, entry))] | None, None)
    return create_model(entry.class_name, __base__=Basic if entry.basic else Composite,
                        __module__=__name__, **fields)


JOINT_CLASSES: dict[str, type[Spec]] = {}  # joint type -> its class, made when first asked for
_BUILT_FROM: dict[str, JointType] = {}  # joint type -> the entry its class was built from


def joint_class_of(name: str) -> type[Spec]:
    """The class of a registered joint type, made from its current registry entry when first
    asked for (and again after the entry or a coordinate kind changed)."""
    entry = REGISTRY[name]
    if _BUILT_FROM.get(name) is not entry:
        JOINT_CLASSES[name], _BUILT_FROM[name] = joint_class(entry), entry
    return JOINT_CLASSES[name]


def _joint_union():
    """The `joints:` item: a union of the registered types' classes, discriminated on `type`,
    each made and validated by its own validator when a document first holds one
    (spec_base.Deferred)."""
    for name in set(JOINT_CLASSES) - set(REGISTRY):
        del JOINT_CLASSES[name], _BUILT_FROM[name]
    classes = tuple(Annotated[Spec, Deferred(partial(joint_class_of, name), name), Tag(name)]
                    for name in REGISTRY)
    return Annotated[Union[classes], Field(discriminator="type")]  # noqa: UP007


Joint = _joint_union()


def rebuild():
    """The union after a joint type was (un)registered (schema/spec.py rebuilds its users)."""
    global Joint
    Joint = _joint_union()
    return Joint


def __getattr__(name: str) -> type[Spec]:
    """A joint type's class by its name (spec.Revolute, spec.DP1, ...), or a block's
    (spec.Driver, spec.Limit, ...)."""
    if name in ("Driver", "Motor", "Reactions", "Limit", "JointFriction", "MotorBase"):
        return block(name)
    found = [key for key, entry in REGISTRY.items() if entry.class_name == name]
    if not found:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return joint_class_of(found[0])
