"""The force element registry: one entry per force element type (`ForceType`), read by every
stage.

An entry says everything casmech knows about a type: its YAML class (schema/spec_forces.py puts
it in the `forces:` union), its checks (`resolve`, called by schema/force_laws.py with the
schema's Checker), its lowering to the ForceIR fields (`lower`, called by model/lower.py with
its poses helper), its generalized force and potential energy (`law`, equations/eom.py), whether
it is an input of a linearization (`inputs`; schema/modal.py, runtime/linearize.py), which keys
read the state, its extra results columns (`outputs`; contacts), whether it limits the
integrator's step (runtime/contact_steps.py) and its mapped kernel (equations/force_kernels.py). The
code of the built-in types is in casmech.elements.forces. Adding a force element is
`register(ForceType(...))` (docs/architecture.md, "Adding a force element";
tests/unit/elements/test_force_registry.py registers one).

The callables receive what they need from the calling layer as arguments, so this module and
casmech.elements.forces import nothing from schema/ or model/:

- resolve(check, path, given) -> dict | None: the resolved.Force fields of the YAML item
  `given` (its class), or None after reporting a problem through `check` (the schema's
  StateChecker, schema/force_laws.py: error, number, numbers, vector, direction, function,
  reference, two_bodies, orientation; bodies, joint_types, joint_bodies). `path` locates the
  item; the fields hold no None.
- lower(force, model, poses) -> dict: the ForceIR fields besides name, type and source
  (body_i, body_j as indices, points and axes in the bodies' frames, params, actuator, value,
  frame) of a resolved.Force. `poses` (model/lower.py): `index[body]`, `local(body,
  quantity, global vector)` ("P" a point, "axis" a direction), `pose[body]` = (r0, A0),
  `joint(name)` = (resolved joint, its global joint frame at t = 0).
- law(force, x, read) -> (generalized force over q, potential energy) of a ForceIR: x the
  model's coordinates (equations/assemble.Coordinates: t, q, q_dot, frame(k), r(k), p(k)),
  `read(function, x)` the state values a force law (ScalarFunction) reads, to pass to its
  `casadi(t=..., **values)`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from functools import partial

import numpy as np

from casmech.core.records import record
from casmech.core.registry import Registry
from casmech.elements.forces import bushing, contact, contact_spec, loads, springs


@record
class Kernel:
    """An element's law as one SX kernel mapped over its instances (equations/force_kernels.py):
    the numbers of an instance (`data(force)`), the entries of its value input (a force or torque
    vector: 3), and `build(type, frame, motion, data, value, actuator, frame_name)` ->
    (generalized force over the pair's 14 coordinates (or body i's 7), potential), with
    `frame(0)`, `frame(1)` the two bodies' frames and motion = (x, x_dot, t)."""

    data: Callable[..., np.ndarray]
    build: Callable[..., tuple]
    n_value: int = 0


@record
class ForceType:
    """One force element type (module docstring)."""

    name: str  # YAML `type:`
    # its YAML class (pydantic, casmech.core.spec_base.Spec): `type: Literal[name]`; or a
    # function of no arguments returning it, called when the schema first needs it (spec_of)
    spec: type | Callable[[], type]
    resolve: Callable[..., dict | None]
    lower: Callable[..., dict]
    law: Callable[..., tuple]
    state_keys: tuple[str, ...] = ()  # its keys whose expressions may read the state
    inputs: tuple[str, ...] = ()  # input name suffixes when it is a linearization input
    with_inputs: Callable | None = None  # (ForceIR, u) -> the ForceIR with its law the inputs
    outputs: tuple[str, ...] = ()  # its results columns `<name>.<output>`
    output_values: Callable | None = None  # (ForceIR, x) -> their expressions
    contact: bool = False  # the integrator's step is capped at the output step
    thickness: Callable[[Mapping], float] | None = None  # params -> depth of its overlap window
    one_body: bool = False  # acts on body_i only (none on ground)
    kernel: Kernel | None = None
    points: Callable | None = None  # a contact's (ForceIR, x) -> its contact.Point list
    # its law reads t and the motion of body_j relative to body_i only, not where the pair is:
    # on the two bodies of a tree joint, a generalized force on that joint's coordinates
    # (formulations/joint_forces.py)
    relative: bool = False


