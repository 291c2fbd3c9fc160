"""The model's analysis settings, events and outputs (schema/spec.py); estimation, optimal
control and parameter studies are in spec_problems."""

# (annotations are objects here, not strings: no `from __future__ import annotations`, so that
# pydantic makes each class without evaluating them; docs/decisions/pydantic-defer-build.md)

import importlib
from typing import Any, Literal

from pydantic import StrictStr

from casmech.core import options
from casmech.core.spec_base import Name, Scalar, Spec

_DYNAMICS = options.DynamicsOptions()  # the defaults (written once, in casmech.core.options)


# ---------------------------------------------------------------------------------- analysis
class Analysis(Spec):
    type: Literal[tuple(options.OPTIONS)] = "dynamics"  # type: ignore[valid-type]
    t_end: Scalar = 1.0
    output_step: Scalar = 0.01
    rtol: Scalar = 1e-8
    atol: Scalar = 1e-10
    # dynamics (and modal at a time): the options of casmech.core.options.DynamicsOptions:
    # formulation (rp or romega DAE, joint coordinates, or auto), stabilization of the DAEs,
    # CVODES's method in joint coordinates of a tree
    # (the registered formulations and auto: schema/spec.py rebuilds this on a change)
    formulation: Literal[tuple(options.FORMULATIONS)] = (  # type: ignore[valid-type]
        _DYNAMICS.formulation)
    stabilization: Literal[options.STABILIZATIONS] = (  # type: ignore[valid-type]
        _DYNAMICS.stabilization)
    method: Literal[options.METHODS] = _DYNAMICS.method  # type: ignore[valid-type]
    # modal: linearize at this time of a dynamics run (0 <= at <= t_end) instead of at the static
    # equilibrium; inputs: the effort-motor joints and force elements whose force is an input
    # (default: every effort motor). runtime/modal.py
    at: Scalar | None = None
    inputs: tuple[Name, ...] | None = None
    # the solvers' settings of the analysis type (casmech.core.options: its `solver` fields;
    # checked by schema.semantic against the type, docs/analyses.md#options)
    solver: dict[StrictStr, Any] | None = None


# the `events:` and `outputs:` items' classes, Event and Output: imported when a document first
# has one (spec_base.Deferred)
EVENTS = "casmech.schema.spec_events"


def section(name: str) -> type[Spec]:
    """A class of spec_events (the module imported on the first call)."""
    return getattr(importlib.import_module(EVENTS), name)


def __getattr__(name: str) -> type[Spec]:
    """The classes of spec_events by name (spec.Event, spec.Output)."""
    if name in ("Event", "Output"):
        return section(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
