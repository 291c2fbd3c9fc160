"""The `events:` and `outputs:` items (schema/spec.py, spec_analysis), imported when a document
first has one of them (spec_base.Deferred)."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

from typing import Literal

from casmech.core.spec_base import Name, Scalar, Spec


# ----------------------------------------------------------------------------------- events
class Event(Spec):
    """An event: where `when` (an expression of the results columns, joint coordinates, t and
    parameters) crosses zero in `direction`; `action` stop ends the run there, log records it
    (docs/format.md#events, casmech.schema.events)."""

    name: Name
    when: Scalar
    direction: Literal["rising", "falling", "both"] = "both"
    action: Literal["stop", "log"] = "log"


class Output(Spec):
    """A named value written as a results column at every row (docs/format.md#outputs,
    casmech.schema.outputs): an expression of t, parameters, earlier outputs, the state and
    the reactions."""

    name: Name
    value: Scalar