def _spec(name: str) -> type:
    """A built-in type's YAML class: casmech.elements.forces.specs, imported on the first call
    (a model without force elements makes none of their classes)."""
    from casmech.elements.forces import specs

    return getattr(specs, name)


def spec_of(entry: ForceType) -> type:
    """The YAML class of an entry (its `spec`, or what that function returns)."""
    return entry.spec if isinstance(entry.spec, type) else entry.spec()


def _contact(name: str, spec: Callable, shape_spec: Callable, shape: Callable,
             **extra) -> ForceType:
    return ForceType(name, spec, partial(contact_spec.resolve, shape=shape_spec), contact.lower,
                     partial(contact.generalized_force, shape=shape),
                     outputs=contact.OUTPUTS, output_values=partial(contact.outputs, shape=shape),
                     contact=True, points=shape, **extra)


BUILT_IN = (
    ForceType("tsda", partial(_spec, "TSDA"), springs.resolve_tsda, springs.lower_tsda, springs.law,
              state_keys=("actuator",), inputs=("force",), with_inputs=springs.with_inputs,
              kernel=Kernel(springs.kernel_data, springs.kernel), relative=True),
    ForceType("rsda", partial(_spec, "RSDA"), springs.resolve_rsda, springs.lower_rsda, springs.law,
              state_keys=("actuator",), inputs=("torque",), with_inputs=springs.with_inputs,
              kernel=Kernel(springs.kernel_data, springs.kernel), relative=True),
    ForceType("force", partial(_spec, "PointForce"), loads.resolve_force, loads.lower,
              loads.force_law,
              state_keys=("value",), inputs=("fx", "fy", "fz"), with_inputs=loads.with_inputs,
              one_body=True, kernel=Kernel(loads.force_data, loads.force_kernel, 3)),
    ForceType("torque", partial(_spec, "Torque"), loads.resolve_torque, loads.lower,
              loads.torque_law,
              state_keys=("value",), inputs=("tx", "ty", "tz"), with_inputs=loads.with_inputs,
              one_body=True, kernel=Kernel(loads.no_data, loads.torque_kernel, 3)),
    ForceType("bushing", partial(_spec, "Bushing"), bushing.resolve, bushing.lower, bushing.law,
              inputs=("fx", "fy", "fz", "tx", "ty", "tz"), with_inputs=bushing.with_inputs),
    _contact("sphere_plane", partial(_spec, "SpherePlane"), contact_spec.sphere_plane,
             contact.sphere_plane),
    _contact("sphere_sphere", partial(_spec, "SphereSphere"), contact_spec.sphere_sphere,
             contact.sphere_sphere, thickness=contact.pair_thickness),
    _contact("points_plane", partial(_spec, "PointsPlane"), contact_spec.points_plane,
             contact.points_plane),
    _contact("capsule_plane", partial(_spec, "CapsulePlane"), contact_spec.capsule_plane,
             contact.capsule_plane),
)

REGISTRY: Registry = Registry(BUILT_IN)  # name -> ForceType
# register(entry) adds or replaces a type, unregister(name) removes it, on_change(listener)
# follows both (casmech.core.registry)
register, unregister, on_change = REGISTRY.register, REGISTRY.unregister, REGISTRY.on_change


def entry_of(force_type: str) -> ForceType | None:
    """The entry of a force element type (None: a joint's motor or stop, equations/eom.py)."""
    return REGISTRY.get(force_type)


def input_types() -> tuple[str, ...]:
    """The types whose elements may be inputs of a linearization, in registry order."""
    return tuple(name for name, entry in REGISTRY.items() if entry.inputs)


def outputs_of(force_type: str) -> tuple[str, ...]:
    """The extra results columns of an element of this type (none for motors and stops)."""
    entry = REGISTRY.get(force_type)
    return () if entry is None else entry.outputs


def state_reading() -> str:
    """Where force laws read the state, e.g. 'force/torque value, tsda/rsda actuator': the
    types by key, keys in reverse alphabetical order."""
    keys: dict[str, list[str]] = {}
    for name, entry in REGISTRY.items():
        for key in entry.state_keys:
            keys.setdefault(key, []).append(name)
    return ", ".join(f"{'/'.join(keys[key])} {key}" for key in sorted(keys, reverse=True))
