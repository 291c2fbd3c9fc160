"""The `events:` block: names, the `when` expression and what it may read (docs/format.md#events).

`when` is an expression of t, the parameters and the state: every body column of the results
table (`bar.x` ... `bar.alphaz`, resolved.BODY_COLUMNS) and the coordinates of revolute,
cylindrical and translational joints (`pivot.angle`, `slide.displacement_dot`: the names of
casmech.core.states). A misspelt or unknown name is E201 at its place in the expression, with
a did-you-mean hint; a duplicate event name is E301.
"""

from __future__ import annotations

from dataclasses import replace

from casmech.core.columns import BODY_COLUMNS, JOINT_COLUMNS
from casmech.core.expressions import ExpressionError, parse
from casmech.elements.joint_types import attributes as joint_attributes
from casmech.elements.joint_types import coordinate_types, listed
from casmech.errors import did_you_mean
from casmech.schema import contact, resolved, spec
from casmech.schema.checker import Checker
from casmech.schema.force_laws import initial_states
from casmech.schema.loader import Path, format_path


def state_names(check: Checker) -> dict[str, float]:
    """Every state name `when` may read, with its value at t = 0 (joint coordinates: 0)."""
    return initial_states(check, BODY_COLUMNS)


def misnamed(check: Checker, name: str, states, reactions: bool = False
             ) -> tuple[str, str | None]:
    """Message and hint for a dotted name an event (or, with `reactions`, an output:
    schema/outputs.py) cannot read."""
    owner, _, attribute = name.rpartition(".")
    if owner == resolved.GROUND:
        return "'ground' does not move: it has no state", "name a moving body or a joint"
    if owner in check.joint_types:
        kind = check.joint_types[owner]
        has = joint_attributes(kind) + (list(JOINT_COLUMNS) if reactions else [])
        if attribute in JOINT_COLUMNS:
            states = joint_attributes(kind)
            return (f"reaction column '{name}' cannot be read by an event",
                    f"events read body columns and joint coordinates ({', '.join(states)})"
                    if states else "events read body columns and joint coordinates")
        known = ", ".join(has) if has else "no coordinates (" \
            f"{listed(coordinate_types())} joints have)"
        return (f"{kind} joint '{owner}' has no '{attribute}'",
                did_you_mean(attribute, has) or f"{kind} joints have {known}")
    if owner in check.bodies:
        return (f"body '{owner}' has no '{attribute}'",
                did_you_mean(attribute, BODY_COLUMNS) or f"bodies have {', '.join(BODY_COLUMNS)}")
    columns = [state.rpartition(".")[2] for state in states if state.startswith(f"{owner}.")]
    if columns:  # a contact element's or a joint stop's columns
        return (f"'{owner}' has no column '{attribute}'",
                did_you_mean(attribute, columns) or f"it has {', '.join(columns)}")
    known = [*check.joint_types, *check.bodies]
    hint = did_you_mean(name, states) or did_you_mean(owner, known)
    return f"unknown state '{name}': no body or joint '{owner}'", hint


def parsed_names(text) -> tuple[tuple[str, int, int], ...]:
    """(name, offset, length) of every name `text` uses (none when it is a number or does
    not parse: Checker.function reports the syntax error)."""
    try:
        expr = parse(text) if isinstance(text, str) else None
    except ExpressionError:
        return ()
    return expr.names_with_offsets() if expr else ()


def read_names(text) -> tuple[str, ...]:
    """The names `text` uses, in text order."""
    return tuple(name for name, _, _ in parsed_names(text))


def _unknown_states(check: Checker, path: Path, text, states) -> set[str]:
    """Report (E201) every dotted name of `text` that is not a state; those names."""
    unknown: set[str] = set()
    for name, offset, _ in parsed_names(text):
        if "." in name and name not in states and name not in unknown:
            message, hint = misnamed(check, name, states)
            check.error("E201", path, message, source=check.inside(path, offset), hint=hint)
            unknown.add(name)
    return unknown


def reactions_read(outputs, value: resolved.ScalarFunction) -> set[str]:
    """The reaction columns `value` (an output's) reads, through the outputs it reads too."""
    found: set[str] = set()
    for name in value.variables:
        owner, _, attribute = name.rpartition(".")
        if owner and attribute in JOINT_COLUMNS:
            found.add(name)
        elif name in outputs:
            found |= reactions_read(outputs, outputs[name].value)
    return found


def _reading_reactions(check: Checker, path: Path, text, outputs) -> set[str]:
    """Report (E201) the outputs `text` reads that read reactions; those names."""
    found = set()
    for name, offset, _ in parsed_names(text):
        if name in outputs and name not in found and reactions_read(outputs, outputs[name].value):
            read = ", ".join(sorted(reactions_read(outputs, outputs[name].value)))
            check.error("E201", path, f"output '{name}' reads reactions ({read}), which events "
                        "cannot read", source=check.inside(path, offset),
                        hint="events read the body columns, joint states, contact and stop "
                             "columns and the outputs made of them")
            found.add(name)
    return found


def event(check: Checker, index: int, given: spec.Event, states, outputs=None
          ) -> resolved.Event | None:
    """One entry of `events:`; its `when` reads t, parameters, the states and the outputs it
    names (checked finite at their values at t = 0; outputs: 0)."""
    outputs = outputs or {}
    path: Path = ("events", index, "when")
    unknown = _unknown_states(check, path, given.when, states)
    unknown |= _reading_reactions(check, path, given.when, outputs)
    used = {name: states.get(name, 0.0) for name in read_names(given.when)
            if name in states or name in outputs}
    at = {"t": 0.0, **used, **dict.fromkeys(unknown, 0.0)}  # unknown: reported above
    found = check.function(path, given.when, at)
    if found is None or unknown:
        return None
    when = replace(found, variables=tuple(name for name in at if name in found.expr.symbols))
    return resolved.Event(given.name, when, given.direction, given.action,
                          check.doc.locate(("events", index)))


def events(check: Checker, given: tuple[spec.Event, ...], joints=(), forces=(), outputs=()
           ) -> tuple[resolved.Event, ...] | None:
    """The resolved events (None when any is wrong; every finding reported). Besides the
    states, `when` reads the contacts' and joint stops' columns (`floor.gap`,
    `pivot.limit_torque`; value 0 for the finite check at t = 0) and the `outputs:` that do
    not read reactions (schema/outputs.py)."""
    if not given:
        return ()
    states = state_names(check) | dict.fromkeys(contact.output_names(joints, forces), 0.0)
    first: dict[str, Path] = {}
    found = []
    for index, item in enumerate(given):
        name_path: Path = ("events", index, "name")
        named = check.valid_name(name_path, item.name, check.doc.locate(name_path), set(), "")
        if named and item.name in first:
            line = check.doc.locate(first[item.name]).line
            check.error("E301", name_path, f"duplicate event name '{item.name}' (first used "
                        f"by {format_path(first[item.name][:2])}, line {line})")
            named = False
        first.setdefault(item.name, name_path)
        resolved_event = event(check, index, item, states,  # its findings, named or not
                               {output.name: output for output in outputs or ()})
        found.append(resolved_event if named else None)
    return None if any(item is None for item in found) else tuple(found)
