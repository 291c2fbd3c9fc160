"""The results columns of a model's force elements with outputs (contacts:
casmech.elements.forces.contact)
and of its joint stops (equations/limits.py) and frictions (equations/friction.py), in the
order of schema/contact.output_names."""

from __future__ import annotations

import casadi as ca

from casmech.elements.force_types import REGISTRY, outputs_of
from casmech.equations import friction


def output_names(ir) -> list[str]:
    """Results columns of the elements with outputs (their entry's `outputs` each, in file
    order), then the joint stops."""
    names = [f"{f.name}.{o}" for f in ir.forces for o in outputs_of(f.type)]
    return names + [n for limit in ir.limits for n in _of(limit).output_names(limit)]


def element_outputs(ir, x):
    """Their values (a column, output_names' order) as expressions of t, q, q_dot."""
    values = [v for f in ir.forces if outputs_of(f.type)
              for v in REGISTRY[f.type].output_values(f, x)]
    values += [v for limit in ir.limits for v in _of(limit).outputs(limit, x)]
    return ca.vertcat(*values) if values else ca.SX(0, 1)


def _of(element):
    """The module of a joint element of ir.limits: a stop's or a friction's."""
    from casmech.equations import limits

    return friction if element.type in friction.COORDINATE else limits
