"""Force laws that read the state of the mechanism, and the bushing (docs/forces.md).

A force's or torque's `value` and a tsda's or rsda's `actuator` may name the state
(`pivot.angle`, `slide.displacement_dot`, `bar.vx`; the names are casmech.geometry.states)
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

from casmech.errors import did_you_mean
from casmech.geometry.states import BODY_STATES, JOINT_COORDINATES, split
from casmech.joint_types import attributes as joint_attributes
from casmech.joint_types import coordinate_types, listed
from casmech.schema import connections, resolved
from casmech.schema.bodies import orientation
from casmech.schema.checker import Checker, failed
from casmech.schema.contact import SHAPES, contact
from casmech.schema.loader import Path

STATE_KEYS = "force/torque value, tsda/rsda actuator"
STATE_NAMES = ("<joint>.angle", "<joint>.displacement", "<body>.vx", "...")
BUSHING_VECTORS = ("at", "stiffness", "damping", "rotational_stiffness", "rotational_damping",
                   "preload_force", "preload_torque")
NON_NEGATIVE = ("stiffness", "damping", "rotational_stiffness", "rotational_damping")
BODY_INITIAL = {"": "position", "v": "velocity", "w": "angular_velocity"}


def _body_value(body: resolved.Body | None, column: str) -> float:
    """A body column's value at t = 0 as the file writes it (accelerations 0; a body that
    failed its checks: 0)."""
    if body is None or column.startswith("a"):
        return 0.0
    if column.startswith("e"):
        return float(body.euler_parameters[int(column[1])])
    return float(getattr(body, BODY_INITIAL[column[:-1]])["xyz".index(column[-1])])


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
            return f"the state '{name}' is not allowed here", f"states are read in: {STATE_KEYS}"
        return (f"unknown symbol '{name}'",
                f"dotted names are states ({', '.join(STATE_NAMES)}), read in: {STATE_KEYS}")

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


# --------------------------------------------------------------------------------- bushing
def bushing(check: Checker, path: Path, given) -> dict[str, Any] | None:
    bodies_ok = check.two_bodies(path, given.body_i, given.body_j)
    vectors = {key: check.numbers((*path, key), getattr(given, key)) for key in BUSHING_VECTORS}
    for key in NON_NEGATIVE:
        if vectors[key] is not None and np.any(vectors[key] < 0):
            got = ", ".join(f"{v:g}" for v in vectors[key])
            check.error("E103", (*path, key), f"bushing {key.replace('_', ' ')} must not be "
                        "negative", got=got, hint="zero leaves that direction free")
            vectors[key] = None
    vectors["orientation"] = orientation(check, (*path, "orientation"), given.orientation)
    if not bodies_ok or failed(vectors.values()):
        return None
    return dict(body_i=given.body_i, body_j=given.body_j, vectors=vectors)


# force types resolved here (contact: schema/contact.py); the others in connections.py
LAWS = {"bushing": bushing, **dict.fromkeys(SHAPES, contact)}


def force(check: Checker, index: int, given) -> resolved.Force | None:
    """One entry of `forces:`; value and actuator read the state when `check` can."""
    if given.type in LAWS:
        path = ("forces", index)
        fields = LAWS[given.type](check, path, given)
        return None if fields is None else resolved.Force(
            given.name, given.type, **fields, source=check.doc.locate(path))
    if not isinstance(check, StateChecker):
        return connections.force(check, index, given)
    with check.reading_state():
        return connections.force(check, index, given)
