"""The law of every force element type: ForceIR type -> (force, x) -> (generalized force over
q, potential). The force types of casmech.elements.force_types (their `law`, reading the state
through equations.coordinates), then the joints' effort motors (ir.motors: equations.motors) and
stops (ir.limits: equations.limits). Generalized forces come from virtual work by AD
(casmech.elements.forces.terms)."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from functools import partial

from casmech.elements.coordinate_kinds import BY_TYPE, RELATIVE_ROLES, View
from casmech.elements.force_types import REGISTRY as FORCE_TYPES
from casmech.equations import coordinates, friction, limits, motors
from casmech.schema.resolved import ScalarFunction


class _Elements(Mapping):
    """ForceIR type -> its law (force, x) -> (generalized force, potential)."""

    def __getitem__(self, kind: str) -> Callable:
        entry = FORCE_TYPES.get(kind)
        if entry is not None:
            return partial(entry.law, read=coordinates.values)
        return JOINT_ELEMENTS[kind]

    def __iter__(self) -> Iterator[str]:
        yield from FORCE_TYPES
        yield from JOINT_ELEMENTS

    def __len__(self) -> int:
        return len(FORCE_TYPES) + len(JOINT_ELEMENTS)


class _Inputs(Mapping):
    """ForceIR type -> (input name suffixes, (element, u) -> the element with its law replaced
    by the inputs u) of the elements that may be linearization inputs (runtime/linearize.py):
    effort motors, and the force element types with `inputs`."""

    def __getitem__(self, kind: str) -> tuple:
        entry = FORCE_TYPES.get(kind)
        if entry is not None and entry.inputs:
            return entry.inputs, entry.with_inputs
        return motors.INPUTS[kind]

    def __iter__(self) -> Iterator[str]:
        yield from motors.INPUTS
        yield from (name for name, entry in FORCE_TYPES.items() if entry.inputs)

    def __len__(self) -> int:
        return sum(1 for _ in self)


# a coordinate kind's element role -> its law: effort motors (ir.motors), stops and joint
# friction (ir.limits)
ROLE_LAWS = {"effort": motors.generalized_force, "limit": limits.generalized_force,
             "friction": friction.generalized_force}
# ForceIR type of a coordinate kind's element (casmech.elements.coordinate_kinds) -> its law
JOINT_ELEMENTS: Mapping[str, Callable] = View(
    lambda: {kind_type: ROLE_LAWS[role] for kind_type, (_, role) in BY_TYPE.items()})
FORCE_ELEMENTS: Mapping[str, Callable] = _Elements()
INPUT_KINDS: Mapping[str, tuple] = _Inputs()


def elements(ir) -> tuple:
    """Every element with a law: the force elements, the effort motors, the stops."""
    return (*ir.forces, *ir.motors, *ir.limits)


def relative(element) -> bool:
    """Whether an element's law reads t and the motion of its body_j relative to its body_i
    only: a force type whose entry says so (ForceType.relative) or a joint's effort motor or
    stop (coordinate_kinds.RELATIVE_ROLES), whose laws are expressions of t and its own
    coordinate and rate (no other state bound, no input symbol)."""
    entry = FORCE_TYPES.get(element.type)
    if entry is not None:
        if not entry.relative:
            return False
    elif BY_TYPE[element.type][1] not in RELATIVE_ROLES:
        return False
    laws = ([element.actuator] if element.actuator is not None else []) + list(element.value or ())
    return all(isinstance(law, ScalarFunction) and not getattr(law, "states", None)
               for law in laws)
