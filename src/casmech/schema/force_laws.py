"""Force elements (their checks: casmech.elements.force_types) and the force laws that read the
state of
the mechanism (docs/forces.md).

The keys a force type's entry names in `state_keys` (a force's or torque's `value`, a tsda's or
rsda's `actuator`) may name the state
(`pivot.angle`, `slide.displacement_dot`, `bar.vx`; the names are casmech.core.states)
besides t and parameters. `StateChecker` lets those expressions (and only those) read it, and
says what is wrong with a dotted name anywhere: a state where none is allowed, a misspelt one
(did you mean), an attribute the joint type does not have, ground.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from typing import Any

import numpy as np

from casmech.core import traced
from casmech.core.states import BODY_STATES, JOINT_COORDINATES, split
from casmech.elements.force_types import REGISTRY, state_reading
from casmech.elements.joint_types import COORDINATES, coordinate_types, listed
from casmech.elements.joint_types import attributes as joint_attributes
from casmech.errors import did_you_mean, failed
from casmech.schema import bodies, resolved
from casmech.schema.checker import Checker
from casmech.schema.loader import Path


def state_names() -> tuple[str, ...]:
    """Examples of the state names for a hint: each coordinate kind's, a body's."""
    return (*(f"<joint>.{kind}" for kind in COORDINATES), "<body>.vx", "...")
BODY_INITIAL = {"": "position", "v": "velocity", "w": "angular_velocity"}


def _body_value(body: resolved.Body | None, column: str) -> float:
    """A body column's value at t = 0 as the file writes it (accelerations 0; a body that
    failed its checks: 0), for the checks of the expressions that read it."""
    if body is None or column.startswith("a"):
        return 0.0
    if column.startswith("e"):
        return float(traced.value(body.euler_parameters[int(column[1])]))
    return float(traced.value(getattr(body, BODY_INITIAL[column[:-1]])["xyz".index(column[-1])]))


def initial_states(check: Checker, columns=BODY_STATES) -> dict[str, float]:
    """Every state name a force law may read (an event: `columns` of each body), with its value
    at t = 0 (joint coordinates: 0)."""
    states = {f"{joint}.{attribute}": 0.0 for joint, kind in check.joint_types.items()
              for attribute in joint_attributes(kind)}
    states.update({f"{name}.{column}": _body_value(body, column)
                   for name, body in check.bodies.items() for column in columns})
    return states


class StateChecker(Checker):
    """A Checker whose functions read the state inside `reading_state()`."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self.states: dict[str, float] | None = None

    @contextmanager
    def reading_state(self) -> Iterator[None]:
        self.states = initial_states(self)
        try:
            yield
        finally:
            self.states = None

    def function(self, path: Path, value: Any, at):
        """As Checker.function; its variables are `at`'s plus the states the expression uses."""
        found = super().function(path, value, {**at, **(self.states or {})})
        if found is None or not self.states:
            return found
        used = tuple(name for name in self.states if name in found.expr.symbols)
        return replace(found, variables=(*at, *used))

    def orientation(self, path: Path, given) -> np.ndarray | None:
        """An `orientation:` item as Euler parameters (a bushing's frame)."""
        return bodies.orientation(self, path, given)

    def unknown_symbol(self, path, name: str, source, variables) -> None:
        if "." not in name:
            super().unknown_symbol(path, name, source, variables)
            return
        allowed = self.states is not None and self.states.keys() <= set(variables)
        message, hint = self.misnamed_state(name) if allowed else self.misplaced_state(name)
        self.error("E201", path, message, source=source, hint=hint)

    def misplaced_state(self, name: str) -> tuple[str, str]:
        _, attribute = split(name)
        if attribute in JOINT_COORDINATES or attribute in BODY_STATES:
            return (f"the state '{name}' is not allowed here",
                    f"states are read in: {state_reading()}")
        return (f"unknown symbol '{name}'",
                f"dotted names are states ({', '.join(state_names())}), read in: {state_reading()}")

    def misnamed_state(self, name: str) -> tuple[str, str | None]:
        owner, attribute = split(name)
        if owner == resolved.GROUND:
            return "'ground' does not move: it has no state", "name a moving body or a joint"
        if owner in self.joint_types:
            kind = self.joint_types[owner]
            has = joint_attributes(kind)
            known = ", ".join(has) if has else "no coordinates (" \
                f"{listed(coordinate_types())} joints have)"
            hint = did_you_mean(attribute, has) or f"{kind} joints have {known}"
            return f"{kind} joint '{owner}' has no '{attribute}'", hint
        if owner in self.bodies:
            hint = did_you_mean(attribute, BODY_STATES) or f"bodies have {', '.join(BODY_STATES)}"
            return f"body '{owner}' has no '{attribute}'", hint
        known = [*self.joint_types, *self.bodies]
        hint = did_you_mean(name, self.states or {}) or did_you_mean(owner, known)
        return f"unknown state '{name}': no body or joint '{owner}'", hint


# ------------------------------------------------------------------------- force elements
def force(check: StateChecker, index: int, given) -> resolved.Force | None:
    """One entry of `forces:`, checked by its casmech.elements.force_types entry; the keys the entry
    names in `state_keys` read the state."""
    path = ("forces", index)
    entry = REGISTRY[given.type]
    if entry.state_keys:
        with check.reading_state():
            fields = entry.resolve(check, path, given)
    else:
        fields = entry.resolve(check, path, given)
    if fields is None or failed([*fields.values(), *(fields.get("value") or ())]):
        return None
    return resolved.Force(given.name, given.type, **fields, source=check.doc.locate(path))
