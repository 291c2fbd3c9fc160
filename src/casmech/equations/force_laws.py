"""The law of every force element type: ForceIR type -> (force, x) -> (generalized force over
q, potential). The force types of casmech.elements.force_types (their `law`, reading the state
through equations.coordinates), then the joints' effort motors (ir.motors: equations.motors) and
stops (ir.limits: equations.limits). Generalized forces come from virtual work by AD
(casmech.elements.forces.terms)."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from functools import partial

from casmech.elements.force_types import REGISTRY as FORCE_TYPES
from casmech.equations import coordinates, friction, limits, motors


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


JOINT_ELEMENTS: dict[str, Callable] = {
    "limit_angle": limits.generalized_force,  # stops (ir.limits)
    "limit_displacement": limits.generalized_force,
    "friction_angle": friction.generalized_force,  # joint friction (ir.limits)
    "friction_displacement": friction.generalized_force,
    **motors.FORCE_ELEMENTS,  # effort motors of joints (ir.motors)
}
FORCE_ELEMENTS: Mapping[str, Callable] = _Elements()
INPUT_KINDS: Mapping[str, tuple] = _Inputs()


def elements(ir) -> tuple:
    """Every element with a law: the force elements, the effort motors, the stops."""
    return (*ir.forces, *ir.motors, *ir.limits)
