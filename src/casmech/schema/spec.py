"""The model format (docs/format.md) as pydantic v2 models, one class per YAML mapping.

Frozen, `extra="forbid"`; joints and forces are unions discriminated on `type`, inertia and
geometry items on their shape. Every scalar is a number or an expression string (evaluated in
`semantic`); `spec_errors.validate` turns pydantic's errors into Diagnostics.

The classes live in the parts, by what they hold: casmech.core.spec_base (scalars, vectors),
spec_bodies, spec_joints (one class per joint type of casmech.elements.joint_types),
spec_forces, spec_analysis; the classes of what a document may leave out live in parts
imported when a document first has one (spec_base.Deferred): casmech.core.spec_items
(orientations, repeat), spec_shapes (geometry other than boxes), spec_joint_blocks (reactions,
limits, friction), spec_events (events, outputs), spec_components (components, instances),
spec_problems (estimation, optimal control, studies). This module holds the whole file
(ModelSpec) and gives every part's names as its own (`spec.Body`, `spec.Instance`, `from
casmech.schema.spec import Revolute`).
"""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

import importlib
import sys
from functools import partial
from typing import Annotated, Any, Literal, Union

from pydantic import ConfigDict, Discriminator, Field, StrictStr, Tag
from pydantic.fields import FieldInfo

from casmech.core import options, spec_base
from casmech.core.spec_base import (
    Deferred,
    Scalar,
    Spec,
    Vector,
    Version,
)
from casmech.elements import coordinate_kinds, force_types
from casmech.elements.joint_types import on_change
from casmech.schema import spec_analysis, spec_bodies, spec_forces, spec_joints
from casmech.schema.spec_analysis import Analysis, section
from casmech.schema.spec_bodies import Body
from casmech.schema.spec_forces import Force
from casmech.schema.spec_joints import Joint

PARTS = (spec_base, spec_bodies, spec_joints, spec_analysis, spec_forces)
# the part imported when first used: the sections of `casmech optimize` and `casmech sweep`
PROBLEMS = "casmech.schema.spec_problems"


def _problem(name: str) -> type[Spec]:
    """A class of spec_problems (the module imported on the first call)."""
    return getattr(importlib.import_module(PROBLEMS), name)


# the optional sections of spec_problems' classes
EstimateSection, OptimalControlSection, StudySection = (
    Annotated[Spec, Deferred(partial(_problem, name))] | None
    for name in ("Estimate", "OptimalControl", "Study"))


# ------------------------------------------------------ components and instances (issue 6)
COMPONENTS = "casmech.schema.spec_components"  # Instance, ComponentFile, Component


def _component(name: str) -> type[Spec]:
    """A class of spec_components (the module imported on the first call)."""
    return getattr(importlib.import_module(COMPONENTS), name)


ComponentRef = Annotated[
    Union[  # noqa: UP007
        Annotated[Spec, Deferred(partial(_component, "ComponentFile")), Tag("file")],
        Annotated[Spec, Deferred(partial(_component, "Component")), Tag("inline")],
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
    # the sections a model may leave out: validated by their classes' own validators, built
    # when a document first has one (spec_base.Deferred)
    events: tuple[Annotated[Spec, Deferred(partial(section, "Event"))], ...] = ()
    outputs: tuple[Annotated[Spec, Deferred(partial(section, "Output"))], ...] = ()
    estimate: EstimateSection = None
    ocp: OptimalControlSection = None
    study: StudySection = None
    components: dict[StrictStr, ComponentRef] = Field(default_factory=dict)
    instances: tuple[Annotated[Spec, Deferred(partial(_component, "Instance"))], ...] = ()

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


def _holders() -> tuple[type[Spec], ...]:
    """The classes holding joints and forces: ModelSpec, and Component once made."""
    components = sys.modules.get(COMPONENTS)
    return (ModelSpec,) if components is None else (components.Component, ModelSpec)


def _joints_changed() -> None:
    """A joint type was (un)registered: rebuild the union and the classes that hold it."""
    global Joint
    Joint = spec_joints.rebuild()
    for cls in _holders():
        cls.model_fields["joints"] = FieldInfo.from_annotated_attribute(tuple[Joint, ...], ())
        cls.model_rebuild(force=True)


on_change(_joints_changed)


def _kinds_changed() -> None:
    """A coordinate kind was (un)registered: its driver, motor and initial keys in every joint
    class."""
    spec_joints.kinds_changed()
    _joints_changed()


coordinate_kinds.on_change(_kinds_changed)


def _forces_changed() -> None:
    """A force element type was (un)registered: rebuild the union and the classes that hold
    it."""
    global Force
    Force = spec_forces.rebuild()
    for cls in _holders():
        cls.model_fields["forces"] = FieldInfo.from_annotated_attribute(tuple[Force, ...], ())
        cls.model_rebuild(force=True)


force_types.on_change(_forces_changed)


def _formulations_changed() -> None:
    """A formulation was (un)registered (formulations.registry): the analysis block's
    `formulation` takes the registered ones and auto."""
    field = Analysis.model_fields["formulation"]
    Analysis.model_fields["formulation"] = FieldInfo.from_annotated_attribute(
        Literal[tuple(options.FORMULATIONS)], field.default)
    for cls in (Analysis, *_holders()):
        cls.model_rebuild(force=True)


options.FORMULATIONS.on_change(_formulations_changed)


def __getattr__(name: str) -> Any:
    """Every name of the parts (spec.Body, spec.Revolute, spec.Analysis, ...)."""
    for part in PARTS:
        try:
            return getattr(part, name)
        except AttributeError:
            pass
    if name in ("Instance", "ComponentFile", "Component"):
        return _component(name)
    if not name.startswith("__"):  # (the import system asks for `__path__`)
        try:
            return _problem(name)
        except AttributeError:
            pass
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
